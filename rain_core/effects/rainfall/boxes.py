"""The container: nested axis-aligned boxes (layers) that follow the camera, their fade-in membership and the
drawn density a drop's weight divides by (package docstring, "Container")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core.effects.rainfall.constants import (
    BOX_BOTTOM_Y_M,
    EYE_ALLOWANCE_M,
    FADE_FRACTION,
    FORWARD_OFFSET,
    GROUND_Y_M,
    LAYER_PROFILE,
    LAYER_SCALES,
    PERIOD_M,
    TOP_PAD_M,
    TOP_SLOPE,
)


@dataclass
class Boxes:
    """The layers' boxes: lo, hi (L, 3) in world coordinates (m), fade (L, 3) widths (m) at the sides and the top,
    profile ν (L,), fade_bottom (L,) width (m) of the bottom's fade (0: a hard floor below the ground)."""

    lo: np.ndarray
    hi: np.ndarray
    fade: np.ndarray
    nu: np.ndarray
    fade_bottom: np.ndarray | None = None

    def __post_init__(self):
        if self.fade_bottom is None:
            self.fade_bottom = np.zeros(len(self.nu))

    @property
    def ext(self) -> np.ndarray:
        """(L, 3) box sizes (m): the periods of the drops' wrap."""
        return self.hi - self.lo

    def shifted_z(self, dz: float) -> Boxes:
        """The same boxes moved by dz (m) along z (e.g. into the renderer's wrapped frame)."""
        d = np.array([0.0, 0.0, dz])
        return Boxes(self.lo + d, self.hi + d, self.fade, self.nu, self.fade_bottom)

    @property
    def volumes(self) -> np.ndarray:
        return np.prod(self.hi - self.lo, axis=1)


def box_heights(container_m: float) -> np.ndarray:
    """(L,) fixed heights (m) of the layers' boxes: from BOX_BOTTOM_Y_M to TOP_SLOPE × half-size + TOP_PAD_M above
    an eye EYE_ALLOWANCE_M high. Fixed, since a box's height is its drops' vertical period."""
    h = 0.5 * float(container_m) * np.asarray(LAYER_SCALES)
    return EYE_ALLOWANCE_M + TOP_SLOPE * h + TOP_PAD_M - BOX_BOTTOM_Y_M


def layer_boxes(camera_position, camera_forward, container_m: float) -> Boxes:
    """The container's nested boxes (m, world) for a camera at camera_position looking along camera_forward.

    container_m: horizontal size (m) of the outer box. Each box is centred FORWARD_OFFSET half-sizes ahead of the
    camera along the horizontal view direction (scaled by its horizontal share, so a camera looking straight
    down sits at the centre). Heights are fixed (``box_heights``): a box reaches from just below the ground
    unless the eye is higher than EYE_ALLOWANCE_M, when it slides up and its bottom fades in."""
    # Every frame, four layers: in Python floats, the same float64 operations in the same order as the array
    # form (tests/effects/rainfall/test_cpu_paths.py keeps that form as the oracle); fade and ν depend on
    # container_m alone and are shared, read-only, between frames.
    cx, cy, cz = np.asarray(camera_position, dtype=np.float64).tolist()  # float() of each, in one call
    f0, _, f2 = np.asarray(camera_forward, dtype=np.float64).tolist()
    n = _horizontal_length(f0, f2)
    fx, fz = (f0 / n, f2 / n) if n > 1e-9 else (0.0, 0.0)
    reach = min(n, 1.0)
    shape = _layer_shape(float(container_m))
    eye = max(cy, GROUND_Y_M)
    lo, hi, fade_bottom = [], [], []
    for h, height, ff_height in shape.rows:
        s = FORWARD_OFFSET * h * reach
        x, z = cx + fx * s, cz + fz * s
        top = max(BOX_BOTTOM_Y_M + height, eye + TOP_SLOPE * h + TOP_PAD_M)
        bottom = top - height
        lo.append((x - h, bottom, z - h))
        hi.append((x + h, top, z + h))
        fade_bottom.append(min(bottom - BOX_BOTTOM_Y_M, ff_height))
    return Boxes(np.array(lo), np.array(hi), shape.fade, shape.nu, np.array(fade_bottom))


_HYPOT = (None, None, 0.0)  # the last (f0, f2) and np.hypot of it: a camera driving straight keeps its forward


