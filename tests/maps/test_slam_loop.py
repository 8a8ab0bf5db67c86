"""Loop closure: the planar motion between two keyframes by hand and by RANSAC, the pose graph, and a
drifted pose pulled back when an old place is seen again."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maps.exploration.head import StereoHead
from maps.exploration.pose import OdometryNoise
from maps.slam.graph import Edge, compose, optimise, relative, whitener
from maps.slam.keyframes import Keyframe
from maps.slam.loop import align_planar, find_loop, guided_matches, ransac_planar
from maps.slam.slam import SlamParams, StereoSlam
from maps.slam.viewpoint import Viewpoint
from perception.camera import PinholeCamera, StereoRig
from perception.geometry import Pose2D, rot_z, wrap_angle
from perception.stereo import StereoPoints, points_from_disparity
from perception.stereo_geometry import project

CAMERA = PinholeCamera(640, 480, 500.0, 500.0, 320.0, 240.0)
RIG = StereoRig(CAMERA, CAMERA, 0.1)
HEAD = StereoHead(ptu=(0.1, 0.0, 1.0), camera=(0.05, 0.0, 0.08))


def test_align_planar_by_hand():
    # turn by 90 degrees, then shift by (1, 2): (1, 0) -> (0, 1) + (1, 2) = (1, 3); (0, 1) -> (-1, 0) + (1, 2) = (0, 2)
    motion = align_planar(np.array([[1.0, 0.0], [0.0, 1.0]]), np.array([[1.0, 3.0], [0.0, 2.0]]))
    assert motion == pytest.approx([1.0, 2.0, math.pi / 2])


def test_ransac_finds_the_motion_among_wrong_matches():
    rng = np.random.default_rng(2)
    a = np.column_stack((rng.uniform(-3, 3, 60), rng.uniform(-3, 3, 60), rng.uniform(0, 2, 60)))
    truth = np.array([0.4, -0.7, math.radians(25.0)])
    b = a @ rot_z(truth[2]).T + (truth[0], truth[1], 0.0) + rng.normal(0, 0.01, a.shape)
    b[:20] = rng.uniform(-3, 3, (20, 3))  # a third of the matches are wrong
    cov = np.broadcast_to(np.eye(3) * 0.02**2, (60, 3, 3)).copy()
    match = ransac_planar(a, b, cov, cov, rng=rng)
    assert match is not None
    assert match.motion[:2] == pytest.approx(truth[:2], abs=0.01)
    assert match.motion[2] == pytest.approx(truth[2], abs=math.radians(0.3))
    inliers = set(match.a.tolist())
    assert len(inliers & set(range(20, 60))) >= 38 and len(inliers & set(range(20))) <= 1


def test_pose_graph_spreads_a_loop_error_over_the_weak_edges():
    # a square driven with a heading error: odometry edges say 1 m, turn 90 deg; the loop edge says the
    # fifth pose is the first; the solution closes the square
    step = np.array([1.0, 0.0, math.pi / 2])
    poses = [np.zeros(3)]
    for _ in range(4):
        last = poses[-1]
        wrong = step + (0.0, 0.0, math.radians(3.0))  # each turn measured 3 degrees too far
        c, s = math.cos(last[2]), math.sin(last[2])
        poses.append(np.array([last[0] + c * wrong[0] - s * wrong[1], last[1] + s * wrong[0] + c * wrong[1],
                               wrap_angle(last[2] + wrong[2])]))
    start = np.array(poses)
    soft = whitener(np.diag([0.05**2, 0.05**2, math.radians(2.0) ** 2]))
    edges = [Edge(i, i + 1, step, soft) for i in range(4)]
    edges.append(Edge(0, 4, np.zeros(3), whitener(np.diag([1e-4, 1e-4, 1e-6]))))
    solved = optimise(start, edges)
    assert np.linalg.norm(solved[4, :2]) < 0.02 and abs(solved[4, 2]) < math.radians(0.5)
    assert np.linalg.norm(start[4, :2]) > 0.1  # it was open before
    assert relative(solved[0], solved[2])[0, :2] == pytest.approx([1.0, 1.0], abs=0.05)


def _keyframe(index: int, points: np.ndarray, descriptors: np.ndarray, sigma: float = 0.02) -> Keyframe:
    cov = np.broadcast_to(np.eye(3) * sigma**2, (len(points), 3, 3)).copy()
    return Keyframe(index, float(index), np.zeros(3), np.eye(3) * 1e-4, 0.0, 0.0, points, cov, descriptors,
                    np.full(len(points), -1, dtype=np.int64))


def test_the_guided_gate_widens_with_the_predicted_heading_by_hand():
    # a new point 1 m ahead (x), the old one 0.1 m to its left; points 1 cm on each axis. A heading
    # sigma s moves a point 1 m ahead by s sideways: J Sigma J^T = diag(0, s^2, 0), so (L2) reads
    # 0.1^2 / (2 * 0.01^2 + s^2): s = 0.05 rad gives 3.70 (inside 11.34), s = 0.02 rad gives 16.7 (outside)
    descriptor = np.full((1, 32), 7, dtype=np.uint8)
    new = _keyframe(1, np.array([[1.0, 0.0, 0.0]]), descriptor, sigma=0.01)
    old = _keyframe(0, np.array([[1.0, 0.1, 0.0]]), descriptor, sigma=0.01)
    wide, narrow = np.diag([0.0, 0.0, 0.05**2]), np.diag([0.0, 0.0, 0.02**2])
    assert len(guided_matches(new, old, np.zeros(3), wide)[0]) == 1
    assert len(guided_matches(new, old, np.zeros(3), narrow)[0]) == 0


def test_a_place_of_repeated_texture_is_recognised_with_the_predicted_motion():
    # the old keyframe saw 60 corners, each twice (a repeated texture: the same descriptor 2 m away); the
    # new one sees the 60 again from T. Unguided, every corner has a look-alike: the ratio test keeps
    # none and no loop closes. Guided by a prediction 3 degrees and 0.15 m off, with the uncertainty
    # that says so, each corner's look-alike lies outside the gate (L2): the loop closes at T.
    rng = np.random.default_rng(4)
    corners = np.column_stack((rng.uniform(0.5, 3.0, 60), rng.uniform(-1.5, 1.5, 60), rng.uniform(0.0, 1.5, 60)))
    descriptors = rng.integers(0, 256, (60, 32), dtype=np.uint8)
    old = _keyframe(0, np.vstack((corners, corners + (0.0, 2.0, 0.0))), np.vstack((descriptors, descriptors)))
    truth = np.array([0.3, 0.1, math.radians(20.0)])
    seen = (corners - (truth[0], truth[1], 0.0)) @ rot_z(truth[2])  # T^-1 b: the corners in the new frame
    new = _keyframe(40, seen + rng.normal(0.0, 0.005, seen.shape), descriptors)
    assert find_loop(new, [old], "orb", rng=rng) is None
    drifted = truth + (0.1, -0.1, math.radians(3.0))
    sure = np.diag([0.1**2, 0.1**2, math.radians(2.0) ** 2])
    a, b = guided_matches(new, old, drifted, sure)
    assert len(a) == 60 and np.array_equal(b, a)  # each corner, none of its look-alikes
    loop = find_loop(new, [old], "orb", rng=rng, predicted=[(drifted, sure)])
    assert loop is not None and loop.old == 0 and loop.match.inliers == 60
    assert loop.match.motion[:2] == pytest.approx(truth[:2], abs=0.01)
    assert loop.match.motion[2] == pytest.approx(truth[2], abs=math.radians(0.3))
    # a prediction that is sure of a wrong motion finds nothing to match: no loop from the gate alone
    assert find_loop(new, [old], "orb", rng=rng, predicted=[(truth + (0.0, 0.0, math.radians(30.0)), sure)]) is None


# -- a drifted pose pulled back -----------------------------------------------------------------


def synthetic_frame(view: Viewpoint, pose: np.ndarray, world: np.ndarray, descriptors: np.ndarray,
                    rng: np.random.Generator) -> StereoPoints:
    """What the rig sees of the points ``world`` at the TRUE ``pose`` (0.3 px noise)."""
    p = view.to_camera(pose, world)[0]
    front = p[:, 0] > 0.5
    observed = project(RIG, p[front])[0] + rng.normal(0.0, 0.3, (int(front.sum()), 3))
    inside = (observed[:, 0] > 5) & (observed[:, 0] < 635) & (observed[:, 1] > 5) & (observed[:, 1] < 475)
    observed = observed[inside]
    return points_from_disparity(RIG, observed[:, :2], observed[:, 0] - observed[:, 2],
                                 descriptors[front][inside], "orb")


def scene(view: Viewpoint, pose: np.ndarray, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``count`` points 1.5-4 m in front of the camera at ``pose``, with random ORB-like descriptors."""
    camera = np.column_stack((rng.uniform(1.5, 4.0, count), rng.uniform(-1.2, 1.2, count),
                              rng.uniform(-0.9, 0.9, count)))
    return view.to_world(pose, camera)[0], rng.integers(0, 256, (count, 32), dtype=np.uint8)


