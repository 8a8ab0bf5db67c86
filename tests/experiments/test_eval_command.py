"""The generic ``bearings eval`` command: an area's own options (``--option NAME=VALUE``)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from experiments.commands.eval import area_options

AREA = SimpleNamespace(OPTIONS={"camera": "which camera", "route": "waypoints"})


def test_options_reach_the_area_as_text():
    assert area_options(AREA, "demo", ["camera=landmarks", "route = 1,0,2,0"]) == {
        "camera": "landmarks", "route": "1,0,2,0"}
    assert area_options(AREA, "demo", []) == {}
    assert area_options(AREA, "demo", ["route="]) == {"route": ""}  # an empty value is the area's to judge


@pytest.mark.parametrize(("given", "message"), [
    (["camera"], "NAME=VALUE"),
    (["=x"], "NAME=VALUE"),
    (["speed=1"], "no option 'speed' (its options: camera, route)"),
    (["camera=a", "camera=b"], "given twice"),
])
def test_bad_options_are_refused(given, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        area_options(AREA, "demo", given)


def test_an_area_without_options_takes_none():
    with pytest.raises(ValueError, match="its options: none"):
        area_options(SimpleNamespace(), "demo", ["camera=x"])
