"""Feature detection: kinds, upright descriptors, wrap-around at the panorama seam."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from perception.camera import PanoramaCamera
from perception.features import available_kinds, detect
from perception.matching import match_features
from perception.synthetic import textured_panorama

PANO = PanoramaCamera()


@pytest.fixture(scope="module")
def image() -> np.ndarray:
    return textured_panorama(0)


def test_orb_is_the_default_and_respects_the_budget(image):
    features = detect(image, n_features=300)
    assert features.kind == "orb" and features.binary
    assert 200 <= len(features) <= 300
    assert features.descriptors.shape == (len(features), 32) and features.descriptors.dtype == np.uint8
    u, v = features.keypoints_uv.T
    assert (u >= -0.5).all() and (u < 719.5).all() and (v >= -0.5).all() and (v < 171.5).all()


def test_upright_sift_has_one_keypoint_per_location(image):
    features = detect(image, "sift", n_features=300)
    assert features.descriptors.shape[1] == 128 and features.descriptors.dtype == np.float32
    assert not features.binary
    positions = {tuple(np.round(p, 2)) for p in features.keypoints_uv}
    assert len(positions) == len(features)  # SIFT's multi-orientation copies were merged


def test_brisk_only_where_opencv_has_it(image):
    assert ("brisk" in available_kinds()) == hasattr(cv2, "BRISK_create")
    if "brisk" in available_kinds():
        assert detect(image, "brisk").descriptors.shape[1] == 64
    else:
        with pytest.raises(ValueError, match="BRISK"):
            detect(image, "brisk")
    with pytest.raises(ValueError, match="unknown feature kind"):
        detect(image, "surf")


def test_panorama_features_cover_the_seam_only_with_wrap(image):
    wrapped = detect(image, camera=PANO, n_features=1000)
    plain = detect(image, camera=PANO, n_features=1000, wrap=False)
    near_seam = lambda f: np.minimum(f.keypoints_uv[:, 0], 719 - f.keypoints_uv[:, 0]) < 15  # noqa: E731
    assert near_seam(wrapped).sum() >= 5
    assert near_seam(plain).sum() == 0  # ORB cannot see a corner whose patch crosses the border
    u = wrapped.keypoints_uv[:, 0]
    assert (u >= -0.5).all() and (u < 719.5).all()  # folded back: the pads' copies are gone


@pytest.mark.parametrize("kind", ["orb", "sift"])
def test_upright_descriptors_survive_a_turn_across_the_seam(image, kind):
    shift = 360  # a 180 deg turn: the seam's neighbourhood moves to the centre and back
    turned = np.roll(image, shift, axis=1)
    a = detect(image, kind, camera=PANO, n_features=800)
    b = detect(turned, kind, camera=PANO, n_features=800)
    found = match_features(a, b)
    du = (b.keypoints_uv[found.train, 0] - a.keypoints_uv[found.query, 0] - shift + 360) % 720 - 360
    dv = b.keypoints_uv[found.train, 1] - a.keypoints_uv[found.query, 1]
    # keypoints from coarse pyramid levels are quantised to ~1.2^level px: 4 px still tells right from wrong
    correct = (np.abs(du) < 4.0) & (np.abs(dv) < 4.0)
    assert len(found) > 150 and correct.mean() > 0.95
    seam = np.minimum(a.keypoints_uv[found.query, 0], 719 - a.keypoints_uv[found.query, 0]) < 20
    assert (correct & seam).sum() >= 3  # features on the seam are matched too
