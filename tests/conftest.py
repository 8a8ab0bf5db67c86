"""Shared fixtures: a clean py_trees blackboard for every test, and helpers to write missions."""

from __future__ import annotations

import textwrap
from pathlib import Path

import py_trees
import pytest


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
