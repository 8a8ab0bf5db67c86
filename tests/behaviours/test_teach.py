"""LearnRoute in isolation: teaching around a scripted drive, saving, online pruning, its report and drawings."""

from __future__ import annotations

import math

import numpy as np
import py_trees
import pytest
from py_trees.common import Status

from behaviours.teach import LearnRoute
from behaviours.telemetry import Points, report_sections
from behaviours.testing import BehaviourHarness
from maps.ltmap.file import load_ltmap
from perception.geometry import Pose2D
from perception.synthetic_route import observe_route, straight_route
from tests.behaviours.routes import WORLD


class Scripted(py_trees.behaviour.Behaviour):
    """A drive that runs for ``ticks`` ticks, then ends with ``result``."""

    def __init__(self, ticks: int, result: Status = Status.SUCCESS) -> None:
        super().__init__(name="drive")
        self.ticks, self.result, self.count = ticks, result, 0

    def update(self) -> Status:
        self.count += 1
        return self.result if self.count >= self.ticks else Status.RUNNING


def teach(harness: BehaviourHarness, poses) -> Status:
    rng = np.random.default_rng(4)
    status = Status.INVALID
    for pose in poses:
        harness.write("/robot/odometry", pose)
        harness.write("/perception/observation", observe_route(WORLD, pose, rng, noise_deg=0.1))
        status = harness.tick()
        harness.clock.advance(0.1)
    return status


def test_learn_route_saves_the_map_when_the_drive_succeeds(tmp_path):
    path = tmp_path / "route.ltmap"
    poses = straight_route(3.0, 0.05)
    node = LearnRoute(name="learn", child=Scripted(len(poses)), path=str(path))
    harness = BehaviourHarness(node)
    assert teach(harness, poses[:-1]) == Status.RUNNING
    assert not path.exists() and harness.read("/map/ltmap").viewframe_count > 3  # on the blackboard meanwhile
    assert teach(harness, poses[-1:]) == Status.SUCCESS
    saved = load_ltmap(path)
    assert saved.viewframe_count == harness.read("/map/ltmap").viewframe_count
    section = report_sections(node)["ltmap"]
    assert section["saved"] and section["viewframes"] == saved.viewframe_count
    assert list(section) == ["landmark_kind", "viewframes", "landmarks", "nodes", "height", "bytes",
                             "landmarks_per_level", "threshold", "map_file", "saved", "online_prunes", "taught",
                             "gap_filling", "shifted", "loops", "loop_closures"]
    assert section["map_file"] == str(path) and section["online_prunes"] == 0
    assert section["gap_filling"] is True and section["loops"] == [] and section["loop_closures"] == 0
    # each viewframe keeps the odometry place it was taught at (the pose of the tick at its taught time)
    at = [poses[round(entry["time_s"] / 0.1)] for entry in section["taught"]]
    assert saved.has_places and len(at) == saved.viewframe_count
    for index, pose in enumerate(at):
        assert saved.place(index) == pytest.approx([pose.x, pose.y], abs=1e-6)
    times = [entry["time_s"] for entry in section["taught"]]
    assert len(times) == saved.viewframe_count and times == sorted(times) and times[-1] == pytest.approx(6.0)


def test_learn_route_counts_the_landmarks_shifted_and_the_loops_closed():
    out = straight_route(2.0, 0.05)
    back = [Pose2D(2.0 - p.x, 0.0, math.pi, stamp=out[-1].stamp + 0.1 + p.stamp) for p in out[1:]]
    for gap_filling in (True, False):
        node = LearnRoute(name="learn", child=Scripted(len(out) + len(back)), gap_filling=gap_filling)
        teach(BehaviourHarness(node), out + back)
        section = report_sections(node)["ltmap"]
        loops = section["loops"]
        assert section["gap_filling"] is gap_filling
        if gap_filling:  # back along the way out: loops, each an earlier viewframe and a later one, one closure
            assert loops and all(a < b and shared >= 8 for (a, b), shared in
                                 ((loop["viewframes"], loop["shared"]) for loop in loops))
            later = [loop["viewframes"][1] for loop in loops]
            assert section["loop_closures"] == 1 + sum(b - a > 1 for a, b in zip(later, later[1:], strict=False))
        else:
            assert loops == [] and section["shifted"] == 0


def test_learn_route_saves_nothing_when_the_drive_fails(tmp_path):
    path = tmp_path / "route.ltmap"
    path.write_bytes(b"the previous file")
    poses = straight_route(1.0, 0.05)
    harness = BehaviourHarness(LearnRoute(name="learn", child=Scripted(len(poses), Status.FAILURE), path=str(path)))
    assert teach(harness, poses) == Status.FAILURE
    assert path.read_bytes() == b"the previous file"


def test_learn_route_without_observations_fails():
    harness = BehaviourHarness(LearnRoute(name="learn", child=Scripted(1)))
    assert harness.tick() == Status.FAILURE
    assert "nothing was observed" in harness.behaviour.feedback_message


def test_learn_route_prunes_online_to_its_budget_and_keeps_the_taught_times():
    poses = straight_route(3.0, 0.05)
    whole = BehaviourHarness(LearnRoute(name="learn", child=Scripted(len(poses))))
    teach(whole, poses)
    budget = whole.read("/map/ltmap").memory_bytes() // 2
    node = LearnRoute(name="learn", child=Scripted(len(poses)), budget=budget, min_landmarks=5)
    harness = BehaviourHarness(node)
    assert teach(harness, poses) == Status.SUCCESS
    tree = harness.read("/map/ltmap")
    section = report_sections(node)["ltmap"]
    assert tree.memory_bytes() <= budget and section["online_prunes"] > 0
    assert len(section["taught"]) == tree.viewframe_count and section["taught"][0]["time_s"] == pytest.approx(0.1)


def test_learn_route_reports_nothing_before_its_first_observation_and_draws_new_viewframes_once():
    poses = straight_route(1.0, 0.05)
    node = LearnRoute(name="learn", child=Scripted(len(poses)))
    harness = BehaviourHarness(node)
    assert report_sections(node) == {} and list(node.drawings()) == []
    teach(harness, poses[:6])
    (drawn,) = node.drawings()
    assert isinstance(drawn, Points) and drawn.entity == "odometry_frame/route/viewframes"
    tree = harness.read("/map/ltmap")
    assert drawn.positions.tolist() == [tree.place(i).tolist() for i in range(tree.viewframe_count)]
    assert drawn.colours == (255, 200, 0) and drawn.radius == 0.05
    assert list(node.drawings()) == []  # no new viewframe: nothing drawn
