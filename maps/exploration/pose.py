"""The pose an exploration map is built in: odometry corrected by landmark bearings (a small EKF-SLAM).

Why: the simulator's (and a real Pioneer's) odometry drifts in heading: wheel slip (a random walk,
about a degree per metre here) and a mis-calibrated axle (2 % of every turn). A map integrated at
odometry poses smears walls by the heading error times their distance, and a 0.9 m door smeared
by a few degrees looks impassable. Exploration turns a lot (surveys, turns towards every goal), so
the heading error grows with time as much as with distance: in a simulated wander it reached 25
degrees within 50 s. It has to be corrected from what the robot sees.

What: an extended Kalman filter over the robot's pose (x, y, theta) and the landmarks it identifies
with a bearings sensor (the simulator's ideal ``landmarks`` camera, or any source of identified
bearings: ids and unit vectors in the sensor frame). Odometry increments predict (eq. of a
differential drive); the azimuth of every identified landmark corrects. The landmarks are not
known in advance: the filter maps them as it goes (bearing-only SLAM), so its frame stays the one
odometry started in and walls seen again line up.

Choices:

- **Why not Z-infinity** (bearings' rotation between two landmark sets): it takes the rotation from
  *far*, translation-invariant landmarks. In rooms every landmark is a few metres away, and
  chaining keyframe-to-keyframe rotations accumulates their error; the filter uses the same
  bearings without either limitation.
- **Frame**: the filter starts at the first odometry pose with zero uncertainty: its frame is the
  odometry frame, and a corrected pose is directly comparable with odometry.
- **Prediction** (:meth:`PoseFilter.predict`): the odometry increment in the robot frame, with noise
  growing with distance and turn (:class:`OdometryNoise`; the calibration errors are systematic,
  modelled as generous proportional noise).
- **Landmarks in inverse depth** (Civera, Davison, Montiel 2008, in the plane): a landmark is the
  sensor position it was first seen from ``(x0, y0)``, the world azimuth ``alpha`` of that ray and
  the inverse distance ``rho`` along it, started at ``rho0 +- sigma_rho`` (from ~1.3 m to
  infinity). A landmark at unknown distance constrains the heading at once: while the robot only
  turns (a survey, a turn on the spot) its azimuth is pure rotation, whatever ``rho``; the
  distance firms up as the robot moves. (A delayed, triangulated start in x, y lets the heading
  error of the first turn into the map for good: tried, a bias of 1-1.5 degrees.)
- **Measurement**: the azimuth ``atan2(b_y, b_x)`` of each bearing, noise ``sigma / cos(elevation)``
  (a landmark near the zenith has an ill-defined azimuth). Innovations beyond ``gate`` standard
  deviations are ignored (a wrong id, an occlusion edge); ``rho`` is kept positive.
- Without landmarks (a world with none, a sensor that sees nothing) the filter is plain odometry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from perception.geometry import Pose2D, wrap_angle, wrap_angles

Mount = tuple[float, float, float]  # the bearings sensor on the base: x, y (m), yaw (rad)


@dataclass(frozen=True, slots=True)
class OdometryNoise:
    """How uncertain an odometry increment is (variances add up tick by tick)."""

    trans_rel: float = 0.02  # of the distance driven (scale error, slip)
    trans_per_m: float = 1e-4  # m^2 of variance per metre (slip: a random walk)
    rot_rel: float = 0.03  # of the angle turned (axle calibration)
    rot_per_m: float = 4e-4  # rad^2 of variance per metre driven (slip: ~1.1 deg per sqrt(m))
    rot_per_rad: float = 4e-4  # rad^2 of variance per radian turned (slip in turns)


@dataclass(frozen=True, slots=True)
class FilterParams:
    """Parameters of :class:`PoseFilter`."""

    bearing_sigma: float = math.radians(1.0)  # azimuth noise of a landmark on the horizon (rad)
    gate: float = 3.0  # innovations beyond this many standard deviations are ignored
    rho0: float = 0.3  # 1/m: a new landmark's inverse distance...
    sigma_rho: float = 0.25  # ...and its uncertainty (2 sigma: from 1.25 m to infinity)
    min_rho: float = 1e-3  # inverse distances are kept above this (1 km)
    odometry: OdometryNoise = OdometryNoise()


def _rotation(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


_PERP = np.array([[0.0, -1.0], [1.0, 0.0]])  # d/dtheta of R(theta) v is _PERP @ R(theta) v


@dataclass(frozen=True, slots=True)
class PoseFilter:
    """The filter's state, a value (every step returns a new one).

    ``mean`` = [x, y, theta, then per landmark x0, y0, alpha, rho], ``covariance`` its covariance,
    ``ids`` the landmark ids in state order, ``last_odometry`` the odometry pose of the last
    prediction.
    """

    mean: np.ndarray
    covariance: np.ndarray
    ids: tuple[int, ...] = ()
    last_odometry: Pose2D | None = None
    params: FilterParams = FilterParams()

    @classmethod
    def start(cls, odometry: Pose2D, params: FilterParams = FilterParams()) -> PoseFilter:
        """A filter at the first odometry pose, certain of it (its frame is the odometry frame)."""
        return cls(np.array([odometry.x, odometry.y, odometry.theta]), np.zeros((3, 3)), last_odometry=odometry,
                   params=params)

    @property
    def pose(self) -> Pose2D:
        """The corrected pose (stamped like the last odometry)."""
        stamp = self.last_odometry.stamp if self.last_odometry is not None else 0.0
        return Pose2D(float(self.mean[0]), float(self.mean[1]), wrap_angle(float(self.mean[2])), stamp)

    @property
    def landmarks(self) -> np.ndarray:
        """(L, 2) plan positions of the landmarks in the state (order of ``ids``): ``p0 + m(alpha) / rho``."""
        lm = self.mean[3:].reshape(-1, 4)
        return lm[:, :2] + np.column_stack((np.cos(lm[:, 2]), np.sin(lm[:, 2]))) / lm[:, 3:4]

    @property
    def landmark_range_sigma(self) -> np.ndarray:
        """(L,) how uncertain each landmark's distance from its first sighting is (m): sigma_rho / rho^2."""
        rho = self.mean[6::4]
        var = np.diag(self.covariance)[6::4]
        return np.sqrt(np.maximum(var, 0.0)) / np.maximum(rho, 1e-9) ** 2

    def pose_sigma(self) -> tuple[float, float]:
        """Standard deviations of the position (m, along its worst axis) and of the heading (rad)."""
        worst = float(np.linalg.eigvalsh(self.covariance[:2, :2])[-1])
        return math.sqrt(max(worst, 0.0)), math.sqrt(max(float(self.covariance[2, 2]), 0.0))

    # -- prediction ----------------------------------------------------------------------------------
    def predict(self, odometry: Pose2D) -> PoseFilter:
        """Move by the odometry increment since the last call, its noise from :class:`OdometryNoise`."""
        last = self.last_odometry
        if last is None:
            return replace(self, last_odometry=odometry)
        local = _rotation(-last.theta) @ np.array([odometry.x - last.x, odometry.y - last.y])
        dtheta = wrap_angle(odometry.theta - last.theta)
        dist = float(np.hypot(*local))
        mean = self.mean.copy()
        rot = _rotation(float(mean[2]))
        step = rot @ local
        mean[:2] += step  # x_k = x_{k-1} + R(theta) dp  (differential drive, increments in the robot frame)
        mean[2] = wrap_angle(float(mean[2]) + dtheta)
        n = self.params.odometry
        var_t = (n.trans_rel * dist) ** 2 + n.trans_per_m * dist
        var_r = (n.rot_rel * dtheta) ** 2 + n.rot_per_m * dist + n.rot_per_rad * abs(dtheta)
        f = np.eye(3)
        f[:2, 2] = _PERP @ step  # d(position)/d(theta)
        w = np.zeros((3, 3))
        w[:2, :2] = rot
        w[2, 2] = 1.0
        cov = self.covariance.copy()
        cov[:3, :] = f @ cov[:3, :]
        cov[:, :3] = cov[:, :3] @ f.T
        cov[:3, :3] += w @ np.diag([var_t + 1e-12, var_t + 1e-12, var_r + 1e-12]) @ w.T
        return replace(self, mean=mean, covariance=cov, last_odometry=odometry)

    # -- correction ----------------------------------------------------------------------------------
    def update(self, ids: np.ndarray, bearings: np.ndarray, mount: Mount = (0.0, 0.0, 0.0)) -> PoseFilter:
        """Correct with identified bearings (``ids`` (N,), unit ``bearings`` (N, 3) in the sensor frame;
        ``mount``: the sensor's x, y, yaw on the base); landmarks seen for the first time join the state."""
        ids = np.asarray(ids, dtype=np.int64).ravel()
        b = np.asarray(bearings, dtype=np.float64).reshape(-1, 3)
        if len(ids) == 0:
            return self
        azimuth = wrap_angles(np.arctan2(b[:, 1], b[:, 0]) + mount[2])
        elevation = np.arctan2(b[:, 2], np.hypot(b[:, 0], b[:, 1]))
        sigma = self.params.bearing_sigma / np.maximum(np.cos(elevation), 0.2)
        return self._correct(ids, azimuth, sigma, mount)._add(ids, azimuth, sigma, mount)

    def _correct(self, ids: np.ndarray, azimuth: np.ndarray, sigma: np.ndarray, mount: Mount) -> PoseFilter:
        index = {lid: i for i, lid in enumerate(self.ids)}
        mean, cov = self.mean, self.covariance
        n = len(mean)
        offset = _rotation(float(mean[2])) @ np.array(mount[:2])
        sensor = mean[:2] + offset
        rows, innovations, variances = [], [], []
        for k, lid in enumerate(int(i) for i in ids):
            if lid not in index:
                continue
            j = 3 + 4 * index[lid]
            x0, y0, alpha, rho = mean[j : j + 4]
            m = np.array([math.cos(alpha), math.sin(alpha)])
            d = rho * (np.array([x0, y0]) - sensor) + m  # direction to the landmark, scaled by rho
            q = float(d @ d)
            if q < 1e-12:
                continue
            dh = np.array([-d[1], d[0]]) / q  # d atan2(d_y, d_x) / d d
            h = np.zeros(n)
            h[0:2] = -rho * dh
            h[2] = -rho * float(dh @ (_PERP @ offset)) - 1.0
            h[j : j + 2] = rho * dh
            h[j + 2] = float(dh @ np.array([-m[1], m[0]]))
            h[j + 3] = float(dh @ (np.array([x0, y0]) - sensor))
            rows.append(h)
            innovations.append(wrap_angle(float(azimuth[k]) - (math.atan2(d[1], d[0]) - float(mean[2]))))
            variances.append(float(sigma[k]) ** 2)
        if not rows:
            return self
        hm, nu, r = np.array(rows), np.array(innovations), np.array(variances)
        hp = hm @ cov  # H P
        s_diag = np.einsum("ij,ij->i", hp, hm) + r
        keep = nu**2 <= self.params.gate**2 * s_diag  # a wrong id, an occlusion edge: gated out
        if not keep.any():
            return self
        hm, hp, nu, r = hm[keep], hp[keep], nu[keep], r[keep]
        s_mat = hp @ hm.T + np.diag(r)
        gain = np.linalg.solve(s_mat, hp).T  # K = P H^T S^-1
        mean = mean + gain @ nu
        mean[2] = wrap_angle(float(mean[2]))
        mean[6::4] = np.maximum(mean[6::4], self.params.min_rho)
        cov = cov - gain @ hp  # P - K H P
        return replace(self, mean=mean, covariance=(cov + cov.T) / 2.0)

    def _add(self, ids: np.ndarray, azimuth: np.ndarray, sigma: np.ndarray, mount: Mount) -> PoseFilter:
        known = set(self.ids)
        fresh = [k for k, lid in enumerate(int(i) for i in ids) if lid not in known]
        if not fresh:
            return self
        theta = float(self.mean[2])
        offset = _rotation(theta) @ np.array(mount[:2])
        sensor = self.mean[:2] + offset
        n, p = len(self.mean), self.params
        g = np.zeros((4, 3))  # d(x0, y0, alpha, rho) / d(x, y, theta)
        g[0:2, 0:2] = np.eye(2)
        g[0:2, 2] = _PERP @ offset
        g[2, 2] = 1.0
        mean, cov, new_ids = [self.mean], self.covariance, list(self.ids)
        for k in fresh:
            y = np.array([sensor[0], sensor[1], wrap_angle(theta + float(azimuth[k])), p.rho0])
            p_yx = g @ cov[:3, :]
            p_yy = g @ cov[:3, :3] @ g.T + np.diag([0.0, 0.0, float(sigma[k]) ** 2, p.sigma_rho**2])
            size = len(cov)
            grown = np.zeros((size + 4, size + 4))
            grown[:size, :size] = cov
            grown[size:, :size] = p_yx
            grown[:size, size:] = p_yx.T
            grown[size:, size:] = p_yy
            cov = grown
            mean.append(y)
            new_ids.append(int(ids[k]))
        assert len(cov) == n + 4 * len(fresh)
        return replace(self, mean=np.concatenate(mean), covariance=cov, ids=tuple(new_ids))
