"""Differential-drive kinematics of a Pioneer 3-DX class base, with slip and drifting odometry."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import Pose2D, wrap_angle


@dataclass(frozen=True, slots=True)
class DiffDriveLimits:
    """Velocity and acceleration limits (Pioneer 3-DX defaults from ARIA's parameter file)."""

    max_v: float = 1.2  # m/s
    max_w: float = math.radians(300.0)  # rad/s
    accel_v: float = 0.3  # m/s^2 (ARIA TransAccel 300 mm/s^2)
    decel_v: float = 0.3  # m/s^2
    accel_w: float = math.radians(100.0)  # rad/s^2 (ARIA RotAccel 100 deg/s^2)
    wheel_base: float = 0.33  # m, P3-DX axle length


@dataclass(frozen=True, slots=True)
class SlipModel:
    """How the real motion differs from what the encoders count.

    ``slip_sigma`` is the per-step relative noise on each wheel's travel; ``scale_error`` and
    ``base_error`` are the systematic odometry errors (wheel radius, axle length) that make
    odometry drift like a real one.
    """

    slip_sigma: float = 0.02
    scale_error: float = 0.01
    base_error: float = 0.02


class DiffDrive:
    """Integrates a commanded (v, w) into a true pose and an odometry pose.

    The commanded velocity is slewed to the acceleration limits and clipped to the velocity
    limits; the true motion adds wheel slip; odometry integrates what ideal encoders of a
    slightly mis-calibrated robot would count.
    """

    def __init__(
        self,
        *,
        start: Pose2D | None = None,
        limits: DiffDriveLimits | None = None,
        slip: SlipModel | None = None,
        rng: np.random.Generator,
    ) -> None:
        self.limits = limits or DiffDriveLimits()
        self.slip = slip or SlipModel()
        self.rng = rng
        start = start or Pose2D()
        self.true_pose = np.array([start.x, start.y, start.theta], dtype=float)
        self.odom_pose = np.zeros(3)
        self.target = (0.0, 0.0)
        self.velocity = (0.0, 0.0)  # actual (v, w) after the acceleration limits

    def command(self, v: float, w: float) -> None:
        """Set the velocity target, clipped to the limits."""
        lim = self.limits
        self.target = (
            float(np.clip(v, -lim.max_v, lim.max_v)),
            float(np.clip(w, -lim.max_w, lim.max_w)),
        )

    def step(self, dt: float, *, blocked: bool = False) -> None:
        """Advance by ``dt`` seconds; ``blocked`` (a collision) forces the wheels to rest."""
        lim = self.limits
        v, w = self.velocity
        tv, tw = (0.0, 0.0) if blocked else self.target
        dv_max = (lim.accel_v if abs(tv) > abs(v) else lim.decel_v) * dt
        v += float(np.clip(tv - v, -dv_max, dv_max))
        w += float(np.clip(tw - w, -lim.accel_w * dt, lim.accel_w * dt))
        if blocked:
            v, w = 0.0, 0.0
        self.velocity = (v, w)
        # wheel travel this step, as commanded to the motor controllers
        half = lim.wheel_base / 2.0
        left, right = (v - w * half) * dt, (v + w * half) * dt
        # true motion: each wheel slips a little
        s = self.slip
        if s.slip_sigma > 0.0 and (left or right):
            noise = self.rng.normal(0.0, s.slip_sigma, size=2)
            true_left, true_right = left * (1 + noise[0]), right * (1 + noise[1])
        else:
            true_left, true_right = left, right
        self.true_pose = _integrate(self.true_pose, true_left, true_right, lim.wheel_base)
        # odometry: what encoders of a mis-calibrated robot believe
        odo_scale = 1.0 + s.scale_error
        odo_base = lim.wheel_base * (1.0 + s.base_error)
        self.odom_pose = _integrate(self.odom_pose, left * odo_scale, right * odo_scale, odo_base)

    def true(self, stamp: float) -> Pose2D:
        x, y, th = self.true_pose
        return Pose2D(float(x), float(y), float(th), stamp)

    def odometry(self, stamp: float) -> Pose2D:
        x, y, th = self.odom_pose
        return Pose2D(float(x), float(y), float(th), stamp)


def _integrate(pose: np.ndarray, left: float, right: float, wheel_base: float) -> np.ndarray:
    """Exact arc integration of one step of wheel travel."""
    ds = (left + right) / 2.0
    dth = (right - left) / wheel_base
    x, y, th = pose
    if abs(dth) < 1e-9:
        x += ds * math.cos(th)
        y += ds * math.sin(th)
    else:
        r = ds / dth
        x += r * (math.sin(th + dth) - math.sin(th))
        y -= r * (math.cos(th + dth) - math.cos(th))
    return np.array([x, y, wrap_angle(th + dth)])
