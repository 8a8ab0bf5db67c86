"""A mission driving straight at a person, in the simulator with its own sonar ring and bumpers.

``Drive: {distance: 5}`` at a person standing 2 m ahead: the collision monitor stops the base short
of them and the report says so (the monitor's events, no collision); the drive fails once held for
its ``held_timeout``. ``AvoidObstacles`` around the
same ``Drive``: it waits for a person who walks across and passes (and the drive then gets its 5 m),
and it gives up with a reason when the person stays (the mission's recovery would take over).
"""

from __future__ import annotations

import pytest

from drivers.safety.settings import monitor_config
from drivers.sim.simulation import Simulation
from missions.loader import load_mission
from missions.runner import Runner, RunOptions
from perception.polygons import disc

HALL = """
start: {x: 0, y: 0, theta_deg: 0}
robot: {radius: 0.25}
walls: [{points: [[-2, -4], [9, -4], [9, 4], [-2, 4]], closed: true, height: 2.5}]
cameras: [{name: eye, kind: bearings}]
"""
STANDING = "people: [{path: [[2.0, 0]], radius: 0.25}]\n"
# across the robot's way at x = 1.5, from 0.8 m to its right, and on (it stays at the far end)
CROSSING = "people: [{path: [[1.5, -0.8], [1.5, 3.5]], speed: 0.4, wait_s: 60}]\n"


def run(sim_from, tmp_path, world: str, tree: str, max_time: float):
    sim: Simulation = sim_from(world)
    mission = tmp_path / "mission.yaml"
    mission.write_text(f"cameras: []\ntree:\n{tree}")
    options = RunOptions(max_time_s=max_time, report_path=tmp_path / "report.json")
    runner = Runner(load_mission(mission), sim.robot, clock=sim.clock(), observers=[sim], options=options,
                    safety=monitor_config(None, disc(sim.world.robot_radius)))
    return runner.run(), sim


def test_driving_at_a_person_stops_short_of_them_with_the_monitors_event_in_the_report(sim_from, tmp_path):
    result, sim = run(sim_from, tmp_path, HALL + STANDING, "  Drive: {distance: 5.0, held_timeout: 10}\n", 30.0)
    # Drive never gets its 5 m: held by the monitor, it fails after its held_timeout with the monitor's reason
    assert result.status == "FAILURE" and "held by the collision monitor for 10 s: obstacle" in result.reason
    assert result.time_s < 20.0, result.time_s  # held from about 5 s on, not the 30 s time limit
    truth, safety = result.report["ground_truth"], result.report["safety"]
    assert truth["collisions"] == 0 and truth["collisions_with_people"] == 0
    gap = 2.0 - 0.25 - sim.true_pose().x - sim.world.robot_radius  # between the robot's disc and the person's
    assert 0.0 < gap < 0.25, gap  # stopped within the stop zone (0.10 m) and the sonar's blur of it
    assert truth["min_clearance_m"] == pytest.approx(gap, abs=0.02)
    assert safety["safety_stops"] >= 1 and "stop" in [event["action"] for event in safety["events"]]
    assert result.report["last_command"] == {"v": 0.0, "w": 0.0}


def test_avoidance_waits_for_a_person_walking_across_then_drives_on(sim_from, tmp_path):
    tree = "  AvoidObstacles:\n    wait: 30\n    child: {Drive: {distance: 3.0}}\n"
    result, sim = run(sim_from, tmp_path, HALL + CROSSING, tree, 40.0)
    assert result.status == "SUCCESS", result.reason
    truth, figures = result.report["ground_truth"], result.report["avoidance"]["AvoidObstacles"]
    assert truth["collisions"] == 0 and truth["collisions_with_people"] == 0
    assert sim.true_pose().x == pytest.approx(3.0, abs=0.1)
    assert abs(sim.true_pose().y) < 0.15  # straight on (odometry drift aside): no detour
    assert figures["waits"] >= 1 and figures["waits_cleared"] >= 1
    assert figures["detours"] == 0 and figures["give_ups"] == 0


def test_avoidance_gives_up_with_a_reason_when_the_person_stays(sim_from, tmp_path):
    # a person standing in the middle of a corridor too narrow to pass: it backs away the way it came
    # (0.4 m), finds no way round from there either, backs away again, and gives up when the hold's
    # timeout is over, 8 s, in the middle of the second back-off (before, that one ran to its end: 10 s)
    narrow = HALL.replace("[[-2, -4], [9, -4], [9, 4], [-2, 4]]", "[[-2, -0.45], [9, -0.45], [9, 0.45], [-2, 0.45]]")
    tree = "  AvoidObstacles:\n    timeout: 8\n    child: {Drive: {distance: 5.0}}\n"
    result, _ = run(sim_from, tmp_path, narrow + STANDING, tree, 30.0)
    assert result.status == "FAILURE" and "blocked for 8 s: backing away" in result.reason, result.reason
    assert result.reason.endswith("did not free the way")
    assert result.report["ground_truth"]["collisions"] == 0
    avoidance = result.report["avoidance"]["AvoidObstacles"]
    assert avoidance["give_ups"] == 1 and avoidance["backoffs"] == 2
    assert 0.45 < avoidance["backoff_m"] < 0.75  # the first 0.4 m, and part of the second


@pytest.mark.parametrize("start", [4.111, 4.222])
def test_driving_at_a_person_walking_at_the_robot_stops_before_they_meet(sim_from, tmp_path, start):
    # a walker at 0.8 m/s, head on, meets a robot driving at 0.3 m/s: 0.35 m nearer between two firings of
    # a transducer. Judged where the ring last heard them, these two starts ended in a collision (0 of
    # 12 starts 0.037 m apart collided with the closing speed counted, 2 of 12 without; perception.closing)
    walker = f"people: [{{path: [[{start}, 0.05], [-1.8, 0.05]], speed: 0.8, wait_s: 60}}]\n"
    result, _ = run(sim_from, tmp_path, HALL + walker, "  Drive: {distance: 8.0, held_timeout: 10}\n", 15.0)
    truth, safety = result.report["ground_truth"], result.report["safety"]
    assert truth["collisions"] == 0 and truth["min_clearance_m"] > 0.03
    assert any("by itself" in event["reason"] for event in safety["events"])
