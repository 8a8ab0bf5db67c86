"""Target roadmap: covariance fusion and costs by hand, shortest paths, the file and its damage."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from maps.mapfile import read_map_file, write_map_file
from maps.roadmap import EdgeMotion, InconsistentEstimates, Roadmap, fuse, fuse_round_trip
from maps.store import InputError
from perception.geometry import Pose2D

angles = st.floats(-math.pi + 1e-6, math.pi - 1e-6)


def _motion(a1: float, d: float, a2: float, variances=(0.01, 0.04, 0.01)) -> EdgeMotion:
    return EdgeMotion(a1, d, a2, np.diag(variances))


@st.composite
def motions(draw) -> EdgeMotion:
    root = np.array(draw(st.lists(st.floats(-0.3, 0.3), min_size=9, max_size=9))).reshape(3, 3)
    covariance = root @ root.T + np.eye(3) * draw(st.floats(1e-4, 0.05))
    return EdgeMotion(draw(angles), draw(st.floats(0.05, 5.0)), draw(angles), covariance)


def test_fusion_of_independent_estimates_by_hand():
    a = _motion(0.1, 2.0, -0.1, (0.01, 0.04, 0.01))
    b = _motion(0.3, 2.2, 0.1, (0.03, 0.04, 0.01))
    fused = fuse(a, b)
    # angle1: weights 100 and 33.3 -> (10 + 10) / 133.3 = 0.15, variance 1 / 133.3 = 0.0075
    np.testing.assert_allclose(fused.mean, [0.15, 2.1, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.diag(fused.covariance), [0.0075, 0.02, 0.005], atol=1e-12)


def test_fusion_with_correlation_by_hand():
    """Correlated angle1/distance: S1^-1 = [[200, -100], [-100, 200]] / 3, S2^-1 = 50 I."""
    first = EdgeMotion(0.0, 2.0, 0.0, np.array([[0.02, 0.01, 0.0], [0.01, 0.02, 0.0], [0.0, 0.0, 0.01]]))
    second = EdgeMotion(0.1, 2.0, 0.0, np.diag([0.02, 0.02, 0.01]))
    fused = fuse(first, second)
    # information (350 / 3, -100 / 3; -100 / 3, 350 / 3), determinant 12500; information
    # vector (-185 / 3, 700 / 3): angle1 = 5250 / 112500, distance = 226500 / 112500
    np.testing.assert_allclose(fused.mean, [5250 / 112500, 226500 / 112500, 0.0], atol=1e-12)
    np.testing.assert_allclose(fused.covariance[:2, :2], np.array([[350, 100], [100, 350]]) / 3 / 12500, atol=1e-12)
    assert fused.covariance[2, 2] == pytest.approx(0.005)


def test_fusion_across_the_angle_seam():
    fused = fuse(_motion(math.pi - 0.05, 1.0, 0.0), _motion(-math.pi + 0.05, 1.0, 0.0))
    assert abs(math.remainder(fused.angle1 - math.pi, 2 * math.pi)) < 1e-12


def test_estimates_that_disagree_are_not_fused():
    a = _motion(0.0, 1.0, 0.0, (0.01, 0.01, 0.01))
    far = _motion(0.0, 1.6, 0.0, (0.01, 0.01, 0.01))  # 0.6 m apart, sigma 0.14: 4.2 > 4.03 (3 dof, 99.9 %)
    with pytest.raises(InconsistentEstimates, match="Mahalanobis distance 4.2"):
        fuse(a, far)
    assert fuse(a, far, gate=None).distance == pytest.approx(1.3)
    assert fuse(a, _motion(0.0, 1.5, 0.0, (0.01, 0.01, 0.01))).distance == pytest.approx(1.25)  # 3.5: fused
    roadmap = Roadmap().with_target("A", Pose2D()).with_target("B", Pose2D(1.0, 0.0)).with_edge("A", "B", a)
    with pytest.raises(InconsistentEstimates):
        roadmap.with_edge("A", "B", far)


def test_a_fused_negative_distance_is_the_same_motion_forwards():
    """Short motions with a strongly correlated estimate can fuse to a distance below zero."""
    a = _motion(0.0, 0.05, 0.0, (0.01, 0.04, 0.01))
    b = EdgeMotion(0.2, 0.02, 0.0, np.array([[0.01, 0.0095, 0.0], [0.0095, 0.01, 0.0], [0.0, 0.0, 0.01]]))
    info_a, info_b = np.linalg.inv(a.covariance), np.linalg.inv(b.covariance)
    raw_cov = np.linalg.inv(info_a + info_b)
    a1, d, a2 = raw_cov @ (info_a @ a.mean + info_b @ b.mean)
    assert d < 0
    fused = fuse(a, b)
    assert fused.distance == pytest.approx(-d)
    expected = Pose2D(d * math.cos(a1), d * math.sin(a1), a1 + a2)
    assert fused.relative_pose().distance_to(expected) < 1e-12
    assert abs(math.remainder(fused.relative_pose().theta - expected.theta, 2 * math.pi)) < 1e-12
    assert fused.covariance[0, 1] == pytest.approx(-raw_cov[0, 1])


def test_round_trip_turns_the_way_back_around():
    forward = _motion(0.2, 1.5, 0.3, (0.01, 0.04, 0.02))
    backward = EdgeMotion(math.pi - 0.3, 1.5, math.pi - 0.2, np.diag([0.02, 0.04, 0.01]))  # the same placement
    fused = fuse_round_trip(forward, backward)
    np.testing.assert_allclose(fused.mean, forward.mean, atol=1e-12)
    np.testing.assert_allclose(np.diag(fused.covariance), [0.005, 0.02, 0.01], atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(motions())
def test_reversing_inverts_the_relative_pose(motion):
    back = motion.reversed().relative_pose()
    expected = motion.relative_pose().inverse()
    assert back.distance_to(expected) < 1e-9
    assert abs(math.remainder(back.theta - expected.theta, 2 * math.pi)) < 1e-9
    twice = motion.reversed().reversed()
    np.testing.assert_allclose(twice.covariance, motion.covariance)


@st.composite
def consistent_pairs(draw) -> tuple[EdgeMotion, EdgeMotion]:
    """Two estimates of one motion whose difference is within 3 standard deviations (Mahalanobis)."""
    a, other = draw(motions()), draw(motions())
    z = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3)))
    mean = a.mean + np.linalg.cholesky(a.covariance + other.covariance) @ z
    return a, EdgeMotion.from_mean(mean, other.covariance) if mean[1] > 0 else a


@settings(max_examples=100, deadline=None)
@given(consistent_pairs())
def test_fusion_is_symmetric_and_never_less_certain(pair):
    a, b = pair
    ab, ba = fuse(a, b), fuse(b, a)
    assert abs(math.remainder(ab.angle1 - ba.angle1, 2 * math.pi)) < 1e-7
    assert ab.distance == pytest.approx(ba.distance, abs=1e-7)
    assert np.linalg.eigvalsh(a.covariance - ab.covariance).min() > -1e-12  # fused <= either estimate


@settings(max_examples=100, deadline=None)
@given(motions())
def test_from_relative_pose_inverts_relative_pose(motion):
    again = EdgeMotion.from_relative_pose(motion.relative_pose(), motion.pose_covariance())
    np.testing.assert_allclose(np.cos(again.mean - motion.mean)[[0, 2]], 1.0, atol=1e-9)
    assert again.distance == pytest.approx(motion.distance)
    np.testing.assert_allclose(again.covariance, motion.covariance, atol=1e-9)


def test_cost_is_sigma_x_plus_sigma_y_and_depends_on_direction():
    straight = _motion(0.0, 2.0, 0.0, (0.01, 0.04, 0.01))
    assert straight.cost == pytest.approx(0.2 + 2 * 0.1)  # sigma_x = sigma_d, sigma_y = d sigma_a1
    turned = _motion(0.0, 2.0, math.pi / 2, (0.01, 0.04, 1e-4))
    assert turned.cost == pytest.approx(0.4)
    # back: (pi/2, 2, pi), covariance diag(1e-4, 0.04, 0.01): sigma_x = d * 0.01, sigma_y = 0.2
    assert turned.reversed().cost == pytest.approx(0.02 + 0.2)


def _graph() -> Roadmap:
    """A - B - C cheap chain, A - C direct but uncertain, D alone."""
    roadmap = Roadmap()
    for i, name in enumerate("ABCD"):
        roadmap = roadmap.with_target(name, Pose2D(float(i), 0.0, 0.0), image=f"targets/{name}.png")
    cheap = _motion(0.0, 1.0, 0.0, (1e-4, 1e-4, 1e-4))  # cost 0.01 + 0.01
    roadmap = roadmap.with_edge("A", "B", cheap).with_edge("C", "B", cheap)
    return roadmap.with_edge("A", "C", _motion(0.0, 2.0, 0.0, (0.01, 0.04, 0.01)))  # cost 0.4


def test_shortest_path_by_uncertainty_not_by_hops():
    roadmap = _graph()
    path = roadmap.shortest_path("A", "C")
    assert path.names == ("A", "B", "C") and path.cost == pytest.approx(0.04)
    assert path.motions[1].relative_pose().distance_to(Pose2D(-1.0, 0.0)) < 1e-12  # C -> B reversed
    assert roadmap.shortest_path("A", "D") is None
    assert roadmap.shortest_path("A", "A").names == ("A",)
    with pytest.raises(KeyError):
        roadmap.shortest_path("A", "Z")


def test_connectivity():
    roadmap = _graph()
    assert not roadmap.is_connected()
    assert {frozenset("ABC"), frozenset("D")} == set(roadmap.components())
    assert roadmap.with_edge("D", "A", _motion(math.pi, 3.0, 0.0)).is_connected()
    assert Roadmap().is_connected() and Roadmap().with_target("A", Pose2D()).is_connected()


def test_measuring_an_edge_again_fuses_whichever_way():
    roadmap = Roadmap().with_target("A", Pose2D()).with_target("B", Pose2D(1.0, 0.0))
    roadmap = roadmap.with_edge("A", "B", _motion(0.0, 1.0, 0.0)).with_edge("B", "A", _motion(math.pi, 1.2, math.pi))
    assert len(roadmap.edges) == 1
    assert roadmap.motion("A", "B").distance == pytest.approx(1.1)
    assert roadmap.motion("A", "B").covariance[1, 1] == pytest.approx(0.02)


def test_invalid_motions_are_refused():
    with pytest.raises(ValueError, match="positive definite"):
        EdgeMotion(0.0, 1.0, 0.0, np.zeros((3, 3)))
    with pytest.raises(ValueError, match="distance"):
        _motion(0.0, -1.0, 0.0)
    with pytest.raises(ValueError, match="different"):
        _graph().with_edge("A", "A", _motion(0.0, 1.0, 0.0))


def test_file_round_trip(tmp_path):
    roadmap = _graph().with_target("Küche ☕", Pose2D(-1.5, 2.0, 3.0))
    path = tmp_path / "lab.roadmap"
    roadmap.save(path)
    loaded = Roadmap.load(path)
    assert loaded.names == roadmap.names
    assert [t.image for t in loaded.targets] == [t.image for t in roadmap.targets]
    assert [t.pose for t in loaded.targets] == [t.pose for t in roadmap.targets]
    for mine, theirs in zip(roadmap.edges, loaded.edges, strict=True):
        assert (mine.source, mine.target) == (theirs.source, theirs.target)
        np.testing.assert_array_equal(mine.motion.mean, theirs.motion.mean)
        np.testing.assert_array_equal(mine.motion.covariance, theirs.motion.covariance)
    assert read_map_file(path).meta["targets"][-1] == "Küche ☕"  # names readable in the header


def _load_error(path) -> str:
    with pytest.raises(InputError) as info:
        Roadmap.load(path)
    assert len(info.value.diagnostics) == 1 and "\n" not in str(info.value)
    return str(info.value)


def test_every_damage_is_one_clear_line(tmp_path):
    path = tmp_path / "lab.roadmap"
    _graph().save(path)
    data = path.read_bytes()
    path.write_bytes(data[:-7])
    assert "truncated" in _load_error(path)
    flipped = bytearray(data)
    flipped[-40] ^= 0x10
    path.write_bytes(bytes(flipped))
    assert "checksum" in _load_error(path)
    write_map_file(path, kind="ltmap", version=1, arrays={})
    assert "not a roadmap" in _load_error(path)
    write_map_file(path, kind="roadmap", version=2, arrays={})
    assert "newer bearings" in _load_error(path)
    assert "no such file" in _load_error(tmp_path / "missing.roadmap")


def test_inconsistent_content_is_one_clear_line(tmp_path):
    arrays, meta = _graph().to_arrays()
    path = tmp_path / "bad.roadmap"
    cases = [
        ({**meta, "targets": ["A", "A", "B", "C"]}, arrays, "unique"),
        ({**meta, "images": []}, arrays, "one image path per target"),
        ({"targets": meta["targets"]}, arrays, "images"),
        (meta, {**arrays, "edge_ends": np.array([[0, 9]] * 3)}, "target indices"),
        (meta, {**arrays, "edge_covariances": -arrays["edge_covariances"]}, "positive definite"),
        (meta, {k: v for k, v in arrays.items() if k != "edge_motions"}, "edge_motions is missing"),
        (meta, {**arrays, "target_poses": np.full((4, 3), np.nan)}, "finite"),
    ]
    for bad_meta, bad_arrays, message in cases:
        write_map_file(path, kind="roadmap", version=1, arrays=bad_arrays, meta=bad_meta)
        assert message in _load_error(path), message
