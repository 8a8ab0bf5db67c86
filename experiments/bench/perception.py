"""Perception figures for ``bearings bench perception --json``.

1. Pipeline speed on 720 x 172 panoramas rendered by the simulator (the lab world, poses 2-20 cm
   from a viewframe, turned by up to 86 degrees), or, when the simulator cannot render panoramas,
   on synthetic textured panoramas turned by known angles (``frames_source`` says which); also
   the yaw and direction-of-travel errors of Z-infinity on those frames against ground truth.
   One frame of the pipeline = unwarp a catadioptric donut (made from the panorama once, outside
   the timing) with one ``cv2.remap``, upright ORB with the seam wrap, bearings, matching against
   a viewframe (ratio test + mutual check), Z-infinity. The
   reference is OpenCV's bare ORB ``detectAndCompute`` + ``BFMatcher.knnMatch`` on the same
   frames; ``pipeline_cost_ratio`` = pipeline time / reference time.
2. Z-infinity on synthetic bearings with known motion (far and near landmarks all around, 300
   correspondences, noise, outliers) next to PoseLib's LO-RANSAC relative pose and OpenCV's
   ``findEssentialMat`` + ``recoverPose``. Those two take pinhole image points, so they get the
   correspondences in front of both cameras (``pinhole_correspondences``): Z-infinity gets all.
3. Planar homing (3 degrees of freedom) next to two general 5-point relative-pose estimators,
   PoseLib's ``estimate_relative_pose`` (LO-RANSAC + refinement) and OpenCV's
   ``findEssentialMat`` + ``recoverPose`` (``RANSAC``, and ``USAC_MAGSAC``), on the synthetic roadmap scenes:
   150 points in the field of view of the simulator's 640 x 480 front camera, 1 px noise, 25%
   outliers, a random turn and step, the same pixel correspondences and the same 2 px inlier
   threshold for all (:func:`planar_comparison`). ``planar_vs_X_*_ratio`` = ours / theirs, from
   the same run: below 1, ours is better (errors) or faster (time).

Times are medians in milliseconds; errors are medians in degrees.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable, Iterable
from typing import Any

import cv2
import numpy as np

from perception.camera import CatadioptricCamera, PanoramaCamera, PinholeCamera, unwarp
from perception.features import detect
from perception.geometry import Pose2D
from perception.matching import Landmarks, match_landmarks
from perception.planar import estimate_planar_motion, rotation_y
from perception.synthetic import (
    PlanarScene,
    angle_deg,
    make_planar_scene,
    make_scene,
    rotation_error_deg,
    textured_panorama,
)
from perception.zinf import estimate_motion

PANO = PanoramaCamera()
DONUT = CatadioptricCamera()
# OpenCV optical axes from body axes (x right = -y, y down = -z, z forward = x)
_BODY_FROM_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def _median_ms(samples: list[float]) -> float:
    return round(float(np.median(samples)) * 1e3, 4)


def _timed(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[Any, float]:
    """``fn(*args, **kwargs)`` and the seconds it took."""
    start = time.perf_counter()
    value = fn(*args, **kwargs)
    return value, time.perf_counter() - start


def _match_to(viewframe: Any, features: Any) -> Any:
    """Match a frame's features (and their bearings) against the viewframe: the pipeline's match stage."""
    return match_landmarks(features, PANO.pixel_to_bearing(features.keypoints_uv), viewframe)


def _poses(count: int) -> list[Pose2D]:
    """The viewframe pose (the lab's centre) then poses 2-20 cm from it in all directions, turned.

    Route following compares frames with a nearby viewframe; in an 8 x 6 m room the walls are
    "far" (move less than a degree) only for displacements of this order.
    """
    rng = np.random.default_rng(7)
    poses = [Pose2D(4.0, 3.0, 0.0)]
    for _ in range(count - 1):
        r, a = rng.uniform(0.02, 0.2), rng.uniform(-np.pi, np.pi)
        poses.append(Pose2D(4.0 + r * np.cos(a), 3.0 + r * np.sin(a), float(rng.uniform(-1.5, 1.5))))
    return poses


def _frames(count: int) -> tuple[list[np.ndarray], list[Pose2D], str]:
    """Grey panoramas and their true poses: from the simulator if it renders, else synthetic."""
    poses = _poses(count)
    try:
        from drivers.sim.simulation import Simulation

        sim = Simulation.load("lab", seed=0)
        images = [sim.snapshot(pose, camera="panorama").image for pose in poses]
        gray = [cv2.cvtColor(im, cv2.COLOR_BGR2GRAY) if im.ndim == 3 else im for im in images]
        if all(im.shape == (PANO.height, PANO.width) for im in gray):
            return [np.ascontiguousarray(im, dtype=np.uint8) for im in gray], poses, "simulator:lab"
    except Exception:  # noqa: BLE001 - any failure of the (separately developed) renderer: fall back
        pass
    base = textured_panorama(0)
    shifts = [int(round(np.degrees(p.theta - poses[0].theta) / PANO.deg_per_px)) for p in poses]
    frames = [np.roll(base, s, axis=1) for s in shifts]  # pure turns: column shifts of one panorama
    rng = np.random.default_rng(1)
    frames = [np.clip(f + rng.normal(0, 3, f.shape), 0, 255).astype(np.uint8) for f in frames]
    synthetic_poses = [Pose2D(poses[0].x, poses[0].y, p.theta) for p in poses]
    return frames, synthetic_poses, "synthetic:turned-texture"


def _donut_maps() -> tuple[np.ndarray, np.ndarray]:
    """Remap tables panorama -> donut, to make catadioptric test images from panoramas."""
    vs, us = np.mgrid[0 : DONUT.height, 0 : DONUT.width]
    uv = np.column_stack((us.ravel(), vs.ravel())).astype(np.float64)
    src, valid = PANO.bearing_to_pixel(DONUT.pixel_to_bearing(uv))
    src[~valid] = -1.0
    shape = (DONUT.height, DONUT.width)
    return src[:, 0].reshape(shape).astype(np.float32), src[:, 1].reshape(shape).astype(np.float32)


def pipeline_figures(quick: bool) -> dict[str, Any]:
    """Speed of the whole pipeline against bare ORB + knn matching, on the same frames."""
    frames, poses, source = _frames(8 if quick else 24)
    passes = 3 if quick else 10
    to_donut = _donut_maps()
    donuts = [cv2.remap(f, *to_donut, cv2.INTER_LINEAR) for f in frames]
    unwarp_maps = DONUT.unwarp_maps(PANO)
    view = detect(frames[0], camera=PANO)
    viewframe = Landmarks(view.descriptors, PANO.pixel_to_bearing(view.keypoints_uv), view.kind)

    orb = cv2.ORB.create(500)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    _, bare_view = orb.detectAndCompute(frames[0], None)

    def bare(frame: np.ndarray) -> Any:
        _, descriptors = orb.detectAndCompute(frame, None)
        return matcher.knnMatch(descriptors, bare_view, k=2)

    stage: dict[str, list[float]] = {k: [] for k in ("unwarp", "detect", "match", "zinf", "total", "bare")}
    yaw_errors, direction_errors, matches, ok, translated = [], [], [], [], []
    for _ in range(passes):
        for donut, frame, pose in zip(donuts, frames, poses, strict=True):
            start = time.perf_counter()
            pano, t_unwarp = _timed(unwarp, donut, unwarp_maps)
            features, t_detect = _timed(detect, pano, camera=PANO)
            found, t_match = _timed(_match_to, viewframe, features)
            motion, t_zinf = _timed(estimate_motion, found.ref, found.cur)
            stage["total"].append(time.perf_counter() - start)
            for key, value in (("unwarp", t_unwarp), ("detect", t_detect), ("match", t_match), ("zinf", t_zinf)):
                stage[key].append(value)
            stage["bare"].append(_timed(bare, frame)[1])
            matches.append(len(found))
            ok.append(motion.rotation_ok)
            if motion.rotation_ok:  # the landmarks turn by the opposite of the robot's turn
                true_yaw = -(pose.theta - poses[0].theta)
                yaw_errors.append(abs(np.degrees(np.angle(np.exp(1j * (motion.yaw - true_yaw))))))
            moved = np.array([pose.x - poses[0].x, pose.y - poses[0].y, 0.0])  # ref frame: theta 0
            translated.append(motion.ok)
            if motion.ok and np.linalg.norm(moved) > 0:
                direction_errors.append(angle_deg(motion.translation, moved))
    total = float(np.median(stage["total"]))
    bare_time = float(np.median(stage["bare"]))
    return {
        "frames_source": source,
        "frames": len(frames),
        "pipeline_fps": round(1.0 / total, 1),
        "pipeline_ms": _median_ms(stage["total"]),
        "pipeline_unwarp_ms": _median_ms(stage["unwarp"]),
        "pipeline_detect_ms": _median_ms(stage["detect"]),
        "pipeline_match_ms": _median_ms(stage["match"]),
        "pipeline_zinf_ms": _median_ms(stage["zinf"]),
        "bare_orb_detect_knn_ms": _median_ms(stage["bare"]),
        "pipeline_cost_ratio": round(total / bare_time, 3),
        "pipeline_matches_per_frame": round(float(np.mean(matches)), 1),
        "pipeline_rotation_found_fraction": round(float(np.mean(ok)), 3),
        "pipeline_translation_found_fraction": round(float(np.mean(translated)), 3),
        "pipeline_yaw_error_deg": round(float(np.median(yaw_errors)), 3) if yaw_errors else None,
        "pipeline_translation_error_deg": (
            round(float(np.median(direction_errors)), 3) if direction_errors else None
        ),
    }


def _optical(b: np.ndarray) -> np.ndarray:
    return b @ _BODY_FROM_OPTICAL  # row form of B^T b


def _body_motion(R_opt: np.ndarray, t_opt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rotation ref->cur, camera displacement direction in the ref frame) in body axes."""
    R = _BODY_FROM_OPTICAL @ R_opt @ _BODY_FROM_OPTICAL.T
    t = _BODY_FROM_OPTICAL @ np.ravel(t_opt)
    return R, -(R.T @ t)


def zinf_figures(quick: bool) -> dict[str, Any]:
    """Z-infinity vs PoseLib and OpenCV's essential matrix on the same synthetic scenes."""
    trials = 10 if quick else 50
    try:
        poselib = importlib.import_module("poselib")
    except ModuleNotFoundError:
        poselib = None
    rows: dict[str, list[float]] = {}
    threshold = np.radians(0.5)  # normalised units ~ radians near the axis
    cam = {"model": "PINHOLE", "width": 2, "height": 2, "params": [1.0, 1.0, 0.0, 0.0]}

    def add(key: str, value: float) -> None:
        rows.setdefault(key, []).append(value)

    for seed in range(trials):
        rng = np.random.default_rng(1000 + seed)
        heading = rng.uniform(-np.pi, np.pi)
        scene = make_scene(
            seed,
            n_far=120,
            n_near=180,
            yaw_deg=float(rng.uniform(-90, 90)),
            tilt_deg=float(rng.uniform(-3, 3)),
            position=(0.5 * np.cos(heading), 0.5 * np.sin(heading), 0.0),
            noise_deg=0.1,
            outlier_fraction=0.3,
        )
        motion, t = _timed(estimate_motion, scene.ref, scene.cur, rng=seed)
        add("zinf_ms", t)
        add("zinf_rotation_error_deg", rotation_error_deg(motion.rotation, scene.rotation))
        if motion.ok:
            add("zinf_translation_error_deg", angle_deg(motion.translation, scene.position))
        add("zinf_ok", float(motion.ok))
        front = (scene.ref[:, 0] > 0.1) & (scene.cur[:, 0] > 0.1)
        o1, o2 = _optical(scene.ref[front]), _optical(scene.cur[front])
        x1, x2 = o1[:, :2] / o1[:, 2:], o2[:, :2] / o2[:, 2:]
        add("pinhole_correspondences", float(front.sum()))
        if poselib is not None:
            (pose, _), t = _timed(poselib.estimate_relative_pose, x1, x2, cam, cam,
                                  {"max_epipolar_error": threshold, "seed": 0}, {})
            R, c = _body_motion(pose.R, pose.t)
            add("poselib_ms", t)
            add("poselib_rotation_error_deg", rotation_error_deg(R, scene.rotation))
            add("poselib_translation_error_deg", angle_deg(c, scene.position))
        E_and_mask, t_e = _timed(cv2.findEssentialMat, x1, x2, np.eye(3), method=cv2.RANSAC, prob=0.999,
                                 threshold=threshold)
        E, mask = E_and_mask
        if E is not None and E.shape == (3, 3):
            (_, R_opt, t_opt, _), t_r = _timed(cv2.recoverPose, E, x1, x2, np.eye(3), mask=mask)
            R, c = _body_motion(R_opt, t_opt)
            add("opencv_essential_ms", t_e + t_r)
            add("opencv_rotation_error_deg", rotation_error_deg(R, scene.rotation))
            add("opencv_translation_error_deg", angle_deg(c, scene.position))

    out: dict[str, Any] = {"zinf_trials": trials, "zinf_correspondences": 300}
    out.update(_medians(rows, (
        "zinf_ms",
        "zinf_rotation_error_deg",
        "zinf_translation_error_deg",
        "poselib_ms",
        "poselib_rotation_error_deg",
        "poselib_translation_error_deg",
        "opencv_essential_ms",
        "opencv_rotation_error_deg",
        "opencv_translation_error_deg",
    )))
    out["zinf_ok_fraction"] = round(float(np.mean(rows["zinf_ok"])), 3)
    out["pinhole_correspondences"] = round(float(np.mean(rows["pinhole_correspondences"])), 1)
    return out


# the simulator's pan-tilt "front" camera (drivers/sim/world.py) without its distortion
PLANAR_CAMERA = PinholeCamera(640, 480, 525.0, 525.0, 319.5, 239.5)
PLANAR_THRESHOLD_PX = 2.0  # the inlier threshold every method gets (about 2 sigma of the 1 px noise)


def planar_scene(seed: int, *, n: int = 150, noise_px: float = 1.0, outlier_fraction: float = 0.25) -> PlanarScene:
    """Issue 13's scene on :data:`PLANAR_CAMERA`: ``n`` points inside its field of view, a random
    turn (+-30 deg) and a 1 m step in a random direction, ``noise_px`` of keypoint noise,
    ``outlier_fraction`` of the current points replaced by random pixels."""
    cam = PLANAR_CAMERA
    rng = np.random.default_rng(2000 + seed)
    phi = rng.uniform(-np.pi, np.pi)
    return make_planar_scene(
        seed,
        n=n,
        theta_deg=float(rng.uniform(-30.0, 30.0)),
        displacement=(float(np.sin(phi)), float(np.cos(phi))),
        noise=noise_px / cam.fx,
        outlier_fraction=outlier_fraction,
        half_extent=((cam.cx + 0.5) / cam.fx, (cam.cy + 0.5) / cam.fy),
    )


def _pixels(xy: np.ndarray) -> np.ndarray:
    cam = PLANAR_CAMERA
    return xy * [cam.fx, cam.fy] + [cam.cx, cam.cy]


def _errors(R: np.ndarray, c: np.ndarray, scene: PlanarScene) -> tuple[float, float]:
    """Rotation error and direction-of-travel error (deg) of an estimate (optical frame, ``c`` the
    current camera centre in the ref frame; zero when not estimated: 180 degrees wrong)."""
    true_c = np.array([scene.displacement[0], 0.0, scene.displacement[1]])
    direction = angle_deg(c, true_c) if np.linalg.norm(c) > 0 else 180.0
    return rotation_error_deg(R, rotation_y(scene.theta)), direction


def _poselib_relpose(poselib: Any, scene: PlanarScene, threshold_px: float) -> tuple[np.ndarray, np.ndarray]:
    """PoseLib's LO-RANSAC 5-point relative pose with its own refinement: (R, camera centre)."""
    cam = PLANAR_CAMERA
    camera = {"model": "PINHOLE", "width": cam.width, "height": cam.height, "params": [cam.fx, cam.fy, cam.cx, cam.cy]}
    pose, _ = poselib.estimate_relative_pose(
        _pixels(scene.ref), _pixels(scene.cur), camera, camera, {"max_epipolar_error": threshold_px, "seed": 0}, {}
    )
    return pose.R, -(pose.R.T @ pose.t)


def _opencv_relpose(scene: PlanarScene, threshold_px: float, method: int) -> tuple[np.ndarray, np.ndarray]:
    """``cv2.findEssentialMat`` (5-point, ``method``) + ``cv2.recoverPose``: (R, camera centre)."""
    x1, x2, K = _pixels(scene.ref), _pixels(scene.cur), PLANAR_CAMERA.K
    E, mask = cv2.findEssentialMat(x1, x2, K, method=method, prob=0.999, threshold=threshold_px)
    if E is None or E.shape[0] < 3:
        return np.eye(3), np.zeros(3)
    _, R, t, _ = cv2.recoverPose(E[:3], x1, x2, K, mask=mask)
    return R, -(R.T @ t.ravel())


def planar_comparison(
    seeds: Iterable[int], *, threshold_px: float = PLANAR_THRESHOLD_PX, opencv: bool = True, **scene: Any
) -> dict[str, list[float]]:
    """Per-scene errors (deg) and times (s) of planar homing, PoseLib and OpenCV on the same data.

    Every method gets the same pixel correspondences (normalised ones for ours, with the focal
    length) and the same inlier threshold in pixels. Ours estimates 3 degrees of freedom (its
    rotation error is the error of ``theta``), the others 5 (the angle of the whole rotation
    error). A direction not estimated counts as 180 degrees wrong. ``scene`` goes to
    :func:`planar_scene`.
    """
    poselib = _optional("poselib")
    cam = PLANAR_CAMERA
    rows: dict[str, list[float]] = {}

    def add(prefix: str, R: np.ndarray, c: np.ndarray, seconds: float, s: PlanarScene) -> None:
        rotation, direction = _errors(R, c, s)
        for key, value in (("ms", seconds), ("rotation_error_deg", rotation), ("direction_error_deg", direction)):
            rows.setdefault(f"{prefix}_{key}", []).append(value)

    for seed in seeds:
        s = planar_scene(seed, **scene)
        result, t = _timed(estimate_planar_motion, s.ref, s.cur, focal=(cam.fx, cam.fy), threshold_px=threshold_px,
                           rng=seed)
        c = np.array([result.direction[0], 0.0, result.direction[1]])
        add("planar", rotation_y(result.theta), c, t, s)
        rows.setdefault("planar_ok", []).append(float(result.ok))
        if poselib is not None:
            (R, c), t = _timed(_poselib_relpose, poselib, s, threshold_px)
            add("poselib_relpose", R, c, t, s)
        if opencv:
            for name, method in (("opencv_ransac", cv2.RANSAC), ("opencv_magsac", cv2.USAC_MAGSAC)):
                (R, c), t = _timed(_opencv_relpose, s, threshold_px, method)
                add(name, R, c, t, s)
    return rows


def planar_figures(quick: bool) -> dict[str, Any]:
    """Planar homing vs PoseLib's and OpenCV's general (5-point) relative pose on the synthetic roadmap scenes."""
    trials = 12 if quick else 100
    cv2.setRNGSeed(0)
    rows = planar_comparison(range(trials))
    out: dict[str, Any] = {
        "planar_trials": trials,
        "planar_points": 150,
        "planar_noise_px": 1.0,
        "planar_outlier_fraction": 0.25,
        "planar_threshold_px": PLANAR_THRESHOLD_PX,
        "planar_ok_fraction": round(float(np.mean(rows["planar_ok"])), 3),
    }
    methods = ("planar", "poselib_relpose", "opencv_ransac", "opencv_magsac")
    keys = tuple(f"{m}_{k}" for m in methods for k in ("ms", "rotation_error_deg", "direction_error_deg"))
    out.update(_medians(rows, keys))
    for other in methods[1:]:
        for figure in ("ms", "rotation_error_deg", "direction_error_deg"):
            ours, theirs = rows.get(f"planar_{figure}"), rows.get(f"{other}_{figure}")
            name = "time" if figure == "ms" else figure.removesuffix("_deg")
            out[f"planar_vs_{other}_{name}_ratio"] = (
                round(float(np.median(ours) / np.median(theirs)), 3) if ours and theirs else None
            )
    return out


def _optional(name: str) -> Any:
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError:
        return None


def _medians(rows: dict[str, list], keys: tuple[str, ...]) -> dict[str, float | None]:
    """The median of each named series (times via ``_median_ms``); None for a series never measured."""
    out: dict[str, float | None] = {}
    for key in keys:
        values = rows.get(key)
        if not values:
            out[key] = None
        elif key.endswith("_ms"):
            out[key] = _median_ms(values)
        else:
            out[key] = round(float(np.median(values)), 4)
    return out


def run(quick: bool) -> dict[str, Any]:
    """All perception figures as one flat JSON-serialisable dict."""
    cv2.setRNGSeed(0)
    return {**pipeline_figures(quick), **zinf_figures(quick), **planar_figures(quick)}