def _horizontal_length(f0: float, f2: float) -> float:
    # np.hypot as before (math.hypot is another algorithm: it may differ in the last bit), once per forward. The
    # entry is one tuple, read once and replaced whole, so scenes stepping in two threads never mix two entries.
    global _HYPOT
    last = _HYPOT
    if last[0] != f0 or last[1] != f2:
        last = _HYPOT = (f0, f2, float(np.hypot(f0, f2)))
    return last[2]


class _LayerShape:
    """What the boxes of one container size share: per layer (half-size, height, top fade) as floats, and the
    fade (L, 3) and profile ν (L,) arrays (read-only: every frame's Boxes holds them)."""

    __slots__ = ("container_m", "rows", "fade", "nu")

    def __init__(self, container_m: float):
        h = 0.5 * container_m * np.asarray(LAYER_SCALES)
        height = box_heights(container_m)
        self.container_m = container_m
        self.rows = tuple(zip(h.tolist(), height.tolist(), (FADE_FRACTION * height).tolist(), strict=True))
        self.fade = np.stack([FADE_FRACTION * h, FADE_FRACTION * height, FADE_FRACTION * h], axis=1)
        self.nu = np.asarray(LAYER_PROFILE, dtype=np.float64)
        self.fade.flags.writeable = self.nu.flags.writeable = False


_SHAPE: _LayerShape | None = None  # the last container size's (it changes only in the settings panel)


def _layer_shape(container_m: float) -> _LayerShape:
    global _SHAPE
    shape = _SHAPE  # read once (see _horizontal_length)
    if shape is None or shape.container_m != container_m:
        shape = _SHAPE = _LayerShape(container_m)
    return shape


def wrap_near(z, around_z):
    """z (m) shifted by whole periods to lie within half a period of around_z (m)."""
    if type(z) is float:  # one position (the vehicles' uniforms, every frame), without NumPy
        q = (z - around_z) / PERIOD_M
        if math.isfinite(q):  # Python's round, like np.round, rounds halves to even
            return z - PERIOD_M * round(q)
    return z - PERIOD_M * np.round((np.asarray(z) - around_z) / PERIOD_M)


def membership(p, boxes: Boxes, layer) -> np.ndarray:
    """Fade-in factor in [0, 1] of points p (n, 3) in the boxes of their layers (n,): linear ramps over the fade
    widths at the sides and the top; at the bottom a hard floor below the ground (the ground ends the drops), or
    a ramp over ``fade_bottom`` when the box has slid up. Mirrors the shader (``rain_membership``)."""
    layer = np.asarray(layer)
    lo, hi, fade = boxes.lo[layer], boxes.hi[layer], boxes.fade[layer]
    a = np.clip((p - lo) / fade, 0.0, 1.0)
    b = np.clip((hi - p) / fade, 0.0, 1.0)
    fb = boxes.fade_bottom[layer]
    with np.errstate(divide="ignore", invalid="ignore"):
        ramp = np.clip((p[:, 1] - lo[:, 1]) / np.where(fb > 0, fb, 1.0), 0.0, 1.0)
    a[:, 1] = np.where(fb > 0, ramp, (p[:, 1] >= lo[:, 1]).astype(np.float64))
    return np.prod(a, axis=1) * np.prod(b, axis=1)


def drawn_density_factor(p, boxes: Boxes, density=None) -> np.ndarray:
    """max(Σ_k ρ_k·m_k(p), ρ_outer) at points p (n, 3), with ρ = density (L,) (default the profile ν): the drawn
    density a weight divides by."""
    p = np.atleast_2d(p)
    rho = boxes.nu if density is None else np.asarray(density, dtype=np.float64)
    total = np.zeros(len(p))
    for k in range(len(rho)):
        total += rho[k] * membership(p, boxes, np.full(len(p), k))
    return np.maximum(total, rho[-1])


def full_region(boxes: Boxes, layer: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """The part of a layer's box (default the outer one) where no fade applies (m, world): lo, hi."""
    lo = boxes.lo[layer] + boxes.fade[layer] * np.array([1.0, 0.0, 1.0])
    hi = boxes.hi[layer] - boxes.fade[layer]
    lo = lo.copy()
    lo[1] = GROUND_Y_M
    return lo, hi
