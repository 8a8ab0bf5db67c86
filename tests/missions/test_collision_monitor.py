"""The collision monitor in whole runs: a mission that drives at a wall stops short of it, and says so.

Until the simulator has a sonar ring of its own, the tests give the simulated robot one built
here from the scene's ray casting (:class:`SceneSonar`): a Pioneer 3-DX's ring (ARIA's
geometry), each transducer's range the nearest surface in its 30 degree cone.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from behaviours.clock import ManualClock
from behaviours.telemetry import Event, Plot
from drivers.fake import FakeBase
from drivers.interfaces import Robot
from drivers.pioneer_body import BODIES
from drivers.safety.settings import monitor_config
from drivers.sim.simulation import Simulation
from missions.cli import main
from missions.loader import load_mission
from missions.runner import Runner, RunOptions
from missions.summary import summary_line
from perception.geometry import Pose2D
from perception.polygons import disc
from perception.ranges import RangeScan, RangeSensor

RAYS_PER_CONE = 7


class SceneSonar:
    """A range source for the simulated robot: each sensor's nearest surface within its cone."""

    def __init__(self, sim: Simulation, sensors: tuple[RangeSensor, ...]) -> None:
        self.sim = sim
        self.sensors = sensors

    def read(self) -> RangeScan:
        pose = self.sim.true_pose()
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        ranges = []
        for sensor in self.sensors:
            origin = np.array([pose.x + c * sensor.x - s * sensor.y, pose.y + s * sensor.x + c * sensor.y])
            angles = pose.theta + sensor.heading + np.linspace(-sensor.fov / 2, sensor.fov / 2, RAYS_PER_CONE)
            hits, _ = self.sim.scene.cast_columns(origin, angles)
            nearest = float(hits.min()) if hits.size else math.inf
            ranges.append(math.inf if nearest > sensor.max_range else max(nearest, sensor.min_range))
        return RangeScan(self.sensors, np.array(ranges), self.sim.time)

    def close(self) -> None:
        pass

    def describe(self) -> str:
        return f"scene sonar ({len(self.sensors)} transducers)"


def run_towards_the_end_wall(write_mission, tmp_path, *, sonar: bool):
    """Drive: {distance: 5} from 1.5 m in front of the corridor's west end wall, facing it."""
    mission = load_mission(write_mission("cameras: []\ntree:\n  Drive: {distance: 5.0}\n"))
    sim = Simulation.load("corridor", start=Pose2D(1.5, 1.2, math.pi))
    robot = dataclasses.replace(sim.robot, ranges=SceneSonar(sim, BODIES["p3dx"].sensors()) if sonar else None)
    config = monitor_config(None, disc(sim.world.robot_radius))
    options = RunOptions(max_time_s=20.0, report_path=tmp_path / "report.json")
    runner = Runner(mission, robot, clock=sim.clock(), observers=[sim], options=options, safety=config)
    return runner.run(), sim


def test_a_mission_driving_at_a_wall_stops_short_of_it_with_the_event_in_the_report(write_mission, tmp_path):
    result, sim = run_towards_the_end_wall(write_mission, tmp_path, sonar=True)
    assert result.status == "FAILURE" and "time limit" in result.reason  # Drive never gets its 5 m
    truth, safety = result.report["ground_truth"], result.report["safety"]
    assert truth["collisions"] == 0
    gap = truth["final_pose"]["x"] - sim.world.robot_radius  # the wall is x = 0
    assert 0.03 < gap < 0.12  # the stop zone is 0.10 m deep; the last tick at <= 0.1 m/s moves <= 0.01 m
    assert safety["safety_stops"] == 1 and safety["sources"] == "scene sonar (16 transducers)"
    assert safety["min_range_m"] == pytest.approx(gap, abs=0.02)
    # slowed on the way in (the slow-down zone at 0.35 m, then approach below 0.3 m/s x 1 s), then stopped
    assert [event["action"] for event in safety["events"]] == ["slowdown", "approach", "stop"]
    assert safety["slowdowns"] == 1  # one episode of slowing, whichever shape decided
    stop = next(event for event in safety["events"] if event["action"] == "stop")
    assert stop["before"]["v"] > 0.0 and stop["after"] == {"v": 0.0, "w": 0.0}
    assert result.report["last_command"] == {"v": 0.0, "w": 0.0}


