"""Output confinement (issue 22, item 1): every file a mission writes lies in its own folder or the
``--output-dir``, checked at load with file:line (exit 2), never through a symbolic link out;
relative paths resolve against the output folder, for built-in and plugin node types alike."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from behaviours.landmark_tree import save_map
from behaviours.ports import WRITES, InputPort
from behaviours.registry import NodeType
from maps.ltmap.tree import LandmarkTree
from maps.store import InputError, OutputFolders
from missions.builder import build_root
from missions.cli import main
from missions.loader import load_mission

TEACH = """\
sense: [Perceive]
tree:
  LearnRoute:
    path: {path}
    child: Stop
"""


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    path = tmp_path / "mission"
    path.mkdir()
    return path


@pytest.fixture
def victim(tmp_path: Path) -> Path:
    path = tmp_path / "victim.txt"
    path.write_text("precious\n")
    path.chmod(0o640)
    return path


def _problems(path: Path, **kwargs) -> list[str]:
    with pytest.raises(InputError) as info:
        load_mission(path, **kwargs)
    return [str(d) for d in info.value.diagnostics]


def test_a_file_written_outside_the_missions_folder_is_refused_at_load(folder, victim, capsys):
    mission = folder / "m.yaml"
    mission.write_text(TEACH.format(path=victim))
    assert main(["validate", str(mission)]) == 2
    assert main(["run", str(mission), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f"{mission}:4:11: LearnRoute.path: '{victim}' is outside the mission's output folder {folder}" in err
    assert "--output-dir" in err and "Traceback" not in err
    assert victim.read_text() == "precious\n" and victim.stat().st_mode & 0o777 == 0o640


@pytest.mark.parametrize("path", ["../victim.txt", "sub/../../victim.txt", "/etc/bearings-victim"])
def test_parent_folders_and_absolute_paths_do_not_escape(folder, victim, path):
    mission = folder / "m.yaml"
    mission.write_text(TEACH.format(path=path))
    assert any("is outside the mission's output folder" in m for m in _problems(mission))


def test_a_symbolic_link_inside_the_folder_that_points_out_is_refused(folder, victim):
    (folder / "out.ltmap").symlink_to(victim)
    (folder / "elsewhere").symlink_to(victim.parent, target_is_directory=True)
    for path in ("out.ltmap", "elsewhere/victim.txt"):
        mission = folder / "m.yaml"
        mission.write_text(TEACH.format(path=path))
        [message] = _problems(mission)
        assert "is outside the mission's output folder" in message and f"(through a symbolic link: {victim})" in message
    assert victim.read_text() == "precious\n"


def test_relative_paths_resolve_in_the_missions_folder_and_the_node_gets_them_absolute(folder, tmp_path,
                                                                                       monkeypatch):
    monkeypatch.chdir(tmp_path)  # not the mission's folder: relative paths do not follow the current one
    mission = folder / "m.yaml"
    mission.write_text(TEACH.format(path="route.ltmap"))
    spec = load_mission(mission)
    _root, task = build_root(spec)
    assert task.get_input(task.PATH) == str(folder.resolve() / "route.ltmap")
    assert spec.tree.inputs["path"] == "route.ltmap"  # the mission as written (show, export) is unchanged


def test_output_dir_is_where_relative_paths_go_and_what_it_allows(folder, tmp_path, victim, capsys):
    out = tmp_path / "out"
    mission = folder / "m.yaml"
    mission.write_text(TEACH.format(path=victim))
    assert main(["validate", str(mission), "--output-dir", str(tmp_path)]) == 0  # victim is inside the output dir
    mission.write_text(TEACH.format(path="maps.ltmap"))
    _root, task = build_root(load_mission(mission, output_dir=out))
    assert task.get_input(task.PATH) == str(out.resolve() / "maps.ltmap")
    assert main(["run", str(mission), "--output-dir", str(out), "--quiet"]) == 0
    assert f"bearings run: created the output folder {out.resolve()}" in capsys.readouterr().err
    assert (out / "maps.ltmap").is_file() and not (folder / "maps.ltmap").exists()


def test_a_shipped_mission_writes_in_the_current_folder_by_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _root, task = build_root(load_mission("teach_route", overrides={"map": "r.ltmap", "camera": "landmarks"}))
    learn = next(node for node in task.iterate() if type(node).__name__ == "LearnRoute")
    assert learn.get_input(learn.PATH) == str(tmp_path.resolve() / "r.ltmap")
    messages = _problems(Path("teach_route"), overrides={"map": "/etc/bearings-victim"})
    assert any("teach_route.yaml" in m and "LearnRoute.path" in m for m in messages)


PLUGIN = """
from py_trees.common import Status
from behaviours.base import BearingsBehaviour
from behaviours.ports import WRITES, InputPort
from behaviours.registry import register

@register
class Dump(BearingsBehaviour):
    '''Writes a file (a test plugin).'''
    PORTS = (InputPort("target", str, literal_only=True, file=WRITES, doc="where"),)

    def update(self):
        return Status.SUCCESS
"""


def test_a_plugins_output_ports_are_confined_too(folder, victim):
    (folder / "dump.py").write_text(PLUGIN)
    mission = folder / "m.yaml"
    mission.write_text(f"plugins: [dump.py]\ntree: {{Dump: {{target: '{victim}'}}}}\n")
    [message] = _problems(mission)
    assert message.startswith(f"{mission}:2:23: Dump.target: '{victim}' is outside")


def test_an_output_port_must_be_a_literal():
    class Leaky:
        """A node whose written file could arrive from the blackboard (refused)."""

        PORTS = (InputPort("target", str, file=WRITES),)

    with pytest.raises(ValueError, match="names a file it writes: it must be literal_only"):
        NodeType.of(Leaky)


def test_a_link_put_in_the_way_after_loading_is_not_written_through(folder, victim):
    path = folder / "route.ltmap"
    folders = OutputFolders.of(folder)
    assert folders.outside(str(path)) is None
    resolved = folders.resolve("route.ltmap")  # what the node is built with
    path.symlink_to(victim)  # planted between load and save
    with pytest.raises(OSError, match="through a symbolic link"):
        save_map(str(resolved), LandmarkTree("ids"))
    assert victim.read_text() == "precious\n"
    assert os.path.islink(path)
