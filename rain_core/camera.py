"""Pinhole cameras and the rigs that place them relative to a car (driver's seat, chase)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def _cross(a, b) -> np.ndarray:
    """a × b of two 3-vectors: np.cross's products and differences (bit-identical), without its ~35 µs of
    axis handling per call (the renderer builds view matrices every frame)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _normalize(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    n = math.sqrt(v.dot(v)) if v.ndim == 1 else np.linalg.norm(v)  # a vector: np.linalg.norm's own formula
    return v / n if n > 0 else v


@dataclass
class Camera:
    """A perspective camera. position (m, world), forward/up unit vectors, vertical fov (deg), near/far (m)."""

    position: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.5, 0.0]))
    forward: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -1.0]))
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    fov_y_deg: float = 70.0
    near_m: float = 0.05
    far_m: float = 2000.0
    inside_car: bool = False  # the windshield effect draws only when the camera looks through the glass
    focus_m: float = math.inf  # distance the eye/lens is focused at (m): the glass is defocused unless near it

    def forward_axis(self) -> np.ndarray:
        """The unit forward vector (world frame), ``basis()[2]`` without the other two axes."""
        return _normalize(self.forward)

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) orthonormal, world frame."""
        f = self.forward_axis()
        r = _normalize(_cross(f, np.asarray(self.up, dtype=np.float64)))
        if not r.any():
            r = np.array([1.0, 0.0, 0.0])
        u = _cross(r, f)
        return r, u, f

    def view_matrix(self, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
        """World→view 4×4 (row-major, column vectors). ``shift`` (m) is subtracted from the camera position."""
        r, u, f = self.basis()
        eye = np.asarray(self.position, dtype=np.float64) - np.asarray(shift, dtype=np.float64)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = r, u, -f
        m[:3, 3] = -m[:3, :3] @ eye
        return m

    def projection_matrix(self, aspect: float) -> np.ndarray:
        """OpenGL clip-space projection (row-major)."""
        t = 1.0 / math.tan(math.radians(self.fov_y_deg) / 2.0)
        n, f = self.near_m, self.far_m
        m = np.zeros((4, 4))
        m[0, 0] = t / aspect
        m[1, 1] = t
        m[2, 2] = (f + n) / (n - f)
        m[2, 3] = 2.0 * f * n / (n - f)
        m[3, 2] = -1.0
        return m


def look_at(position, target, fov_y_deg: float = 60.0, **kwargs) -> Camera:
    """A camera at position (m) looking at target (m)."""
    position = np.asarray(position, dtype=np.float64)
    return Camera(position=position, forward=_normalize(np.asarray(target, dtype=np.float64) - position),
                  fov_y_deg=fov_y_deg, **kwargs)


DRIVER_FOV_DEG = 40.0  # deg, vertical: the default ``camera.driver_fov_deg``
DRIVER_PITCH_DEG = 0.0  # deg: the default ``camera.driver_pitch_deg``


def driver_camera(car, eye_local, fov_y_deg: float = DRIVER_FOV_DEG, pitch_deg: float = DRIVER_PITCH_DEG) -> Camera:
    """The in-cabin view from the driver's eye (car-local m), looking along the car, ``pitch_deg`` (deg) above
    its horizon, with a vertical field of view of ``fov_y_deg`` (deg). At 40° and level, hood and dashboard fill
    about 23% of a 16:9 frame, as the road over a real car's bonnet (at 60° and −4° they filled 40%)."""
    m = car.model_matrix()
    eye = m[:3, :3] @ np.asarray(eye_local, dtype=np.float64) + m[:3, 3]
    pitch = math.radians(pitch_deg)
    fwd = car.forward() * math.cos(pitch) + np.array([0.0, math.sin(pitch), 0.0])
    return Camera(position=eye, forward=fwd, fov_y_deg=fov_y_deg, near_m=0.05, inside_car=True)


def glass_camera(car, eye_local, look_local, fov_y_deg: float = 12.0) -> Camera:
    """A close-up of the windshield from the driver's eye (car-local m), looking at ``look_local`` (a car-local
    point on the glass) with a narrow field of view and focused on that point: the drops are sharp, the street
    behind them is what the eye sees through them."""
    m = car.model_matrix()
    eye = m[:3, :3] @ np.asarray(eye_local, dtype=np.float64) + m[:3, 3]
    look = m[:3, :3] @ np.asarray(look_local, dtype=np.float64) + m[:3, 3]
    cam = look_at(eye, look, fov_y_deg=fov_y_deg, near_m=0.05, inside_car=True)
    cam.focus_m = float(np.linalg.norm(look - eye))
    return cam


class ChaseRig:
    """A camera behind and above a car that follows it smoothly (critically damped, frame-rate independent).

    ``side_m`` > 0 moves it to the car's right (a beside-the-car chase view)."""

    def __init__(self, distance_m: float = 7.0, height_m: float = 2.6, side_m: float = 0.0,
                 stiffness_per_s: float = 6.0):
        self.distance_m, self.height_m, self.side_m = distance_m, height_m, side_m
        self.stiffness_per_s = stiffness_per_s
        self._pos: np.ndarray | None = None

    def camera(self, car, dt_s: float, fov_y_deg: float = 60.0, keep_inside=None) -> Camera:
        """The camera for ``car`` after dt_s (s). keep_inside: a rain_core.collision.StreetCollider; the camera is
        then pulled in from the façades (a car against a wall never puts it inside the building)."""
        target_pos = (car.position - car.forward() * self.distance_m + car.right() * self.side_m
                      + np.array([0.0, self.height_m, 0.0]))
        if keep_inside is not None:
            target_pos[0] = keep_inside.keep_inside(float(target_pos[0]), float(target_pos[2]))
        if self._pos is None or not np.all(np.isfinite(self._pos)):
            self._pos = target_pos
        else:
            # Exact exponential approach: the same result for one big step or many small ones.
            a = 1.0 - math.exp(-self.stiffness_per_s * max(dt_s, 0.0))
            self._pos = self._pos + (target_pos - self._pos) * a
        if keep_inside is not None:
            self._pos[0] = keep_inside.keep_inside(float(self._pos[0]), float(self._pos[2]))
        look = car.position + car.forward() * 6.0 + np.array([0.0, 1.0, 0.0])
        return look_at(self._pos, look, fov_y_deg=fov_y_deg)

    def reset(self):
        self._pos = None
