"""LT-map files: a :class:`~maps.ltmap.tree.LandmarkTree` saved as map kind ``ltmap``, format version 3.

The container (magic line, JSON header with length and SHA-256, ``.npz`` payload, atomic write)
is :mod:`maps.mapfile`'s; the payload holds exactly :meth:`LandmarkTree.to_arrays`, so a map's
``memory_bytes()`` is what its arrays take in the file, and the header's ``meta`` holds what is
not an array: the landmark kind, the eq. 1 threshold the route was taught with (route
following switches viewframes at the same value) and eq. 1's scale ``b``. Version 1 files hold
a threshold of the earlier form of eq. 1 (the Pseudo-Huber cost of the angle, delta 2 deg) and
no scale: they are read with the eq. 1 threshold of the same bearing change
(:func:`perception.similarity.angle_form_threshold_angle`; 1e-3 becomes the cost of 3.04 deg).
Version 3 adds the viewframes' places (``viewframe_place``: where the teach's odometry put each
viewframe; route following drives by them while people hide the view, docs/ltmap.md); version 1
and 2 files are read as maps without places.
A damaged, truncated, foreign or inconsistent
file is one :class:`~maps.store.InputError` line, and a failed save leaves the previous file.
"""

from __future__ import annotations

import os
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from maps.ltmap.tree import LandmarkTree
from maps.mapfile import MapFile, decode_map, encode_map, read_map_file, write_map_file
from maps.store import Diagnostic, InputError
from perception.similarity import DEFAULT_SCALE, angle_form_threshold_angle, cost_of_angle

KIND = "ltmap"
VERSION = 3
ANGLE_FORM_VERSION = 1  # thresholds of the earlier form of eq. 1, read converted
READABLE = (ANGLE_FORM_VERSION, 2, VERSION)  # 2: no viewframe places


class LtmapMeta(BaseModel):
    """The ``meta`` of an LT-map file header."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    landmarks: Literal["ids", "orb", "brisk", "sift"] = Field(description="descriptor kind, or ids (ideal sensor)")
    threshold: float = Field(gt=0, allow_inf_nan=False, description="eq. 1 threshold the route was taught with")
    scale: float = Field(DEFAULT_SCALE, gt=0, allow_inf_nan=False, description="eq. 1's b (a cosine distance)")


def _meta(tree: LandmarkTree) -> dict:
    return LtmapMeta(landmarks=tree.kind, threshold=tree.threshold, scale=tree.scale).model_dump()


def encode_ltmap(tree: LandmarkTree) -> bytes:
    """The bytes of an LT-map file (what :func:`save_ltmap` writes)."""
    return encode_map(kind=KIND, version=VERSION, arrays=tree.to_arrays(), meta=_meta(tree))


def save_ltmap(path: str | os.PathLike, tree: LandmarkTree) -> None:
    """Save atomically: ``path`` holds either its previous content or all of this map."""
    write_map_file(path, kind=KIND, version=VERSION, arrays=tree.to_arrays(), meta=_meta(tree))


def decode_ltmap(data: bytes, *, file: str) -> LandmarkTree:
    """An LT-map from file bytes; one-line :class:`InputError` naming ``file`` when they are not one."""
    return _tree(decode_map(data, file=file, kind=KIND, versions=READABLE), file)


def load_ltmap(path: str | os.PathLike) -> LandmarkTree:
    """Load an LT-map file, checking container, header and the tree's consistency."""
    return _tree(read_map_file(path, kind=KIND, versions=READABLE), str(path))


def _tree(loaded: MapFile, file: str) -> LandmarkTree:
    try:
        meta = LtmapMeta.model_validate(loaded.meta)
    except ValidationError as exc:
        where = ".".join(str(part) for part in exc.errors()[0]["loc"]) or "meta"
        raise InputError([Diagnostic(file, 0, 0, f"damaged LT-map: bad header meta ({where})")]) from None
    threshold = meta.threshold
    if loaded.header.version == ANGLE_FORM_VERSION:
        threshold = cost_of_angle(angle_form_threshold_angle(threshold), meta.scale)
    try:
        return LandmarkTree.from_arrays(loaded.arrays, kind=meta.landmarks, threshold=threshold, scale=meta.scale)
    except ValueError as exc:
        raise InputError([Diagnostic(file, 0, 0, f"damaged LT-map: {exc}")]) from None
