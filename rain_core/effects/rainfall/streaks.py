"""The NumPy twin of the streak shader (``shaders/rainfall/streak_record.vert``): what the camera sees of each
drop, in float64, for tests and the benchmark's light budget. Keep the two in step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rain_core.effects.rainfall.constants import (
    ALPHA_MAX,
    PERIOD_M,
    SPREAD_ALPHA,
    STRETCH_MAX,
    WIDTH_FLOOR_PX,
    WIDTH_MAX_PX,
)
from rain_core.effects.rainfall.optics import streak_coverage
from rain_core.effects.rainfall.shape import drop_shape_factors
from rain_core.effects.rainfall.sim import RainfallSim


@dataclass
class StreakCamera:
    """What the streak shader knows of the camera: view_proj (4×4, wrapped frame), position (m, wrapped),
    shift_z (m), velocity (m/s), exposure (s), viewport (px), near plane (m)."""

    view_proj: np.ndarray
    position: np.ndarray
    shift_z: float
    velocity: np.ndarray
    exposure_s: float
    viewport: tuple[int, int]
    near_m: float = 0.05

    @property
    def focal_px(self) -> float:
        """Pixels per unit tan(angle), vertically (view_proj[1, 1] equals the projection's since the view has no
        scale)."""
        return float(np.linalg.norm(self.view_proj[1, :3])) * self.viewport[1] / 2.0


def streak_geometry(sim: RainfallSim, index, time_s: float | None, cam: StreakCamera,
                    brightness: float = 1.0) -> dict[str, np.ndarray]:
    """The streaks of the instances ``index`` as ``shaders/rainfall/streak_record.vert`` writes them, in float64.

    Returns arrays: ``visible`` (bool), ``head``/``tail`` (n, 3) m in the wrapped frame (the drop now, and where
    it was relative to the camera when the shutter opened), ``head_px``/``tail_px`` (n, 2) px from the image
    centre (y up), ``width_px``, ``alpha``, ``light_px2`` (the light budget: weight × projected area),
    ``drawn_px2`` (what the quad carries: alpha × width × (length + h), h the drop's own chord along its path),
    ``length_px`` (length + h) and ``d_mm``."""
    d = sim.drops(index, time_s)
    head = d["pos"].copy()
    head[:, 2] -= cam.shift_z
    head[:, 2] -= PERIOD_M * np.round((head[:, 2] - cam.position[2]) / PERIOD_M)
    u = d["vel"]
    weight = np.where(d["visible"], d["weight"], 0.0)
    b_w = head - u * cam.exposure_s + cam.velocity * cam.exposure_s
    ca = np.c_[head, np.ones(len(head))] @ cam.view_proj.T
    cb = np.c_[b_w, np.ones(len(b_w))] @ cam.view_proj.T
    wmin = cam.near_m * 1.01
    visible = (weight > 0) & ~((ca[:, 3] < wmin) & (cb[:, 3] < wmin))
    with np.errstate(divide="ignore", invalid="ignore"):
        fa = np.where(ca[:, 3] < wmin, (wmin - ca[:, 3]) / (cb[:, 3] - ca[:, 3]), 0.0)[:, None]
        ca = np.where(fa > 0, ca + (cb - ca) * fa, ca)
        fb = np.where(cb[:, 3] < wmin, (wmin - cb[:, 3]) / (ca[:, 3] - cb[:, 3]), 0.0)[:, None]
        cb = np.where(fb > 0, cb + (ca - cb) * fb, cb)
        half = 0.5 * np.asarray(cam.viewport, dtype=np.float64)
        sa = ca[:, :2] / ca[:, 3:4] * half
        sb = cb[:, :2] / cb[:, 3:4] * half
    length = np.linalg.norm(sb - sa, axis=1)
    d_mm = d["d_mm"]
    d_px = d_mm * 1e-3 * cam.focal_px / ca[:, 3]
    area_f, width_f = drop_shape_factors(d_mm)
    light = np.pi / 4.0 * d_px**2 * area_f * weight * brightness
    h = np.pi / 4.0 * d_px * area_f / width_f  # the drop's mean chord along its motion (area / width)
    w = np.maximum(d_px * width_f, WIDTH_FLOOR_PX)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = streak_coverage(light, length, h, w)
        # Compensation (constants.SPREAD_ALPHA): longer along the motion up to STRETCH_MAX × the footprint, then
        # wider up to WIDTH_MAX_PX, then brighter.
        over = alpha > SPREAD_ALPHA
        need = light / SPREAD_ALPHA
        footprint = length + h
        stretched = np.clip(need / w, footprint, STRETCH_MAX * footprint)
        w = np.where(over, np.minimum(np.maximum(need / stretched, w), WIDTH_MAX_PX), w)
        footprint = np.where(over, stretched, footprint)
        alpha = np.where(over, np.minimum(light / (w * footprint), ALPHA_MAX), alpha)
    return {"visible": visible, "head": head, "tail": b_w, "head_px": sa, "tail_px": sb, "width_px": w,
            "alpha": alpha, "light_px2": light, "drawn_px2": alpha * w * footprint, "d_mm": d_mm,
            "length_px": footprint}