def test_seeing_the_start_again_pulls_a_drifted_pose_back():
    rng = np.random.default_rng(5)
    precise = OdometryNoise(1e-3, 1e-8, 1e-3, 1e-8, 1e-8)  # the filter trusts odometry: its gate stays tight
    params = SlamParams(loop_window=2, odometry=precise)
    ahead, behind = Viewpoint.of(HEAD, 0.0, 0.0), Viewpoint.of(HEAD, math.pi, 0.0)
    place, place_descriptors = scene(ahead, np.zeros(3), 150, rng)
    slam = StereoSlam.start(Pose2D(0.0, 0.0, 0.0, 0.0), HEAD, params)
    slam.observe(synthetic_frame(ahead, np.zeros(3), place, place_descriptors, rng), RIG, 0.0, 0.0, 0.0)
    assert len(slam.keyframes) == 1 and len(slam.landmarks) > 100
    # drive away looking back at places never seen again, odometry turning 2 degrees too far per step
    truth, odometry = np.zeros(3), np.zeros(3)
    for k in range(1, 7):
        truth = truth + (0.25 * math.cos(truth[2]), 0.25 * math.sin(truth[2]), math.radians(10.0))
        odometry = odometry + (0.25 * math.cos(odometry[2]), 0.25 * math.sin(odometry[2]), math.radians(12.0))
        slam.predict(Pose2D(*odometry, float(k)))
        world, descriptors = scene(behind, truth, 120, rng)
        slam.observe(synthetic_frame(behind, truth, world, descriptors, rng), RIG, math.pi, 0.0, float(k))
    # and back near the start, looking at the first place again
    back = np.array([0.15, 0.1, math.radians(-5.0)])
    odometry = compose(odometry, relative(truth, back)[0])  # the last leg measured right: the drift stays
    slam.predict(Pose2D(*odometry, 7.0))
    before = slam.pose
    assert abs(wrap_angle(before.theta - back[2])) > math.radians(10.0)  # 12 degrees of drift
    outcome = slam.observe(synthetic_frame(ahead, back, place, place_descriptors, rng), RIG, 0.0, 0.0, 7.0)
    assert outcome.loop is not None and outcome.loop.old == 0
    after = slam.pose
    assert math.hypot(after.x - back[0], after.y - back[1]) < 0.02
    assert abs(wrap_angle(after.theta - back[2])) < math.radians(0.3)
