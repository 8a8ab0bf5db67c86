"""The examples in the documentation work as written."""

from __future__ import annotations

import argparse
import contextlib
import glob
import io
import re
import textwrap
from pathlib import Path

import pytest

from drivers.sim.world import shipped_worlds
from missions.cli import build_parser, main
from missions.commands.missions_list import shipped_missions
from tests.docs_text import (
    PAGES,
    ROOT,
    Mention,
    cited_paths,
    commands,
    example_block,
    foreign_citations,
    is_complete,
    tokens,
)

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


# -- every command line, path and citation of README.md and docs/ -------------------------------------
def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _command_parser(words: list[str]) -> tuple[argparse.ArgumentParser | None, list[str], str | None]:
    """The (sub-)parser a command line reaches, the words left, or a problem."""
    parser = build_parser()
    if not words or words[0] in ("-h", "--help"):
        return parser, words, None
    commands_ = _subcommands(parser)
    if words[0] not in commands_:
        return None, words, f"no command {words[0]!r}"
    sub, rest = commands_[words[0]], words[1:]
    nested = _subcommands(sub)
    if nested and rest and not rest[0].startswith("-"):
        if rest[0] not in nested:
            return None, rest, f"no sub-command {words[0]} {rest[0]!r}"
        sub, rest = nested[rest[0]], rest[1:]
    return sub, rest, None


def _loose_problem(words: list[str]) -> str | None:
    """A synopsis line: the command, its sub-command, every option name and every listed choice exist."""
    if words and words[0].isupper():  # bearings COMMAND --help
        return None
    parser, rest, problem = _command_parser(words)
    if parser is None:
        return problem
    options = {name: action for action in parser._actions for name in action.option_strings}
    positional_choices = [a.choices for a in parser._actions if not a.option_strings and a.choices]
    pieces = [p for word in rest for p in re.split(r"[\[\]]", word) if p and p != "|"]
    for index, piece in enumerate(pieces):
        if piece.startswith("-"):
            name = piece.split("=")[0]
            if name not in options:
                return f"{words[0]} has no option {name}"
            continue
        alternatives = piece.split("|")
        before = options.get(pieces[index - 1]) if index else None
        choices = before.choices if before is not None else (positional_choices[0] if positional_choices else None)
        if len(alternatives) > 1 and choices is not None and not set(alternatives) <= set(choices):
            return f"{'|'.join(alternatives)}: not all in the choices {', '.join(map(str, choices))}"
    return None


