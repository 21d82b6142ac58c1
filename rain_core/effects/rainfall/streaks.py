"""The NumPy twin of the streak shader (``shaders/rainfall/streak.vert``): what the camera sees of each drop, in
float64, for tests and the benchmark's light budget. Keep the two in step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rain_core.effects.rainfall.boxes import Boxes, drawn_density_factor, membership
from rain_core.effects.rainfall.constants import ALPHA_MAX, PERIOD_M, TIME_PERIOD_S, WIDTH_FLOOR_PX, WIDTH_MAX_PX
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


def streak_geometry(sim: RainfallSim, slots, time_s: float, cam: StreakCamera, boxes: Boxes,
                    brightness: float = 1.0) -> dict[str, np.ndarray]:
    """The streaks of ``slots`` as ``shaders/rainfall/streak.vert`` draws them, in float64.

    Returns arrays: ``visible`` (bool), ``head``/``tail`` (n, 3) m in the wrapped frame (the drop now, and where
    it was relative to the camera when the shutter opened), ``head_px``/``tail_px`` (n, 2) px from the image
    centre (y up), ``width_px``, ``alpha``, ``light_px2`` (the light budget: weight × projected area) and
    ``drawn_px2`` (what the quad carries: alpha × width × (length + width))."""
    slots = np.asarray(slots)
    tex = sim.texels(slots).astype(np.float64)
    s0, s1, s2 = tex[:, 0], tex[:, 1], tex[:, 2]
    age = np.mod(np.float32(np.mod(time_s, TIME_PERIOD_S)) - s0[:, 3], TIME_PERIOD_S)
    age = np.where(age > 0.5 * TIME_PERIOD_S, 0.0, age)
    life = s1[:, 3]
    cam_z = cam.position[2]
    p0 = np.stack([s0[:, 0], s0[:, 1], s0[:, 2] - PERIOD_M * np.floor((s0[:, 2] - cam_z) / PERIOD_M + 0.5)], axis=1)
    u = s1[:, :3]
    age_head = np.minimum(age, life)
    head = p0 + u * age_head[:, None]
    wrapped = Boxes(boxes.lo - [0.0, 0.0, cam.shift_z], boxes.hi - [0.0, 0.0, cam.shift_z], boxes.fade, boxes.nu)
    layer = (s2[:, 2] + 0.5).astype(np.int64)
    weight = s2[:, 1] * membership(head, wrapped, layer) / drawn_density_factor(head, wrapped)
    a_w = head + cam.velocity * (age - age_head)[:, None]
    b_w = p0 + u * (age - cam.exposure_s)[:, None] + cam.velocity * cam.exposure_s
    ca = np.c_[a_w, np.ones(len(a_w))] @ cam.view_proj.T
    cb = np.c_[b_w, np.ones(len(b_w))] @ cam.view_proj.T
    wmin = cam.near_m * 1.01
    visible = (life > 0) & (age - cam.exposure_s <= life) & (weight > 0) & ~((ca[:, 3] < wmin) & (cb[:, 3] < wmin))
    with np.errstate(divide="ignore", invalid="ignore"):
        fa = np.where(ca[:, 3] < wmin, (wmin - ca[:, 3]) / (cb[:, 3] - ca[:, 3]), 0.0)[:, None]
        ca = np.where(fa > 0, ca + (cb - ca) * fa, ca)
        fb = np.where(cb[:, 3] < wmin, (wmin - cb[:, 3]) / (ca[:, 3] - cb[:, 3]), 0.0)[:, None]
        cb = np.where(fb > 0, cb + (ca - cb) * fb, cb)
        half = 0.5 * np.asarray(cam.viewport, dtype=np.float64)
        sa = ca[:, :2] / ca[:, 3:4] * half
        sb = cb[:, :2] / cb[:, 3:4] * half
    length = np.linalg.norm(sb - sa, axis=1)
    d_px = s2[:, 0] * 1e-3 * cam.focal_px / ca[:, 3]
    area_f, width_f = drop_shape_factors(s2[:, 0])
    light = np.pi / 4.0 * d_px**2 * area_f * weight * brightness
    w = np.maximum(d_px * width_f, WIDTH_FLOOR_PX)
    alpha = light / (w * (length + w))
    over = alpha > ALPHA_MAX
    wide = 0.5 * (-length + np.sqrt(length**2 + 4.0 * light / ALPHA_MAX))
    w = np.where(over, np.minimum(np.maximum(wide, w), WIDTH_MAX_PX), w)
    alpha = np.where(over, np.minimum(light / (w * (length + w)), ALPHA_MAX), alpha)
    return {"visible": visible, "head": head, "tail": b_w, "head_px": sa, "tail_px": sb, "width_px": w,
            "alpha": alpha, "light_px2": light, "drawn_px2": alpha * w * (length + w)}
