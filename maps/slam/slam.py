"""The stereo SLAM, frame after frame: :class:`StereoSlam`.

Per tick, :meth:`StereoSlam.predict` moves the pose by the odometry increment (the prediction of
:class:`maps.exploration.pose.PoseFilter`, with its odometry noise), its turn calibrated against the
cameras (:mod:`maps.slam.odometry`). Per stereo frame,
:meth:`StereoSlam.observe`:

1. predicts every landmark's observation at the predicted pose and the frame's head angles, and
   associates the frame's features with them (:mod:`maps.slam.association`: gate, descriptor);
2. updates the pose with the associated observations (:mod:`maps.slam.tracking`); observations
   that still disagree after the update (chi-square beyond ``outlier_chi2``) are left out of what
   follows;
3. counts each landmark predicted in view and found, takes the found ones' descriptors, and fuses
   their new triangulation into their position (:meth:`maps.slam.landmarks.LandmarkMap.fuse`);
4. when the view is not well covered by the map (:func:`maps.slam.keyframes.wants_keyframe`),
   takes a keyframe: the features not associated and nearer than ``map_depth`` become landmarks
   anchored to it; edges join it to the previous keyframe and to the keyframes whose landmarks it
   found; it is compared with the older keyframes that could see the same place
   (:func:`maps.slam.loop.find_loop`: by descriptor alone, and guided by the motion the pose graph
   predicts between the two with the pose's uncertainty in the odometry frame), and a verified
   loop closes: the pose graph
   (:mod:`maps.slam.graph`) is solved, keyframes, their landmarks and the current pose move with
   it, and the landmarks that now duplicate older ones are merged.

The frame is the odometry frame: the filter starts at the first odometry pose, certain of it.
A map that is being built: this class is mutable.

**Uncertainty.** The filter's covariance is the pose's uncertainty *relative to the landmarks it
was tracked against* (what the gate and the update need). Those landmarks were placed from earlier,
uncertain poses; what a user needs is the uncertainty in the odometry frame. So every keyframe
keeps its pose's covariance in that frame (the relative one plus that of the landmarks' anchor
keyframes, weighted by how many of their landmarks were found), and :attr:`StereoSlam.covariance`
is the filter's plus that of the keyframes the current frame was tracked against: it grows while
the robot maps new places and falls back when it finds old ones (a closed loop: the old keyframe's
plus the loop's own).
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field, replace

import numpy as np

from maps.exploration.head import StereoHead
from maps.exploration.pose import FilterParams, OdometryNoise, PoseFilter
from maps.slam.association import CHI2_3DOF_99, associate, predict
from maps.slam.graph import Edge, compose, optimise, relative, whitener
from maps.slam.keyframes import Keyframe, KeyframePolicy, view_overlap, wants_keyframe
from maps.slam.landmarks import LandmarkMap
from maps.slam.loop import LoopClosure, find_loop
from maps.slam.odometry import TurnCalibration, calibrated
from maps.slam.tracking import refine_pose
from maps.slam.viewpoint import Viewpoint
from perception.camera import StereoRig
from perception.geometry import Pose2D, rot_z
from perception.stereo import StereoPoints
from perception.stereo_geometry import triangulate


@dataclass(frozen=True, slots=True)
class SlamParams:
    """Parameters of :class:`StereoSlam` (the module docstring says where each acts)."""

    sigma_px: float = 0.7  # pixel noise of an observation (u, v, u_r)
    depth: tuple[float, float] = (0.3, 10.0)  # m: landmarks predicted in view between these depths
    map_depth: float = 5.0  # m: nearer features become landmarks (farther: depth too uncertain)
    max_distance: float = 64.0  # descriptor distance of an association (bits of ORB's 256)
    ratio: float = 0.9  # best vs second best descriptor among a landmark's gated candidates
    huber: float = 2.0  # Huber's k (standard deviations) in the pose update
    outlier_chi2: float = 2.0 * CHI2_3DOF_99  # after the update: beyond, an observation is not used further
    min_update: int = 5  # fewer associated landmarks: no pose update (odometry alone)
    floor: float = 0.02**2  # m^2: a landmark's variance stays above this on each axis
    cull_visible: int = 6  # landmarks predicted in view this often...
    cull_ratio: float = 0.25  # ...and found in fewer than this fraction of them are dropped
    keyframes: KeyframePolicy = KeyframePolicy()
    loop_window: int = 15  # the last keyframes are not loop candidates (tracking links them)
    loop_radius: float = 3.0  # m: candidates within this (plus 3 sigma of the pose) of the pose...
    loop_turn: float = math.radians(60.0)  # ...looking within this of the current view direction
    loop_candidates: int = 6  # the closest this many are compared
    loop_min_inliers: int = 25
    covisible_min: int = 15  # landmarks shared with an older keyframe to join the two by an edge
    calibration_gap: float = 0.5  # s: two corrections at most this far apart calibrate odometry's turns
    edge_sigma: tuple[float, float, float] = (0.01, 0.03, math.radians(0.3))  # consecutive keyframes:
    # m + per m driven (x, y), rad + per rad turned (theta) -- also per m driven, times 0.5 deg
    odometry: OdometryNoise = OdometryNoise()


@dataclass(frozen=True, slots=True)
class FrameOutcome:
    """What one frame did: features, landmarks predicted in view, associated, used (inliers), whether
    it became a keyframe and whether a loop closed."""

    features: int
    predicted: int
    associated: int
    used: int
    keyframe: bool
    loop: LoopClosure | None


@dataclass
class StereoSlam:
    """The pose and the map of the stereo SLAM (see the module docstring)."""

    filter: PoseFilter
    head: StereoHead
    params: SlamParams = SlamParams()
    seed: int = 0
    landmarks: LandmarkMap = field(default_factory=LandmarkMap)
    keyframes: list[Keyframe] = field(default_factory=list)
    graph: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # keyframe poses, as solved
    edges: list[Edge] = field(default_factory=list)
    loops: list[LoopClosure] = field(default_factory=list)
    anchor: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # the tracked-against map's covariance
    turns: TurnCalibration = TurnCalibration()
    odometry: Pose2D | None = None  # the last raw odometry pose
    frames: int = 0
    found: int = 0  # landmarks found (used in updates), summed over the frames
    culled: int = 0
    merged: int = 0

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng(self.seed)
        self._calibrated = self.filter.last_odometry  # odometry with its turns calibrated
        self.odometry = self.filter.last_odometry
        self._last_fix: tuple[float, float, float] | None = None  # raw heading, estimate, stamp

    @classmethod
    def start(cls, odometry: Pose2D, head: StereoHead, params: SlamParams = SlamParams(), seed: int = 0) -> StereoSlam:
        """A SLAM at the first odometry pose, certain of it (its frame is the odometry frame)."""
        return cls(PoseFilter.start(odometry, FilterParams(odometry=params.odometry)), head, params, seed)

    @property
    def pose(self) -> Pose2D:
        return self.filter.pose

    @property
    def covariance(self) -> np.ndarray:
        """The pose's (x, y, theta) covariance in the odometry frame (see the module docstring)."""
        return self.tracking_covariance + self.anchor

    @property
    def tracking_covariance(self) -> np.ndarray:
        """The pose's covariance relative to the landmarks it is tracked against (the filter's)."""
        return self.filter.covariance[:3, :3]

    def predict(self, odometry: Pose2D) -> None:
        """Move by the odometry increment since the last call, its turn calibrated."""
        if self.odometry is None or self._calibrated is None:
            self.odometry = self._calibrated = odometry
        self._calibrated = calibrated(self._calibrated, self.odometry, odometry, self.turns.scale)
        self.odometry = odometry
        self.filter = self.filter.predict(self._calibrated)

    # -- a frame ---------------------------------------------------------------------------------
    def observe(self, stereo: StereoPoints, rig: StereoRig, pan: float, tilt: float, stamp: float) -> FrameOutcome:
        """One stereo frame's features (:func:`perception.stereo.sparse_stereo` with descriptors) taken
        with the head at (pan, tilt) rad: steps 1-4 of the module docstring."""
        p = self.params
        self.frames += 1
        view = Viewpoint.of(self.head, pan, tilt)
        observed = np.column_stack((stereo.uv_left, stereo.uv_left[:, 0] - stereo.disparity))
        descriptors = stereo.descriptors if stereo.descriptors is not None else np.zeros((len(stereo), 32), np.uint8)
        mean, cov = self.filter.mean[:3].copy(), self.tracking_covariance.copy()
        prediction = predict(self.landmarks, mean, cov, view, rig, sigma_px=p.sigma_px, depth=p.depth)
        pairs = associate(prediction, self.landmarks.descriptors[prediction.rows], observed, descriptors,
                          max_distance=p.max_distance, ratio=p.ratio)
        rows, features = prediction.rows[pairs.landmark], pairs.feature
        used = np.zeros(len(rows), dtype=bool)
        last_fix, self._last_fix = self._last_fix, None  # set again by a correction
        if len(rows) >= p.min_update:
            update = refine_pose(mean, cov, self.landmarks.positions[rows], self.landmarks.covariances[rows],
                                 observed[features], view, rig, sigma_px=p.sigma_px, huber=p.huber)
            used = update.chi2 <= p.outlier_chi2
            if used.sum() >= p.min_update:
                mean, cov = update.mean, update.covariance
                self._set_pose(mean, cov)
                self._calibrate(last_fix, float(mean[2]), stamp)
            else:
                used[:] = False
        self.landmarks.visible[prediction.rows] += 1
        rows, features = rows[used], features[used]
        self.landmarks.found[rows] += 1
        self.found += len(rows)
        if len(rows):
            self.anchor = self._anchor_covariance(self.landmarks.anchors[rows], mean)
        self.landmarks.descriptors[rows] = descriptors[features]
        points, point_cov = self._world_points(stereo.points[features], observed[features], rig, view, mean, cov)
        self.landmarks.fuse(rows, points, point_cov, p.floor)
        usable = int(np.count_nonzero(stereo.depth <= p.map_depth))
        since = stamp - self.keyframes[-1].stamp if self.keyframes else math.inf
        loop = None
        keyframe = wants_keyframe(len(rows), usable, since, p.keyframes)
        if keyframe:
            loop = self._keyframe(stereo, observed, descriptors, rows, features, rig, view, (pan, tilt), stamp)
        return FrameOutcome(len(stereo), len(prediction), len(pairs), len(rows), keyframe, loop)

    def _calibrate(self, last: tuple[float, float, float] | None, heading: float, stamp: float) -> None:
        """Pair this correction's heading change with odometry's since the ``last`` one (when recent)."""
        raw = self.odometry.theta if self.odometry is not None else 0.0
        self._last_fix = (raw, heading, stamp)
        if last is not None and stamp - last[2] <= self.params.calibration_gap:
            self.turns = self.turns.add(math.remainder(raw - last[0], 2 * math.pi),
                                        math.remainder(heading - last[1], 2 * math.pi))

    def _anchor_covariance(self, anchors: np.ndarray, mean: np.ndarray) -> np.ndarray:
        """The covariance the anchor keyframes of the found landmarks pass on to a pose at ``mean``
        (each keyframe's, compounded to the pose: its heading's uncertainty times the distance
        becomes position uncertainty), weighted by how many of the landmarks each anchors."""
        keys, counts = np.unique(anchors, return_counts=True)
        offset = mean[:2] - self.graph[keys, :2]  # from each keyframe to the pose
        jac = np.broadcast_to(np.eye(3), (len(keys), 3, 3)).copy()  # d(K_k (+) rel) / d(K_k)
        jac[:, 0, 2], jac[:, 1, 2] = -offset[:, 1], offset[:, 0]
        stacked = np.array([self.keyframes[int(k)].covariance for k in keys])
        return np.einsum("k,kij->ij", counts / counts.sum(), jac @ stacked @ np.swapaxes(jac, 1, 2))

    def _set_pose(self, mean: np.ndarray, cov: np.ndarray) -> None:
        full = self.filter.mean.copy()
        full[:3] = mean
        self.filter = replace(self.filter, mean=full, covariance=cov)

    def _world_points(self, camera: np.ndarray, observed: np.ndarray, rig: StereoRig, view: Viewpoint,
                      mean: np.ndarray, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Triangulations in the world with covariances (the stereo's and the pose's, to first order)."""
        if len(camera) == 0:
            return np.zeros((0, 3)), np.zeros((0, 3, 3))
        points, tri_cov = triangulate(rig, observed, self.params.sigma_px)
        world, d_pose, d_camera = view.to_world(mean, points)
        covariance = d_camera @ tri_cov @ np.swapaxes(d_camera, 1, 2) + d_pose @ cov @ np.swapaxes(d_pose, 1, 2)
        return world, covariance

    # -- keyframes and loops ---------------------------------------------------------------------
    def _keyframe(self, stereo: StereoPoints, observed: np.ndarray, descriptors: np.ndarray, rows: np.ndarray,
                  features: np.ndarray, rig: StereoRig, view: Viewpoint, head: tuple[float, float],
                  stamp: float) -> LoopClosure | None:
        p = self.params
        index = len(self.keyframes)
        mean, cov = self.filter.mean[:3].copy(), self.tracking_covariance.copy()
        ids = np.full(len(stereo), -1, dtype=np.int64)
        ids[features] = self.landmarks.ids[rows]
        fresh = np.flatnonzero((ids < 0) & (stereo.depth <= p.map_depth) & (stereo.depth > 0))
        points, point_cov = self._world_points(stereo.points[fresh], observed[fresh], rig, view, mean, cov)
        ids[fresh] = self.landmarks.add(points, point_cov, descriptors[fresh], index)
        tri, tri_cov = triangulate(rig, observed, p.sigma_px)
        frame = Keyframe(index, stamp, mean, cov + self.anchor, head[0], head[1], view.base_points(tri),
                         view.rotation @ tri_cov @ view.rotation.T, descriptors.copy(), ids)
        shared = Counter(int(a) for a in self.landmarks.anchors[rows])
        self.keyframes.append(frame)
        self.graph = np.vstack((self.graph, mean))
        self._link(index, shared)
        self.culled += self.landmarks.cull(p.cull_visible, p.cull_ratio)
        loop = self._close_loop(frame, set(shared), cov + self.anchor)
        return loop

    def _link(self, index: int, shared: Counter[int]) -> None:
        """Edges from the previous keyframe (tracked motion) and from those whose landmarks were found."""
        if index == 0:
            return
        p = self.params
        step = relative(self.graph[index - 1], self.graph[index])[0]
        dist, turn = math.hypot(step[0], step[1]), abs(float(step[2]))
        s_xy = p.edge_sigma[0] + p.edge_sigma[1] * dist
        s_theta = p.edge_sigma[2] + 0.02 * turn + math.radians(0.5) * dist
        self.edges.append(Edge(index - 1, index, step, whitener(np.diag([s_xy**2, s_xy**2, s_theta**2]))))
        for anchor, count in shared.items():
            if anchor >= index - 1 or count < p.covisible_min:
                continue
            scale = math.sqrt(p.covisible_min / count)
            covariance = np.diag([(0.02 * scale) ** 2, (0.02 * scale) ** 2, (math.radians(0.3) * scale) ** 2])
            measured = relative(self.graph[anchor], self.graph[index])[0]
            self.edges.append(Edge(anchor, index, measured, whitener(covariance)))

    def _close_loop(self, frame: Keyframe, covisible: set[int], cov: np.ndarray) -> LoopClosure | None:
        p = self.params
        reach = p.loop_radius + 3.0 * math.sqrt(max(float(np.linalg.eigvalsh(cov[:2, :2])[-1]), 0.0))
        candidates = []
        for old in self.keyframes[: max(0, frame.index - p.loop_window)]:
            if old.index in covisible:
                continue
            moved = replace(old, pose=self.graph[old.index])
            if view_overlap(frame, moved, max_distance=reach, max_turn=p.loop_turn):
                candidates.append(old)
        candidates.sort(key=lambda k: float(np.hypot(*(self.graph[k.index, :2] - frame.pose[:2]))))
        candidates = candidates[: p.loop_candidates]
        predicted = [(relative(self.graph[old.index], frame.pose)[0], cov + old.covariance) for old in candidates]
        loop = find_loop(frame, candidates, "orb", rng=self._rng, min_inliers=p.loop_min_inliers,
                         predicted=predicted)
        if loop is None:
            return None
        self.loops.append(loop)
        self.edges.append(Edge(loop.old, loop.new, loop.match.motion, whitener(loop.match.covariance)))
        self._solve()
        self._last_fix = None  # the pose jumped: no heading change to compare
        self.anchor = self.keyframes[loop.old].covariance + loop.match.covariance
        self.keyframes[-1] = replace(frame, covariance=self.anchor)
        return loop

    def _solve(self) -> None:
        """Solve the pose graph; move keyframes, their landmarks and the current pose with it."""
        before = self.graph.copy()
        after = optimise(before, self.edges)
        corrections = {}
        for k in range(len(after)):
            turn = rot_z(float(after[k, 2] - before[k, 2]))
            shift = np.array([after[k, 0], after[k, 1], 0.0]) - turn @ np.array([before[k, 0], before[k, 1], 0.0])
            corrections[k] = (turn, shift)
        self.landmarks.move(corrections)
        last = len(after) - 1
        mean = compose(after[last], relative(before[last], self.filter.mean[:3])[0])
        self._set_pose(mean, self.tracking_covariance)
        self.graph = after
        self.merged += self.landmarks.merge_duplicates(0.1, self.params.max_distance / 2.0, self.params.floor)
