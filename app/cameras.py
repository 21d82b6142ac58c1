"""Camera modes of the app: driver (in-cabin, default), chase, a free-fly camera, and a close-up of the
windshield from the driver's eye (glass)."""

from __future__ import annotations

import math

import numpy as np

from rain_core.camera import Camera, ChaseRig, driver_camera, glass_camera

MODES = ("driver", "chase", "free", "glass")
_CYCLE = ("driver", "chase", "free")  # C cycles these; G toggles the glass close-up


class FreeFly:
    """WASD/arrow-free camera moved by held keys; mouse drag turns it. Metres, radians, m/s."""

    def __init__(self, position=(0.0, 3.0, 10.0), yaw=0.0, pitch=-0.1, speed_m_s=15.0):
        self.position = np.array(position, dtype=np.float64)
        self.yaw, self.pitch, self.speed_m_s = yaw, pitch, speed_m_s

    def forward(self) -> np.ndarray:
        return np.array([-math.sin(self.yaw) * math.cos(self.pitch), math.sin(self.pitch),
                         -math.cos(self.yaw) * math.cos(self.pitch)])

    def turn(self, dx_px: float, dy_px: float):
        self.yaw -= dx_px * 0.004
        self.pitch = min(max(self.pitch - dy_px * 0.004, -1.5), 1.5)

    def move(self, dt_s: float, held: set[str]):
        f = self.forward()
        right = np.cross(f, [0.0, 1.0, 0.0])
        right /= max(np.linalg.norm(right), 1e-9)
        step = self.speed_m_s * min(max(dt_s, 0.0), 0.1)
        ahead = ("up" in held) - ("down" in held)
        side = ("right" in held) - ("left" in held)
        self.position += step * (ahead * f + side * right)
        self.position[1] = max(self.position[1], 0.3)

    def camera(self, fov_y_deg: float) -> Camera:
        return Camera(position=self.position.copy(), forward=self.forward(), fov_y_deg=fov_y_deg)


class CameraModes:
    """Which camera looks, and switching between them (C cycles)."""

    def __init__(self, mode: str = "driver"):
        if mode not in MODES:
            raise ValueError(f"camera mode must be one of {MODES}, got {mode!r}")
        self.mode = mode
        self.chase = ChaseRig()
        self.free = FreeFly()

    def cycle(self, car=None):
        nxt = _CYCLE[(_CYCLE.index(self.mode) + 1) % len(_CYCLE)] if self.mode in _CYCLE else "driver"
        self.set_mode(nxt, car)

    def toggle_glass(self, car=None):
        """The G key: the windshield close-up, and back to the driver's seat."""
        self.set_mode("driver" if self.mode == "glass" else "glass", car)

    def set_mode(self, mode: str, car=None):
        """Switch camera (from the C key or the panel); free-fly starts behind the car, not where it was left."""
        if mode not in MODES:
            raise ValueError(f"camera mode must be one of {MODES}, got {mode!r}")
        if mode == self.mode:
            return
        self.mode = mode
        if mode == "free" and car is not None:
            self.free.position = car.position - car.forward() * 8.0 + np.array([0.0, 3.0, 0.0])
            self.free.yaw = getattr(car, "yaw", 0.0)
        self.chase.reset()

    def _glass_point(self, car, eye_local) -> np.ndarray:
        """The car-local glass point ahead of the eye (kept: the glass geometry is not rebuilt each frame)."""
        key = (id(getattr(car, "spec", None)), tuple(np.asarray(eye_local, dtype=np.float64)))
        if getattr(self, "_glass_key", None) != key:
            from rain_core.effects.windshield.glass import GlassGeometry

            spec = getattr(car, "spec", None)
            glass = GlassGeometry(spec) if spec is not None else GlassGeometry()
            self._glass_key, self._glass_look = key, glass.point_ahead_of(eye_local)
        return self._glass_look

    def camera(self, car, eye_local, dt_s: float, fov_y_deg: float = 70.0, view=None) -> Camera:
        """The current mode's camera. ``fov_y_deg`` (deg) is the chase and free cameras' field of view; ``view``
        (the settings' ``camera`` section) gives the driver's field of view and pitch, else their defaults."""
        if self.mode == "driver":
            if view is None:
                return driver_camera(car, eye_local)
            return driver_camera(car, eye_local, fov_y_deg=view.driver_fov_deg, pitch_deg=view.driver_pitch_deg)
        if self.mode == "glass":
            return glass_camera(car, eye_local, self._glass_point(car, eye_local))
        if self.mode == "chase":
            return self.chase.camera(car, dt_s, fov_y_deg=min(fov_y_deg, 65.0))
        return self.free.camera(fov_y_deg)