def _complete_problem(words: list[str]) -> str | None:
    """A complete command line: the parser takes it, and the shipped names it uses exist."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            args = build_parser().parse_args(words)
    except SystemExit as exc:
        if exc.code == 0:  # --help
            return None
        return err.getvalue().strip().splitlines()[-1]
    missions = getattr(args, "missions", None) or ([args.mission] if isinstance(getattr(args, "mission", None), str)
                                                   else [])
    for name in missions:
        if "/" not in name and "." not in name and name not in shipped_missions():
            return f"no shipped mission {name!r}"
    for option in ("sim", "world"):
        value = getattr(args, option, None)
        for name in (value.split(",") if isinstance(value, str) else []):
            if "/" not in name and "." not in name and name not in (*shipped_worlds(), "empty"):
                return f"no shipped world {name!r}"
    return None


def _all(finder) -> list[Mention]:
    return [mention for page in PAGES for mention in finder(page)]


def test_every_command_line_in_the_readme_and_docs_is_one_the_cli_takes():
    problems = []
    for mention in _all(commands):
        words = tokens(mention.text)
        complete = mention.in_block and is_complete(mention.text)  # an inline mention names a command
        check = _complete_problem if complete else _loose_problem
        problem = check(words)
        if problem:
            problems.append(f"{mention.where}: bearings {mention.text}: {problem}")
    assert not problems, "\n".join(problems)
    assert len(_all(commands)) > 100  # the check reads what the pages hold


def test_the_checks_catch_a_wrong_command_option_choice_or_name():
    assert _loose_problem(tokens("frobnicate MISSION")) == "no command 'frobnicate'"
    assert _loose_problem(tokens("run MISSION [--simulate WORLD]")) == "run has no option --simulate"
    assert _loose_problem(tokens("bench tree|gpu --json")).startswith("tree|gpu: not all in the choices")
    assert _loose_problem(tokens("map inspect FILE")) == "no sub-command map 'inspect'"
    assert _complete_problem(tokens("run sqare --sim lab")) == "no shipped mission 'sqare'"
    assert _complete_problem(tokens("run square --sim labb")) == "no shipped world 'labb'"
    assert "unrecognized arguments" in _complete_problem(tokens("run square --speed 2"))


def test_every_path_the_docs_cite_exists_inside_the_repository():
    problems = []
    for mention in _all(cited_paths):
        base = mention.page.parent if mention.text.split("/")[0] not in {p.name for p in ROOT.iterdir()} else ROOT
        target = (base / mention.text).resolve()
        if not target.is_relative_to(ROOT):
            problems.append(f"{mention.where}: {mention.text} is outside the repository")
        elif not glob.glob(str(target)) and not target.exists():
            problems.append(f"{mention.where}: {mention.text} does not exist")
    assert not problems, "\n".join(problems)


def test_no_page_cites_what_a_clone_does_not_hold():
    problems = [f"{m.where}: {m.text}" for m in _all(foreign_citations)
                if not m.text.lower().startswith("issue") and (ROOT / m.text).exists() is False
                and (ROOT / "docs" / m.text).exists() is False]
    problems += [f"{m.where}: {m.text} (an issue tracker is not in a clone)" for m in _all(foreign_citations)
                 if m.text.lower().startswith("issue")]
    assert not problems, "\n".join(problems)


def test_the_readme_keeps_two_commands_for_a_fresh_machine():
    fresh = example_block(ROOT / "README.md", "## Two commands for a fresh machine")
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Two commands"):text.index("## Using it")]
    assert section.count("```bash") == 2 and len(fresh) == 1 and "pytest" in section


SHORTER = {"eval": ["--max-time", "20"], "bench": ["--quick"]}
"""What the test adds to an example that takes minutes."""


@pytest.mark.parametrize("heading", ["## Two commands for a fresh machine", "## Using it"])
def test_the_readme_examples_run_as_written(heading, tmp_path, monkeypatch, capsys):
    from experiments.bench import run as bench_run

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bench_run, "EXPLORE_TIME_S", 3.0)
    examples = example_block(ROOT / "README.md", heading)
    assert examples
    for example in examples:
        words = tokens(example.text)
        if words[0] == "run" and heading.startswith("## Two"):
            words += ["--max-time", "10"]  # the showcase takes two minutes of simulated time
        words += SHORTER.get(words[0], [])
        code = main(words)
        shortened = "--max-time" in words and "--max-time" not in example.text
        assert code == 0 or (code == 1 and shortened), f"{example.where}: bearings {example.text}: exit {code}\n" \
                                                       f"{capsys.readouterr().err[-2000:]}"


def test_the_harness_docstring_example_runs_as_written():
    import behaviours.testing

    example = behaviours.testing.__doc__.split("Example::")[1].split("Like the runner")[0]
    exec(compile(textwrap.dedent(example), "behaviours/testing.py", "exec"), {})  # noqa: S102


def test_a_mission_using_a_plugin_survives_the_xml_round_trip(tmp_path, capsys):
    (tmp_path / "corners.py").write_text(_python_block("missions.md", "Writing a behaviour"))
    mission, xml, back = tmp_path / "corner.yaml", tmp_path / "corner.xml", tmp_path / "back.yaml"
    mission.write_text("plugins: [corners.py]\ntree:\n  Sequence:\n    children:\n"
                       "      - NearestCorner: {side: 2.0, goal: '{/mission/corner}'}\n      - Stop\n")
    assert main(["show", str(mission), "--format", "xml", "-o", str(xml)]) == 0
    assert main(["import", str(xml), "-o", str(back)]) == 2  # NearestCorner is not bearings' own
    assert "NearestCorner" in capsys.readouterr().err
    assert main(["import", str(xml), "-o", str(back), "--plugin", "corners.py"]) == 0
    assert "plugins: [corners.py]" in back.read_text()
    assert main(["validate", str(back)]) == 0
    from missions.loader import load_mission

    original, imported = load_mission(mission).tree, load_mission(back).tree
    assert [n.type for n in imported.walk()] == [n.type for n in original.walk()]
    assert imported.children[0].inputs == original.children[0].inputs
