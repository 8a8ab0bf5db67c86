"""The Pioneer's body as ARIA's parameter files give it: footprint, sonar ring, bumpers.

Per model (the subclass the robot reports in SYNC2), from ARIA's public ``params/<subclass>.p``
(``reedhedges/AriaCoda``; the tables and their sources are in docs/protocols.md):

- the footprint: ``RobotLengthFront``, ``RobotLengthRear``, ``RobotWidth`` (a box about the
  centre of rotation) and ``RobotRadius`` (what ARIA turns in place within);
- the sonar ring: one ``SonarUnit <n> <x mm> <y mm> <heading deg>`` line per transducer;
- the bumpers: ``NumFrontBumpers`` / ``NumRearBumpers`` segments, placed as ARIA's
  ``ArBumpers::addBumpToBuffer`` places a hit: bumper ``i`` of ``n`` at angle
  ``-(i + 1/2) 135/n + 135/2`` degrees (the rear ring turned by 180) on the circle of
  ``RobotRadius``; bit ``i + 1`` of the SIP's bumper byte is bumper ``i``.

The sonar cone and range limits are those of the Pioneer's Polaroid-type transducers as ARIA
uses them (``ArSonarDevice``: readings beyond 5 m are ignored). :meth:`PioneerBody.scan` turns
the driver's newest readings into the :class:`~perception.ranges.RangeScan` the collision monitor
reads (``PioneerBase.range_source()``): a reading of 5 m or more is no echo (``inf``), a
transducer not heard for the driver's ``sonar_timeout`` (or never) is no data (``nan``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass

import numpy as np

from perception.polygons import rectangle
from perception.ranges import Bumper, RangeScan, RangeSensor

SONAR_FOV = math.radians(30.0)  # the transducer's cone
SONAR_MAX_RANGE = 5.0  # m: ArSonarDevice's default maximum; farther (or 5000 mm: no echo) is no echo
SONAR_MIN_RANGE = 0.1  # m: nearer objects are not seen (ringing)
BUMPER_ARC_DEG = 135.0  # ArBumpers' default angleRange
RING_SIZE = 8  # transducers per ring: front 0-7 (left to right), rear 8-15 (right to left)


@dataclass(frozen=True, slots=True)
class PioneerBody:
    """One model's footprint (m), sonar ring and bumper segments, in the base frame."""

    model: str
    length_front: float
    length_rear: float
    width: float
    radius: float
    sonar: tuple[tuple[int, int, int], ...]  # (x mm, y mm, heading deg) per transducer, ARIA's numbering
    front_bumpers: int = 5
    rear_bumpers: int = 5

    @property
    def footprint(self) -> np.ndarray:
        """The box of ``RobotLengthFront/Rear`` by ``RobotWidth`` about the centre of rotation."""
        return rectangle(self.length_front, self.length_rear, self.width / 2.0)

    def sensors(self, max_range: float = SONAR_MAX_RANGE) -> tuple[RangeSensor, ...]:
        """The sonar ring as :class:`RangeSensor` (index = ARIA's transducer number)."""
        return tuple(RangeSensor(x / 1000.0, y / 1000.0, math.radians(heading), SONAR_FOV, max_range,
                                 SONAR_MIN_RANGE) for x, y, heading in self.sonar)

    def bumpers(self, radius: float | None = None) -> tuple[Bumper, ...]:
        """Front bumpers, then rear bumpers, where ARIA places their hits, on the circle of
        ``RobotRadius`` (or of ``radius``: the simulator's collision disc)."""
        radius = self.radius if radius is None else radius
        out = []
        for count, facing in ((self.front_bumpers, 1), (self.rear_bumpers, -1)):
            for i in range(count):
                degrees = -((i + 0.5) * BUMPER_ARC_DEG / count - BUMPER_ARC_DEG / 2.0) + (0.0 if facing > 0 else 180.0)
                angle = math.radians(degrees)
                out.append(Bumper(radius * math.cos(angle), radius * math.sin(angle), facing))
        return tuple(out)

    def scan(self, sonar: Mapping[int, float], silent: Collection[int], front_bits: int, rear_bits: int,
             stamp: float, *, with_sonar: bool = True, fired: Mapping[int, float] | None = None) -> RangeScan:
        """The ring's readings (m, by transducer number; ``silent``: not heard lately) and the SIP's
        bumper bits (bit ``i``: bumper ``i``) as one scan; without sonar, the bumpers alone. ``fired``:
        when each transducer's reading came (the stamp of the SIP that reported it; default ``stamp``)."""
        sensors = self.sensors() if with_sonar else ()
        ranges = np.full(len(sensors), np.nan)
        when, fired = np.full(len(sensors), stamp), fired or {}
        for index, metres in sonar.items():
            if index < len(sensors) and index not in silent:
                ranges[index] = np.inf if metres >= SONAR_MAX_RANGE else metres
                when[index] = fired.get(index, stamp)
        pressed = [bool(front_bits >> i & 1) for i in range(self.front_bumpers)]
        pressed += [bool(rear_bits >> i & 1) for i in range(self.rear_bumpers)]
        return RangeScan(sensors, ranges, stamp, self.bumpers(), np.array(pressed, dtype=bool), fired=when)


class PioneerRanges:
    """The :class:`~drivers.interfaces.RangeSource` of a Pioneer base: its newest scan, read from the
    base's I/O thread's latest SIP (closing it releases nothing: the base owns the port)."""

    def __init__(self, scan: Callable[[], RangeScan | None], description: str) -> None:
        self._scan = scan
        self._description = description

    def read(self) -> RangeScan | None:
        return self._scan()

    def close(self) -> None:
        pass

    def describe(self) -> str:
        return self._description


_P3DX_SONAR = ((69, 136, 90), (114, 119, 50), (148, 78, 30), (166, 27, 10), (166, -27, -10), (148, -78, -30),
               (114, -119, -50), (69, -136, -90), (-157, -136, -90), (-203, -119, -130), (-237, -78, -150),
               (-255, -27, -170), (-255, 27, 170), (-237, 78, 150), (-203, 119, 130), (-157, 136, 90))
_P3AT_SONAR = ((147, 136, 90), (193, 119, 50), (227, 79, 30), (245, 27, 10), (245, -27, -10), (227, -79, -30),
               (193, -119, -50), (147, -136, -90), (-144, -136, -90), (-189, -119, -130), (-223, -79, -150),
               (-241, -27, -170), (-241, 27, 170), (-223, 79, 150), (-189, 119, 130), (-144, 136, 90))

BODIES: dict[str, PioneerBody] = {
    "p3dx": PioneerBody("p3dx", 0.210, 0.301, 0.425, 0.250, _P3DX_SONAR),
    "p3dx-sh": PioneerBody("p3dx-sh", 0.210, 0.301, 0.425, 0.250, _P3DX_SONAR),
    "p3at": PioneerBody("p3at", 0.313, 0.313, 0.505, 0.500, _P3AT_SONAR),
    "p3at-sh": PioneerBody("p3at-sh", 0.313, 0.313, 0.505, 0.500, _P3AT_SONAR),
}
"""ARIA's ``params/p3dx.p``, ``p3dx-sh.p``, ``p3at.p``, ``p3at-sh.p`` (AriaCoda): Robot* lines and
SonarUnit lines; NumFrontBumpers/NumRearBumpers 5 in each."""
