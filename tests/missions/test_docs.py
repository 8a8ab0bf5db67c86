"""The examples in the documentation work as written."""

from __future__ import annotations

import re
from pathlib import Path

from missions.cli import main

DOCS = Path(__file__).resolve().parents[2] / "docs"


def _python_block(page: str, section: str) -> str:
    text = (DOCS / page).read_text()
    body = text[text.index(f"## {section}"):]
    return re.search(r"```python\n(.*?)```", body, re.S).group(1)


def test_the_behaviour_in_writing_a_behaviour_runs_as_a_plugin(tmp_path, capsys):
    (tmp_path / "corners.py").write_text(_python_block("missions.md", "Writing a behaviour"))
    mission = tmp_path / "corner.yaml"
    mission.write_text("plugins: [corners.py]\ncameras: []\ntree:\n  Sequence:\n    children:\n"
                       "      - NearestCorner: {side: 2.0, goal: '{/mission/corner}'}\n"
                       "      - CheckBlackboard: {key: /mission/corner.x, op: '==', value: 0.0}\n")
    assert main(["validate", str(mission)]) == 0
    assert main(["run", str(mission), "--quiet"]) == 0, capsys.readouterr().err
