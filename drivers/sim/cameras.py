"""Simulated cameras: where each one is (base or pan-tilt mount) and what it grabs.

A :class:`SimCamera` implements :class:`~drivers.interfaces.Camera`. ``grab()`` renders at the
simulation's current true pose and pan-tilt state and stamps the frame with simulated time;
image cameras return a :class:`~perception.frame.Frame`, the ``bearings`` sensor a
:class:`~perception.frame.LandmarkBearings`. Frame drops, exposure noise and the per-run
lighting change are applied here, after rendering, so geometry tests see clean images.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np

from drivers.sim.render import CameraRenderer
from drivers.sim.scene import Scene
from drivers.sim.sensors import BearingSensorModel, observe_landmarks
from drivers.sim.world_values import CameraSpec, Lighting, PtuSpec
from perception.camera import StereoRig
from perception.frame import Frame, LandmarkBearings
from perception.geometry import Pose2D, rot_pitch, rot_z


@dataclass(frozen=True, slots=True)
class CameraPose:
    """A camera in the world: ``eye`` (3,), and its rotation split as ``Rz(psi) @ rest``.

    ``psi`` is the heading of the level frame; ``rest`` holds what pitch, tilt (and a yaw on a
    tilted head) add, so that renderers can cache per ``rest`` while the robot turns.
    """

    eye: np.ndarray
    psi: float
    rest: np.ndarray

    @property
    def rotation(self) -> np.ndarray:
        """World-from-camera-body rotation."""
        return rot_z(self.psi) @ self.rest


def camera_pose(spec: CameraSpec, ptu: PtuSpec, base: Pose2D, pan: float = 0.0, tilt: float = 0.0) -> CameraPose:
    """Where camera ``spec`` is when the base is at ``base`` and the pan-tilt head at (pan, tilt)."""
    m = spec.pose
    c, s = math.cos(base.theta), math.sin(base.theta)
    if spec.mount == "ptu":
        head = np.array([base.x + c * ptu.x - s * ptu.y, base.y + s * ptu.x + c * ptu.y, ptu.z])
        psi = base.theta + pan
        head_rest = rot_pitch(tilt)
        eye = head + rot_z(psi) @ head_rest @ np.array([m.x, m.y, m.z])
        return CameraPose(eye, psi, head_rest @ rot_z(m.yaw) @ rot_pitch(m.pitch))
    eye = np.array([base.x + c * m.x - s * m.y, base.y + s * m.x + c * m.y, m.z])
    return CameraPose(eye, base.theta + m.yaw, rot_pitch(m.pitch))


class SimCamera:
    """One simulated camera of a :class:`~drivers.sim.simulation.Simulation`.

    ``state`` is a callable returning (true base pose, pan, tilt, time) at the current instant.
    """

    def __init__(
        self,
        spec: CameraSpec,
        scene: Scene,
        ptu: PtuSpec,
        state: Callable[[], tuple[Pose2D, float, float, float]],
        *,
        rng: np.random.Generator,
        lighting: tuple[float, float] = (1.0, 0.0),
    ) -> None:
        self.name = spec.name
        self.spec = spec
        self.scene = scene
        self.ptu = ptu
        self._state = state
        self.rng = rng
        self.gain, self.bias = lighting
        self.enabled_noise = True  # frame drops and exposure noise as configured
        self._renderer: CameraRenderer | None = None
        self._right_renderer: CameraRenderer | None = None
        self.last: Frame | LandmarkBearings | None = None
        if spec.kind == "bearings":
            self.model = BearingSensorModel(spec.azimuth_fov, spec.elevation_limits, spec.max_range, spec.noise)
        else:
            self.model = spec.model

    @property
    def is_image(self) -> bool:
        return self.spec.kind != "bearings"

    def grab(self) -> Frame | LandmarkBearings | None:
        """What the camera sees now; None when the frame is dropped."""
        base, pan, tilt, now = self._state()
        if self.enabled_noise and self.spec.frame_drop > 0 and self.rng.random() < self.spec.frame_drop:
            return None
        pose = camera_pose(self.spec, self.ptu, base, pan, tilt)
        if not self.is_image:
            out: Frame | LandmarkBearings = observe_landmarks(
                self.scene, self.spec, pose.eye, pose.rotation, rng=self.rng, stamp=now
            )
        else:
            left, right = self._render(pose)
            noisy = self.enabled_noise and self.spec.exposure_noise > 0
            left = self._expose(left, noisy)
            right = self._expose(right, noisy) if right is not None else None
            out = Frame(image=left, camera=self.model, stamp=now, camera_name=self.name, right=right)
        self.last = out
        return out

    def snapshot(self, base: Pose2D, pan: float = 0.0, tilt: float = 0.0, stamp: float = 0.0) -> Frame:
        """The clean image at a given true base pose and head angles (lighting, no random noise)."""
        if not self.is_image:
            raise ValueError(f"camera {self.name!r} is a bearings sensor: it makes no images")
        left, right = self._render(camera_pose(self.spec, self.ptu, base, pan, tilt))
        left = self._expose(left, False)
        right = self._expose(right, False) if right is not None else None
        return Frame(image=left, camera=self.model, stamp=stamp, camera_name=self.name, right=right)

    def observe(self, base: Pose2D, pan: float = 0.0, tilt: float = 0.0, stamp: float = 0.0) -> LandmarkBearings:
        """The noise-free landmark bearings at a given true base pose (``bearings`` sensors only)."""
        if self.is_image:
            raise ValueError(f"camera {self.name!r} makes images, not landmark bearings")
        pose = camera_pose(self.spec, self.ptu, base, pan, tilt)
        return observe_landmarks(self.scene, self.spec, pose.eye, pose.rotation, rng=None, stamp=stamp)

    def _render(self, pose: CameraPose) -> tuple[np.ndarray, np.ndarray | None]:
        model = self.model
        if isinstance(model, StereoRig):
            if self._renderer is None:
                self._renderer = CameraRenderer(self.scene, model.left)
                same = model.right == model.left
                self._right_renderer = self._renderer if same else CameraRenderer(self.scene, model.right)
            left = self._renderer.render(pose.eye, pose.psi, pose.rest)
            right_eye = pose.eye + pose.rotation @ model.right_centre
            return left, self._right_renderer.render(right_eye, pose.psi, pose.rest)
        if self._renderer is None:
            self._renderer = CameraRenderer(self.scene, model)
        return self._renderer.render(pose.eye, pose.psi, pose.rest), None

    def _expose(self, image: np.ndarray, noisy: bool) -> np.ndarray:
        """Lighting gain/bias, and with ``noisy`` a random exposure gain and sensor noise."""
        gain, bias = self.gain, self.bias
        if noisy:
            sigma = self.spec.exposure_noise
            gain *= max(0.05, 1.0 + sigma * float(self.rng.standard_normal()))
            noise = self.rng.standard_normal(image.shape, dtype=np.float32) * (40.0 * sigma)
            return np.clip(image * np.float32(gain) + (noise + np.float32(bias)), 0, 255).astype(np.uint8)
        if gain == 1.0 and bias == 0.0:
            return image
        return cv2.addWeighted(image, gain, image, 0.0, bias)  # saturating, unlike convertScaleAbs

    def close(self) -> None:
        pass


def run_lighting(lighting: Lighting, rng: np.random.Generator) -> tuple[float, float]:
    """The (gain, bias) of one run: the world's lighting, varied per seed by ``run_variation``."""
    gain = lighting.gain
    if lighting.run_variation > 0:
        gain *= max(0.05, 1.0 + lighting.run_variation * float(rng.standard_normal()))
    return gain, lighting.bias
