"""The ``safety:`` section of a robot profile: the collision monitor's footprint, zones and limits.

Every setting has a default, so a profile needs no ``safety:`` section at all. The polygons
default to the robot's own footprint grown by a margin: on a Pioneer the box ARIA's parameter
file gives for the model the robot reports (:mod:`drivers.pioneer_body`), in the simulator the
world's robot disc. docs/hardware.md lists the settings; the algorithm that uses them is
:mod:`perception.collision_monitor`.
"""

from __future__ import annotations

import math
from typing import Annotated

import numpy as np
from pydantic import BaseModel, Field, field_validator

from drivers.common import quantity
from maps.located import FILE_MODEL_CONFIG
from perception.collision_monitor import MonitorConfig, Zone
from perception.polygons import as_polygon, contains, grow, is_convex

Point = Annotated[list[float], Field(min_length=2, max_length=2, description="[x, y] in the base frame, m")]
Polygon = Annotated[list[Point], Field(min_length=3, max_length=64)]


class SafetySettings(BaseModel):
    """The collision monitor of one robot (profile section ``safety:``)."""

    model_config = FILE_MODEL_CONFIG

    footprint: Polygon | None = Field(
        None, description="the robot's outline, a convex polygon [[x, y], ...] in the base frame (x forward, "
        "y left) [m]; default: the robot's own (Pioneer: ARIA's RobotLengthFront/Rear by RobotWidth for the "
        "model the robot reports; simulator: the world's robot disc)")
    stop_zone: Polygon | None = Field(
        None, description="a point inside it on the command's path stops the command; a polygon around the "
        "footprint [m]; default: the footprint grown by stop_margin")
    stop_margin: float = quantity(0.10, "default stop zone: the footprint grown by this much", "m", ge=0.0, le=2.0)
    slowdown_zone: Polygon | None = Field(
        None, description="a point inside it on the command's path scales the command by slowdown_ratio; a "
        "polygon around the footprint [m]; default: the footprint grown by slowdown_margin")
    slowdown_margin: float = quantity(0.35, "default slow-down zone: the footprint grown by this much", "m",
                                      ge=0.0, le=3.0)
    slowdown_ratio: float = quantity(0.5, "the share of the speed kept in the slow-down zone", "1", ge=0.0, le=1.0)
    time_before_collision: float = quantity(
        1.0, "approach: the command is scaled so the footprint would touch the nearest point on its arc no sooner "
        "than this; 0 turns approach off", "s", ge=0.0, le=10.0)
    source_timeout: float = quantity(1.0, "a range scan older than this is no data (the monitor crawls)", "s",
                                     ge=0.05, le=10.0)
    crawl_speed: float = quantity(0.1, "speed limit while there is no range data", "m/s", ge=0.0, le=0.5)
    crawl_turn_rate: float = quantity(20.0, "turn rate limit while there is no range data", "deg/s", ge=0.0, le=90.0)
    memory: float = quantity(1.0, "echoes this recent, in the sonar ring's blind gaps now, are judged with the "
                             "newest scan where odometry put them; 0: the newest scan alone", "s",
                             ge=0.0, le=10.0)
    closing: bool = Field(True, description="a transducer's successive readings say how fast what it hears closes "
                          "on the robot by itself (a walker); such an echo is judged where it is now, and the approach "
                          "action allows for its speed (perception.closing); false: every echo stands still")

    @field_validator("footprint", "stop_zone", "slowdown_zone")
    @classmethod
    def _polygon(cls, vertices: list[list[float]] | None) -> list[list[float]] | None:
        if vertices is None:
            return None
        poly = as_polygon(vertices)  # ValueError: the located message
        if not contains(poly, np.zeros((1, 2)))[0]:
            raise ValueError("the polygon must contain the robot's centre (0, 0)")
        return vertices

    @field_validator("footprint")
    @classmethod
    def _convex(cls, vertices: list[list[float]] | None) -> list[list[float]] | None:
        if vertices is not None and not is_convex(as_polygon(vertices)):
            raise ValueError("the footprint must be a convex polygon")
        return vertices


def monitor_config(settings: SafetySettings | None, footprint: np.ndarray) -> MonitorConfig:
    """The monitor's configuration: ``settings`` (None: every default) over the robot's own
    ``footprint``; ValueError when a zone does not contain the footprint."""
    settings = settings or SafetySettings()
    body = as_polygon(settings.footprint) if settings.footprint is not None else as_polygon(footprint)
    zones = []
    for name, given, margin, action, ratio in (
            ("stop", settings.stop_zone, settings.stop_margin, "stop", 0.0),
            ("slowdown", settings.slowdown_zone, settings.slowdown_margin, "slowdown", settings.slowdown_ratio)):
        polygon = as_polygon(given) if given is not None else grow(body, margin)
        if given is not None and not contains(polygon, body * (1.0 - 1e-9)).all():
            raise ValueError(f"safety: the {name}_zone must contain the whole footprint")
        zones.append(Zone(name, polygon, action, ratio))  # type: ignore[arg-type]
    return MonitorConfig(body, tuple(zones), settings.time_before_collision, settings.source_timeout,
                         settings.crawl_speed, math.radians(settings.crawl_turn_rate), memory=settings.memory,
                         closing=settings.closing)
