"""Shared fixtures: a clean py_trees blackboard for every test, and helpers to write missions.

Hypothesis runs derandomized (a fixed seed, no example database) unless told otherwise, so no
random draw decides whether CI is green. The long random fuzz is a separate command:
``HYPOTHESIS_PROFILE=fuzz .venv/bin/python -m pytest tests -k fuzz`` (20x the examples, new
draws every run, failures remembered in .hypothesis/).
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Callable
from pathlib import Path

import py_trees
import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("fuzz", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(autouse=True)
def clean_blackboard():
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def write_mission(tmp_path: Path):
    """Write a mission (dedented YAML) into tmp_path and return its path."""

    def write(text: str, name: str = "mission.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text).lstrip("\n"), encoding="utf-8")
        return path

    return write


@pytest.fixture
def world_file(tmp_path: Path) -> Callable[[str], Path]:
    """Write dedented YAML text to a world file and return its path."""

    def write(text: str, name: str = "world.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write
