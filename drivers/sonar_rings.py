"""Where a Pioneer's sonar transducers and bumper segments sit: the ring geometry of each model.

The sonar tables are the ``SonarUnit`` lines of ARIA's public robot parameter files
(``params/p3dx.p`` and ``params/p3at.p`` of the AriaCoda repository, github.com/reedhedges/AriaCoda;
``p3dx-sh.p`` and ``p3at-sh.p`` list the same units): transducer number, x and y on the base in mm
(x forward, y left, from the centre of rotation) and the heading of its disc in degrees
(counter-clockwise from forward). Transducers 0-7 are the front ring, left to right; 8-15 the rear
ring, right to left. The same files give five front and five rear bumper segments
(``NumFrontBumpers 5``, ``NumRearBumpers 5``); their positions are not in the files, so
:func:`bumper_ring` spreads them over the front and rear arcs of the robot's disc.

The simulator builds its sonar ring and bumpers from these (:mod:`drivers.sim.ranges`); a driver
of a real Pioneer can describe its readings with the same values.
"""

from __future__ import annotations

import math

from perception.ranges import Bumper, RangeSensor

# (x mm, y mm, heading deg) of SonarUnit 0..15
SONAR_UNITS: dict[str, tuple[tuple[int, int, int], ...]] = {
    "p3dx": (
        (69, 136, 90), (114, 119, 50), (148, 78, 30), (166, 27, 10),
        (166, -27, -10), (148, -78, -30), (114, -119, -50), (69, -136, -90),
        (-157, -136, -90), (-203, -119, -130), (-237, -78, -150), (-255, -27, -170),
        (-255, 27, 170), (-237, 78, 150), (-203, 119, 130), (-157, 136, 90),
    ),
    "p3at": (
        (147, 136, 90), (193, 119, 50), (227, 79, 30), (245, 27, 10),
        (245, -27, -10), (227, -79, -30), (193, -119, -50), (147, -136, -90),
        (-144, -136, -90), (-189, -119, -130), (-223, -79, -150), (-241, -27, -170),
        (-241, 27, 170), (-223, 79, 150), (-189, 119, 130), (-144, 136, 90),
    ),
}  # fmt: skip
RING_SIZE = 8  # transducers per ring: front 0-7, rear 8-15
SONAR_FOV = math.radians(30.0)  # rad: the whole cone of one transducer
BUMPER_BEARINGS_DEG = (60, 30, 0, -30, -60, -120, -150, 180, 150, 120)  # front left to right, then rear


def sonar_ring(model: str, *, max_range: float = 5.0) -> tuple[RangeSensor, ...]:
    """The 16 transducers of ``model`` (``p3dx`` or ``p3at``) as range sensors, in SonarUnit order."""
    if model not in SONAR_UNITS:
        raise ValueError(f"no sonar ring for {model!r} (known: {', '.join(SONAR_UNITS)})")
    return tuple(RangeSensor(x / 1000.0, y / 1000.0, math.radians(heading), SONAR_FOV, max_range)
                 for x, y, heading in SONAR_UNITS[model])


def bumper_ring(radius: float) -> tuple[Bumper, ...]:
    """Five front and five rear bumper segments on a disc of ``radius`` (m), every 30 degrees over
    the front arc (-60..60 deg) and the rear arc (120..240 deg): front left to right, then rear
    right to left (clockwise round the robot seen from above)."""
    out = []
    for bearing in BUMPER_BEARINGS_DEG:
        a = math.radians(bearing)
        out.append(Bumper(radius * math.cos(a), radius * math.sin(a), 1 if abs(bearing) < 90 else -1))
    return tuple(out)
