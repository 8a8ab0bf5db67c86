"""The simulated pan-tilt unit: PTU-D46 limits and slew rate, stepped by the simulation clock."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from drivers.interfaces import PanTiltLimits, PanTiltState
from drivers.sim.world_values import PtuSpec


class SimPanTilt:
    """A :class:`~drivers.interfaces.PanTilt` that slews each axis at a bounded constant speed.

    Targets outside the limits are clipped to them (the real unit refuses them with an error; a
    mission asking for 170 degrees gets 159). The requested speed is clipped to ``max_speed``;
    both axes move at that speed until they reach their targets. Acceleration is not modelled (the
    PTU-D46 ramps in a few milliseconds, well under one control tick).
    """

    def __init__(self, spec: PtuSpec, clock: Callable[[], float]) -> None:
        self.spec = spec
        self._clock = clock
        self.pan = 0.0
        self.tilt = 0.0
        self._target = (0.0, 0.0)
        self._speed = spec.max_speed
        self.commands: list[tuple[float, float, float, float]] = []  # (time, pan, tilt, speed)

    def move(self, pan: float, tilt: float, speed: float) -> None:
        """Start slewing to (pan, tilt) rad at ``speed`` rad/s; returns at once."""
        if not all(math.isfinite(v) for v in (pan, tilt, speed)):
            raise ValueError(f"pan-tilt command must be finite, got pan={pan}, tilt={tilt}, speed={speed}")
        s = self.spec
        self._target = (float(np.clip(pan, *s.pan_limits)), float(np.clip(tilt, *s.tilt_limits)))
        self._speed = float(np.clip(abs(speed), 1e-6, s.max_speed))
        self.commands.append((self._clock(), float(pan), float(tilt), float(speed)))

    def halt(self) -> None:
        """Stop where it is now."""
        self._target = (self.pan, self.tilt)

    def state(self) -> PanTiltState:
        return PanTiltState(self.pan, self.tilt, self.moving, self._clock(), self.limits)

    @property
    def limits(self) -> PanTiltLimits:
        """What the simulated unit reports: the world's limits and top speed, continuous positions."""
        s = self.spec
        return PanTiltLimits(s.pan_limits, s.tilt_limits, max_speed=s.max_speed)

    @property
    def moving(self) -> bool:
        return (self.pan, self.tilt) != self._target

    def step(self, dt: float) -> None:
        """Advance the motion by ``dt`` seconds."""
        reach = self._speed * dt
        self.pan = _approach(self.pan, self._target[0], reach)
        self.tilt = _approach(self.tilt, self._target[1], reach)

    def close(self) -> None:
        self.halt()


def _approach(value: float, target: float, reach: float) -> float:
    delta = target - value
    return target if abs(delta) <= reach else value + math.copysign(reach, delta)
