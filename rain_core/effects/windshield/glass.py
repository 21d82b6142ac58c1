"""The windshield as a surface: ``GlassGeometry`` wraps ``car_mesh.windshield_frame``.

A trapezoid of height H (m, along the glass) whose width shrinks linearly from the bottom to the top, bulged
outward by ``sag``. Coordinates: s (m) to the car's right, t (m) up the glass; UV: u = s/width(t) + ½, v = t/H
(the mesh's UV). Gravity along the glass follows the real curved surface (a drop near the edge of the bulge
slides outward a little).
"""

from __future__ import annotations

import numpy as np

from rain_core.car_mesh import windshield_frame
from rain_core.effects.windshield.constants import FILM_CELLS
from rain_core.physics import G_M_S2
from rain_core.vehicles import CAR_SPEC, VehicleSpec


class GlassGeometry:
    """The windshield as a trapezoid in its own frame (see the module docstring). Lengths in m."""

    def __init__(self, spec: VehicleSpec = CAR_SPEC):
        f = windshield_frame(spec)
        self.spec = spec
        self.width_bottom = float(f["width_m"])
        self.width_top = float(f["top_width_m"])
        self.height = float(f["height_m"])
        self.sag = float(f["sag_m"])
        self.rake = float(f["rake_rad"])
        self.bottom_center = np.asarray(f["bottom_center"], dtype=np.float64)
        self.up = np.asarray(f["up_along_glass"], dtype=np.float64)
        self.right = np.asarray(f["right"], dtype=np.float64)
        self.normal = np.asarray(f["normal"], dtype=np.float64)
        self.area_m2 = 0.5 * (self.width_bottom + self.width_top) * self.height
        self._dw = (self.width_top - self.width_bottom) / self.height  # d width / d t

    def width(self, t) -> np.ndarray:
        """Glass width (m) at height t (m) up the glass."""
        return self.width_bottom + self._dw * np.asarray(t, dtype=np.float64)

    def to_uv(self, st) -> np.ndarray:
        st = np.asarray(st, dtype=np.float64)
        return np.stack([st[..., 0] / self.width(st[..., 1]) + 0.5, st[..., 1] / self.height], axis=-1)

    def from_uv(self, uv) -> np.ndarray:
        uv = np.asarray(uv, dtype=np.float64)
        t = uv[..., 1] * self.height
        return np.stack([(uv[..., 0] - 0.5) * self.width(t), t], axis=-1)

    def contains(self, st) -> np.ndarray:
        st = np.asarray(st, dtype=np.float64)
        t = st[..., 1]
        return (t >= 0.0) & (t <= self.height) & (np.abs(st[..., 0]) <= 0.5 * self.width(t))

    def local_points(self, st) -> np.ndarray:
        """Car-local positions (m) of glass points, the bulge included."""
        uv = self.to_uv(st)
        st = np.asarray(st, dtype=np.float64)
        bulge = self.sag * (1.0 - (2.0 * uv[..., 0] - 1.0) ** 2) * (1.0 - (2.0 * uv[..., 1] - 1.0) ** 2)
        return (
            self.bottom_center
            + st[..., 1:2] * self.up
            + st[..., 0:1] * self.right
            + bulge[..., None] * self.normal
        )

    def point_ahead_of(self, eye_local, pitch_deg: float = -8.0) -> np.ndarray:
        """Car-local point (m) on the glass that an eye at ``eye_local`` (car-local m) sees looking straight
        ahead (−z), pitched by ``pitch_deg`` (deg, negative = down); kept 5 cm inside the glass's edges. The
        close-up glass camera looks there."""
        eye = np.asarray(eye_local, dtype=np.float64)
        p = np.radians(pitch_deg)
        d = np.array([0.0, np.sin(p), -np.cos(p)])
        lam = float(np.dot(self.bottom_center - eye, self.normal) / np.dot(d, self.normal))
        rel = eye + lam * d - self.bottom_center
        t = min(max(float(np.dot(rel, self.up)), 0.05), self.height - 0.05)
        half = 0.5 * float(self.width(t)) - 0.05
        s = min(max(float(np.dot(rel, self.right)), -half), half)
        return self.local_points(np.array([s, t]))

    def gravity(self, st) -> np.ndarray:
        """Acceleration of gravity along the curved glass, (…, 2) m/s² in (s, t) (the car is level)."""
        st = np.asarray(st, dtype=np.float64)
        s, t = st[..., 0], st[..., 1]
        w = self.width(t)
        u = s / w + 0.5
        v = t / self.height
        bu, bv = 1.0 - (2.0 * u - 1.0) ** 2, 1.0 - (2.0 * v - 1.0) ** 2
        dbu_du, dbv_dv = -4.0 * (2.0 * u - 1.0), -4.0 * (2.0 * v - 1.0)
        du_dt = -s * self._dw / (w * w)
        ny = self.normal[1]
        dy_ds = self.sag * ny * dbu_du / w * bv
        dy_dt = self.up[1] + self.sag * ny * (dbu_du * du_dt * bv + bu * dbv_dv / self.height)
        return np.stack([-G_M_S2 * dy_ds, -G_M_S2 * dy_dt], axis=-1)

    def sample_uniform(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """n points (s, t) m uniformly distributed over the glass area."""
        u1, u2 = rng.random(n), rng.random(n)
        w0, dw, h = self.width_bottom, self._dw * self.height, self.height
        # Inverse CDF of the density ∝ width(t): solve w0·x + dw·x²/2 = q·(w0 + dw/2), x = t/H.
        q = u1 * (w0 + 0.5 * dw)
        x = 2.0 * q / (w0 + np.sqrt(w0 * w0 + 2.0 * dw * q)) if dw != 0 else q / w0
        t = np.clip(x, 0.0, 1.0) * h
        return np.stack([(u2 - 0.5) * self.width(t), t], axis=-1)

    def cells(self, n: int = FILM_CELLS) -> tuple[np.ndarray, np.ndarray]:
        """Centres (n, n, 2) (s, t) m and areas (n, n) m² of the film grid's cells; index [iv, iu]."""
        c = (np.arange(n) + 0.5) / n
        uu, vv = np.meshgrid(c, c)
        centres = self.from_uv(np.stack([uu, vv], axis=-1))
        areas = self.width(centres[..., 1]) / n * (self.height / n)
        return centres, areas

    def cell_index(self, st, n: int = FILM_CELLS) -> np.ndarray:
        """Flat film-cell index (iv·n + iu) of points (…, 2) (s, t) m; points on the edge go to the edge cell."""
        uv = self.to_uv(st)
        iu = np.minimum(np.maximum((uv[..., 0] * n).astype(np.int64), 0), n - 1)  # np.clip is slow on small arrays
        iv = np.minimum(np.maximum((uv[..., 1] * n).astype(np.int64), 0), n - 1)
        return iv * n + iu
