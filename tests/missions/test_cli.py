"""The command line finds commands from outside ``missions`` by entry point (group ``bearings.commands``)."""

from __future__ import annotations

import textwrap
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest

from missions import cli
from missions.commands import COMMANDS, ENTRY_POINT_GROUP


def _entry(name: str, module: str) -> EntryPoint:
    return EntryPoint(name=name, value=module, group=ENTRY_POINT_GROUP)


def _commands(parser) -> list[str]:
    """The sub-command names in the order ``--help`` lists them."""
    sub = next(a for a in parser._actions if a.dest == "command")
    return [choice.dest for choice in sub._choices_actions]


@pytest.fixture
def plugins(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    """Command modules on the path: one that works, one that raises on import, one without
    ``register``, one that takes a built-in's name."""
    (tmp_path / "bearings_hello_cmd.py").write_text(textwrap.dedent("""
        def register(sub):
            parser = sub.add_parser("hello", help="say hello")
            parser.set_defaults(func=lambda args: print("hello") or 0)
    """))
    (tmp_path / "bearings_broken_cmd.py").write_text("raise RuntimeError('boom at import')\n")
    (tmp_path / "bearings_empty_cmd.py").write_text("X = 1\n")
    (tmp_path / "bearings_run_cmd.py").write_text("def register(sub):\n    sub.add_parser('run', help='not run')\n")
    monkeypatch.syspath_prepend(str(tmp_path))


def test_the_experiments_commands_are_installed_entry_points():
    found = {e.name: e.value for e in cli.command_entry_points()}
    assert {k: found.get(k) for k in ("bench", "eval", "sweep")} == {
        "bench": "experiments.commands.bench", "eval": "experiments.commands.eval",
        "sweep": "experiments.commands.sweep"}
    assert not any(name.startswith("experiments") for name in COMMANDS)  # never imported by name


def test_help_lists_the_built_ins_then_the_entry_points_by_name(monkeypatch, plugins):
    entries = (_entry("zz", "bearings_hello_cmd"), _entry("bench", "experiments.commands.bench"))
    monkeypatch.setattr(cli, "command_entry_points", lambda: tuple(sorted(entries, key=lambda e: e.name)))
    names = _commands(cli.build_parser())
    builtin = ["run", "validate", "show", "import", "schema", "sim", "calibrate", "doctor", "map", "plot", "missions",
               "log"]
    assert names == [*builtin, "bench", "hello"]


def test_the_installed_order_is_stable():
    assert list(cli.command_entry_points()) == sorted(cli.command_entry_points(), key=lambda e: (e.name, e.value))


def test_an_entry_point_that_fails_costs_only_its_own_command(monkeypatch, plugins, capsys, write_mission):
    entries = (_entry("broken", "bearings_broken_cmd"), _entry("empty", "bearings_empty_cmd"),
               _entry("gone", "bearings_no_such_module"), _entry("hello", "bearings_hello_cmd"))
    monkeypatch.setattr(cli, "command_entry_points", lambda: entries)
    assert cli.main(["hello"]) == 0
    out, err = capsys.readouterr()
    assert out == "hello\n"
    lines = err.splitlines()
    assert len(lines) == 3 and "Traceback" not in err
    assert "'broken' (bearings_broken_cmd)" in lines[0] and "RuntimeError: boom at import" in lines[0]
    assert "'empty' (bearings_empty_cmd)" in lines[1] and "register" in lines[1]
    assert "'gone' (bearings_no_such_module)" in lines[2] and "ModuleNotFoundError" in lines[2]
    mission = write_mission("tree:\n  Success: {}\n")
    assert cli.main(["validate", str(mission)]) == 0  # the built-ins still work


def test_an_entry_point_may_not_take_a_built_in_name(monkeypatch, plugins, capsys):
    monkeypatch.setattr(cli, "command_entry_points", lambda: (_entry("run", "bearings_run_cmd"),))
    parser = cli.build_parser()
    assert _commands(parser).count("run") == 1
    assert "'run' (bearings_run_cmd) is not available" in capsys.readouterr().err
    assert parser.parse_args(["run", "square"]).mission == "square"  # the built-in run
