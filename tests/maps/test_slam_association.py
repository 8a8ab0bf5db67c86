"""Which feature is which landmark: the gate (A2) by hand, and the gate before the descriptor."""

from __future__ import annotations

import numpy as np
import pytest

from maps.slam.association import CHI2_3DOF_99, Prediction, associate, gate_distance


def test_gate_distance_by_hand():
    # diagonal S: (1 / 1) + (2^2 / 4) + 0 = 2
    assert gate_distance(np.array([1.0, 2.0, 0.0]), np.diag([1.0, 4.0, 1.0])[None])[0] == pytest.approx(2.0)
    # correlated u, v: S_uv = [[2, 1], [1, 2]], S_uv^-1 = [[2, -1], [-1, 2]] / 3; nu = (1, 1): (2 - 1 - 1 + 2) / 3
    s = np.array([[[2.0, 1.0, 0.0], [1.0, 2.0, 0.0], [0.0, 0.0, 1.0]]])
    assert gate_distance(np.array([1.0, 1.0, 0.0]), s)[0] == pytest.approx(2.0 / 3.0)
    # across the correlation the same size of innovation is less likely: (2 + 1 + 1 + 2) / 3 = 2
    assert gate_distance(np.array([1.0, -1.0, 0.0]), s)[0] == pytest.approx(2.0)


def _prediction(observed: np.ndarray, sigma: float = 2.0) -> Prediction:
    n = len(observed)
    zeros = np.zeros((n, 3, 3))
    return Prediction(np.arange(n), observed, zeros, zeros, np.broadcast_to(np.eye(3) * sigma**2, (n, 3, 3)).copy())


def test_the_gate_tells_look_alikes_apart_that_descriptors_cannot():
    same = np.full((1, 32), 0b10101010, dtype=np.uint8)
    # two landmarks with the same descriptor, predicted 200 px apart (sigma 2 px)
    prediction = _prediction(np.array([[100.0, 100.0, 90.0], [300.0, 100.0, 290.0]]))
    features = np.array([[299.0, 101.0, 289.0], [101.0, 100.0, 91.0]])
    found = associate(prediction, np.repeat(same, 2, axis=0), features, np.repeat(same, 2, axis=0))
    assert dict(zip(found.landmark.tolist(), found.feature.tolist(), strict=True)) == {0: 1, 1: 0}


def test_a_feature_at_another_depth_or_beyond_the_gate_is_not_the_landmark():
    same = np.full((1, 32), 7, dtype=np.uint8)
    prediction = _prediction(np.array([[100.0, 100.0, 90.0]]))
    # same pixel, disparity 40 px instead of 10 (a nearer object in front): d^2 = 30^2 / 4 = 225 > 11.34
    behind = associate(prediction, same, np.array([[100.0, 100.0, 60.0]]), same)
    # 8 px off in u and u_r: d^2 = 2 * 64 / 4 = 32 > 11.34
    aside = associate(prediction, same, np.array([[108.0, 100.0, 98.0]]), same)
    # 3 px off in u and u_r: d^2 = 2 * 9 / 4 = 4.5 <= 11.34
    near = associate(prediction, same, np.array([[103.0, 100.0, 93.0]]), same)
    assert (len(behind), len(aside), len(near)) == (0, 0, 1)
    assert 2 * 9 / 4 <= CHI2_3DOF_99 < 2 * 64 / 4


def test_the_descriptor_decides_within_the_gate_and_must_be_close():
    rng = np.random.default_rng(0)
    landmark = rng.integers(0, 256, (1, 32), dtype=np.uint8)
    other = rng.integers(0, 256, (1, 32), dtype=np.uint8)  # ~128 bits away
    close = landmark.copy()
    close[0, 0] ^= 0b111  # 3 bits away
    prediction = _prediction(np.array([[100.0, 100.0, 90.0]]))
    features = np.array([[101.0, 100.0, 91.0], [99.0, 100.0, 89.0]])
    found = associate(prediction, landmark, features, np.vstack((other, close)))
    assert found.feature.tolist() == [1]
    assert len(associate(prediction, landmark, features[:1], other)) == 0  # nothing close enough