def test_without_ranges_the_same_mission_drives_into_the_wall(write_mission, tmp_path):
    result, _ = run_towards_the_end_wall(write_mission, tmp_path, sonar=False)
    assert result.report["ground_truth"]["collisions"] >= 1
    assert result.report["safety"]["sources"] == "none" and result.report["safety"]["safety_stops"] == 0


class WallAhead:
    """A range source whose one forward sensor reads 0.08 m (in the stop zone), stamped now."""

    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock

    def read(self) -> RangeScan:
        return RangeScan((RangeSensor(0.2, 0.0, 0.0),), np.array([0.08]), self.clock.now())

    def close(self) -> None:
        pass


class Drawings:
    """Stands in for the recorder: keeps what the runner draws."""

    def __init__(self) -> None:
        self.drawn: list = []

    def log_tick(self, **_: object) -> None:
        pass

    def draw(self, drawing: object) -> None:
        self.drawn.append(drawing)

    def log_stop(self, **_: object) -> None:
        pass

    def close(self) -> None:
        pass


def test_the_tree_reads_the_monitors_state_and_the_recording_gets_an_event_line(write_mission):
    mission = load_mission(write_mission("""
        cameras: []
        tree:
          Guard:
            key: /robot/safety.state
            op: '!='
            value: stopped
            child: {Drive: {distance: 1.0}}
        """))  # the data-flow check knows /robot/safety and its type: the mission loads
    clock = ManualClock()
    base = FakeBase()
    seen: list[str] = []
    runner = Runner(mission, Robot(base=base, ranges=WallAhead(clock)), clock=clock,
                    options=RunOptions(max_time_s=5.0),
                    on_tick=lambda r: seen.append(r.blackboard.get("/robot/safety").state))
    recorder = Drawings()
    runner._recorder = recorder  # noqa: SLF001 - a recording without a file
    result = runner.run()
    # tick 1: Drive asks for 0.3 m/s, the monitor stops it; tick 2: the guard sees the stop and fails
    assert result.status == "FAILURE" and result.ticks == 2
    assert seen == ["stopped", "clear"] and base.commands[:2] == [(0.0, 0.0), (0.0, 0.0)]
    events = [d for d in recorder.drawn if isinstance(d, Event)]
    assert [e.entity for e in events] == ["safety/events"]
    assert events[0].text.startswith("safety stopped (stop stop): obstacle 0.07 m from the footprint")
    assert [d.value for d in recorder.drawn if isinstance(d, Plot)] == [0.0, 1.0]


def test_bearings_run_ends_with_the_collisions_the_stops_and_the_clearance(capsys):
    assert main(["run", "square", "--quiet"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[1].startswith("ground truth: collisions 0, goal error ")  # the empty world: no clearance to tell
    assert "; safety: safety stops 0, slowdowns 0, bumper hits 0, " in out[1]
    report = {"safety": {"safety_stops": 2, "slowdowns": 1, "bumper_hits": 0, "min_range_m": 0.081,
                         "sources": "scene sonar (16 transducers)"},
              "ground_truth": {"collisions": 0, "min_clearance_m": 0.0794, "trajectory_length_m": 1.2},
              "headline": ["ground_truth.trajectory_length_m"]}
    assert summary_line(report) == (
        "ground truth: collisions 0, min clearance 0.079 m, trajectory length 1.200 m; safety: safety stops 2, "
        "slowdowns 1, bumper hits 0, min range 0.081 m, sources scene sonar (16 transducers)")


def test_the_runner_publishes_the_robots_own_footprint_before_the_first_tick(write_mission):
    mission = load_mission(write_mission("""
        cameras: []
        tree: {Drive: {distance: 0.1}}
        """))
    clock = ManualClock()
    seen: list[np.ndarray] = []
    runner = Runner(mission, Robot(base=FakeBase()), clock=clock, options=RunOptions(max_time_s=0.3),
                    safety=monitor_config(None, BODIES["p3at"].footprint),
                    on_tick=lambda r: seen.append(r.blackboard.get("/robot/footprint")))
    runner.run()
    # ARIA's p3at.p: RobotLengthFront/Rear 313 mm, RobotWidth 505 mm
    assert seen and np.array_equal(seen[0], BODIES["p3at"].footprint)
    assert np.abs(seen[0]).max(axis=0) == pytest.approx((0.313, 0.2525))
