"""The simulated base and pan-tilt unit: collisions stall the robot, PTU-D46 limits and slew rate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.interfaces import Base, PanTilt
from perception.geometry import Pose2D, frame_to_parent, parent_to_frame

ROOM = """
start: {x: 1.0, y: 1.0, theta_deg: 0}
robot: {radius: 0.25}
walls: [{points: [[0, 0], [4, 0], [4, 2], [0, 2]], closed: true, height: 2}]
pillars: [{center: [2.0, 1.6], radius: 0.2, height: 2}]
cameras: [{name: eye, kind: bearings}]
"""


def drive(sim, v: float, w: float, seconds: float, dt: float = 0.05) -> None:
    for _ in range(round(seconds / dt)):
        sim.robot.base.drive(v, w)  # commanded every step, as a client does (the base's watchdog)
        sim.step(dt)


def test_the_sim_drivers_implement_the_interfaces(sim_from) -> None:
    sim = sim_from(ROOM)
    assert isinstance(sim.robot.base, Base)
    assert isinstance(sim.robot.ptu, PanTilt)


def test_driving_into_a_wall_stops_the_robot_and_raises_the_stall_flag(sim_from) -> None:
    sim = sim_from(ROOM)
    drive(sim, 0.5, 0.0, 15.0)
    pose = sim.true_pose()
    assert sim.robot.base.stalled()
    assert 4.0 - 0.25 - 0.05 < pose.x <= 4.0 - 0.25  # at the wall, never through it
    odom_before = sim.robot.base.odometry()
    drive(sim, 0.5, 0.0, 1.0)  # still pushing: nothing moves, odometry included
    assert sim.true_pose().x == pose.x
    assert (sim.robot.base.odometry().as_array() == odom_before.as_array()).all()
    assert sim.robot.base.stalled()
    drive(sim, -0.3, 0.0, 2.0)  # backing off frees it
    assert not sim.robot.base.stalled()
    assert sim.true_pose().x < pose.x - 0.3
    report = sim.ground_truth_report()
    assert report["collisions"] == 1 and report["stalled_time_s"] > 1.0


def test_a_pillar_stops_the_robot_too(sim_from) -> None:
    sim = sim_from(ROOM.replace("theta_deg: 0", "theta_deg: 0").replace("y: 1.0,", "y: 1.5,"))
    drive(sim, 0.4, 0.0, 6.0)
    assert sim.robot.base.stalled()
    assert math.hypot(sim.true_pose().x - 2.0, sim.true_pose().y - 1.6) >= 0.45 - 1e-9


def test_turning_in_place_next_to_a_wall_is_not_a_collision(sim_from) -> None:
    sim = sim_from(ROOM.replace("x: 1.0, y: 1.0", "x: 0.3, y: 1.0"))
    drive(sim, 0.0, 1.0, 3.0)
    assert not sim.robot.base.stalled() and sim.collisions == 0


def test_ptu_clips_targets_to_the_ptu_d46_limits(sim_from) -> None:
    sim = sim_from(ROOM)
    ptu = sim.robot.ptu
    ptu.move(math.radians(170), math.radians(-60), 10.0)
    drive(sim, 0.0, 0.0, 3.0)
    state = ptu.state()
    assert math.degrees(state.pan) == pytest.approx(159.0)
    assert math.degrees(state.tilt) == pytest.approx(-47.0)
    assert not state.moving
    ptu.move(math.radians(-170), math.radians(40), 10.0)
    drive(sim, 0.0, 0.0, 3.0)
    assert math.degrees(ptu.state().pan) == pytest.approx(-159.0)
    assert math.degrees(ptu.state().tilt) == pytest.approx(31.0)
    limits = ptu.state().limits  # what it reports, for the head behaviours to keep within
    assert np.degrees(limits.pan).tolist() == pytest.approx([-159.0, 159.0])
    assert np.degrees(limits.tilt).tolist() == pytest.approx([-47.0, 31.0])
    assert math.degrees(limits.max_speed) == pytest.approx(300.0) and limits.pan_step == 0.0


def test_ptu_slews_at_the_requested_speed_capped_at_its_top_rate(sim_from) -> None:
    sim = sim_from(ROOM)
    ptu = sim.robot.ptu
    ptu.move(math.radians(90), math.radians(20), math.radians(30))  # 30 deg/s
    drive(sim, 0.0, 0.0, 1.0)
    state = ptu.state()
    assert math.degrees(state.pan) == pytest.approx(30.0)
    assert math.degrees(state.tilt) == pytest.approx(20.0)  # reached after 2/3 s
    assert state.moving and state.stamp == pytest.approx(1.0)
    ptu.halt()
    drive(sim, 0.0, 0.0, 0.5)
    assert math.degrees(ptu.state().pan) == pytest.approx(30.0) and not ptu.state().moving
    ptu.move(math.radians(-150), 0.0, 100.0)  # asks for 100 rad/s: gets 300 deg/s
    drive(sim, 0.0, 0.0, 0.25)
    assert math.degrees(ptu.state().pan) == pytest.approx(30.0 - 75.0)


def test_ptu_rejects_non_finite_commands(sim_from) -> None:
    with pytest.raises(ValueError, match="finite"):
        sim_from(ROOM).robot.ptu.move(math.nan, 0.0, 1.0)


def test_ptu_mounted_cameras_follow_pan_and_tilt(sim_from) -> None:
    sim = sim_from(
        """
        landmarks: [{id: 1, position: [0, 5, 1.08]}]
        ptu: {position: [0, 0, 1.0]}
        cameras: [{name: eye, kind: bearings, mount: ptu, pose: {x: 0, z: 0.08}, azimuth_fov_deg: 60}]
        """
    )
    pose = Pose2D(0, 0, 0)
    assert len(sim.observe(pose, "eye")) == 0  # 90 deg to the left, outside 60 deg
    sim.robot.ptu.move(math.radians(90), 0.0, 10.0)
    drive(sim, 0.0, 0.0, 1.0)
    seen = sim.observe(pose, "eye")
    assert seen.ids.tolist() == [1]
    assert seen.bearings[0] == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
    sim.robot.ptu.move(math.radians(90), math.radians(20), 10.0)
    drive(sim, 0.0, 0.0, 1.0)
    b = sim.observe(pose, "eye").bearings[0]
    # the camera looks 20 deg up (and sits a little higher and back): the landmark is ~20 deg below
    assert math.degrees(math.atan2(b[2], b[0])) == pytest.approx(-20.0, abs=1.5)


def test_ground_truth_report_measures_goal_and_path_errors_in_world_or_start_frame(sim_from) -> None:
    sim = sim_from(ROOM.replace("theta_deg: 0", "theta_deg: 90"), seed=1)
    drive(sim, 0.3, 0.0, 2.0)  # about 0.6 m straight along +y of the world
    pose = sim.true_pose()
    world = sim.ground_truth_report(goal=(1.0, 1.7), reference_path=[(1.0, 0.0), (1.0, 3.0)])
    assert world["goal_error_m"] == pytest.approx(math.hypot(pose.x - 1.0, pose.y - 1.7))
    assert world["path_error_max_m"] == pytest.approx(abs(pose.x - 1.0), abs=0.02)
    assert world["path_error_m"] <= world["path_error_max_m"]
    assert world["trajectory_length_m"] == pytest.approx(pose.y - 1.0, abs=0.02)
    start = sim.ground_truth_report(goal=(0.7, 0.0), reference_path=[(0, 0), (2, 0)], frame="start")
    assert start["goal_error_m"] == pytest.approx(math.hypot(pose.y - 1.0 - 0.7, 1.0 - pose.x), abs=1e-9)
    assert start["path_error_m"] == pytest.approx(world["path_error_m"], abs=1e-9)
    assert start["trajectory_length_m"] == pytest.approx(world["trajectory_length_m"])


def test_the_start_frame_is_the_start_pose_turned_and_moved() -> None:
    """From the start (1, 2) facing +y (90 deg): 1 m ahead is world (1, 3), 1 m left is world (0, 2)."""
    start = Pose2D(1.0, 2.0, math.pi / 2)
    world = frame_to_parent(start, np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]))
    assert world == pytest.approx(np.array([[1.0, 3.0], [0.0, 2.0], [1.0, 2.0]]), abs=1e-12)
    assert parent_to_frame(start, world) == pytest.approx(np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]), abs=1e-12)


def test_a_long_step_cannot_jump_over_a_thin_wall(sim_from) -> None:
    sim = sim_from(
        """
        start: {x: 0, y: 0}
        walls: [{points: [[0.6, -2], [0.6, 2]], height: 1}]
        cameras: [{name: eye, kind: bearings}]
        """
    )
    sim.drive.velocity = (1.2, 0.0)  # already at full speed: one 1 s step would end beyond the wall
    sim.robot.base.drive(1.2, 0.0)
    sim.step(1.0)
    assert sim.robot.base.stalled() and sim.true_pose().x < 0.6


def test_the_report_holds_every_stop_exactly_where_the_trajectory_is_decimated(sim_from) -> None:
    """A still stretch between two motions is one ``stops`` row: its times and the pose held."""
    sim = sim_from(ROOM)
    drive(sim, 0.3, 0.0, 1.0)
    drive(sim, 0.0, 0.0, 2.0)  # decelerates, then stands
    still = sim.true_pose()
    t_still = sim.time
    drive(sim, 0.0, 0.5, 1.0)  # turns on the spot
    drive(sim, 0.0, 0.0, 1.0)
    stops = sim.ground_truth_report()["stops"]
    middle = [s for s in stops if s[0] <= t_still <= s[1]]
    assert len(middle) == 1
    t0, t1, x, y, theta = middle[0]
    assert 1.0 < t0 < 2.0 and t1 == pytest.approx(t_still, abs=0.051)  # the turn starts at once
    assert (x, y, theta) == pytest.approx((still.x, still.y, still.theta), abs=1e-4)
    assert stops[-1][1] == pytest.approx(sim.time) and len(stops) == 2  # and standing at the end


def test_a_base_left_without_commands_stops_as_the_robots_firmware_stops_it(sim_from) -> None:
    """The firmware's watchdog rule (docs/protocols.md): no command for 2 s, the base stops."""
    sim = sim_from(ROOM)
    sim.robot.base.drive(0.3, 0.0)  # once, and never again
    for _ in range(round(1.9 / 0.05)):
        sim.step(0.05)
    assert sim.drive.target == (0.3, 0.0) and sim.drive.velocity[0] > 0.29
    for _ in range(round(0.2 / 0.05)):
        sim.step(0.05)
    assert sim.drive.target == (0.0, 0.0)  # 2 s without a command: stopping (at the deceleration limit)
    for _ in range(round(2.0 / 0.05)):
        sim.step(0.05)
    assert sim.drive.velocity == (0.0, 0.0)
