"""The recorder turns a node's figures and drawings into rerun archetypes (a fake rerun module records the calls)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import py_trees
import rerun

from behaviours.telemetry import Arrows, Drawing, Event, Figure, Lines, Picture, Plot, Points
from missions.images import ImageRate
from missions.recording import Recorder


class _FakeRerun:
    def __init__(self) -> None:
        self.logged: list[tuple[str, str, dict[str, Any]]] = []

    def log(self, entity: str, archetype: tuple[str, dict[str, Any]]) -> None:
        self.logged.append((entity, *archetype))

    def __getattr__(self, name: str) -> Any:
        return lambda *args, **kwargs: (name, {"args": args, **kwargs})

    @staticmethod
    def escape_entity_path_part(part: str) -> str:
        return rerun.escape_entity_path_part(part)


class _Node:
    def __init__(self) -> None:
        self.count = 0

    def figures(self) -> Iterator[Figure]:
        yield Figure("ltmap", "search.scans", self.count)
        yield Figure("ltmap", "reached", [1, 2])  # not a number: report only

    def drawings(self) -> Iterator[Drawing]:
        yield Points("a/points2d", np.zeros((3, 2)), colours=(1, 2, 3))
        yield Points("a/points3d", np.zeros((3, 3)), colours=[(1, 2, 3)] * 3, labels=("x", "y", "z"))
        yield Lines("a/lines", [np.zeros((2, 2))], colours=(0, 0, 0))
        yield Arrows("a/arrows", np.ones((1, 2)), colours=(9, 9, 9), labels=("north",))
        yield Picture("a/picture", np.zeros((2, 2, 3), np.uint8))
        yield Event("a/events", "hello")
        yield Plot("a/plot", 0.5)


def _recorder() -> tuple[Recorder, _FakeRerun]:
    recorder = Recorder.__new__(Recorder)  # no file: the fake module stands in for rerun
    fake = _FakeRerun()
    recorder.rr, recorder._last_figure = fake, {}
    return recorder, fake


def test_every_drawing_becomes_its_archetype():
    recorder, fake = _recorder()
    recorder.log_node(_Node())
    kinds = {entity: kind for entity, kind, _ in fake.logged}
    assert kinds == {"figures/ltmap/search/scans": "Scalars", "a/points2d": "Points2D", "a/points3d": "Points3D",
                     "a/lines": "LineStrips2D", "a/arrows": "Arrows2D", "a/picture": "EncodedImage",
                     "a/events": "TextLog", "a/plot": "Scalars"}
    labels = {entity: kwargs["labels"] for entity, _, kwargs in fake.logged if entity in ("a/points3d", "a/arrows")}
    assert labels == {"a/points3d": ["x", "y", "z"], "a/arrows": ["north"]}


def test_a_figure_is_plotted_only_when_it_changes():
    recorder, fake = _recorder()
    node = _Node()
    for count in (0, 0, 1, 1, 2):
        node.count = count
        recorder.log_node(node)
    plotted = [kwargs["args"][0] for entity, _, kwargs in fake.logged if entity == "figures/ltmap/search/scans"]
    assert plotted == [[0.0], [1.0], [2.0]]


def test_a_figure_of_a_node_named_in_words_is_one_entity_path_part_per_name():
    recorder, fake = _recorder()

    class Named(_Node):
        def figures(self) -> Iterator[Figure]:
            yield Figure("avoidance", "around obstacles on the tour.detours", 2)

    recorder.log_node(Named())
    # the node's name is one part, its spaces escaped (rerun warned of unescaped whitespace before)
    assert [entity for entity, _, _ in fake.logged if entity.startswith("figures/")] == [
        "figures/avoidance/around\\ obstacles\\ on\\ the\\ tour/detours"]


def test_figures_are_gathered_at_most_once_a_second_of_the_run():
    recorder, fake = _recorder()
    recorder._figures_at, recorder._last_status, recorder.images = float("-inf"), {}, ImageRate()
    recorder.timeline = "sim_time"
    node = _Node()
    root = py_trees.behaviours.Success(name="root")
    for tick in range(25):  # 10 Hz for 2.4 s: figures at 0.0, 1.0 and 2.0 s
        node.count = tick
        recorder.log_tick(time_s=tick * 0.1, tick=tick, root=root, odometry=None, command=None, nodes=[node])
    plotted = [kwargs["args"][0] for entity, _, kwargs in fake.logged if entity == "figures/ltmap/search/scans"]
    assert plotted == [[0.0], [10.0], [20.0]]
