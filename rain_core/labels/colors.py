"""False colours for looking at label images (sheets, previews): uint8 (H, W, 3) sRGB. GL-free."""

from __future__ import annotations

import numpy as np

from rain_core.labels.classes import CLASS_COLORS, CLASS_IDS
from rain_core.labels.images import ROAD_WATER_IDS

# Road water: as the road's debug view (rain_core.effects.road.surface.REGION_COLORS, in sRGB), black off the road.
ROAD_WATER_COLORS: dict[str, tuple[int, int, int]] = {"dry": (194, 179, 137), "wet": (108, 194, 108),
                                                      "drenched": (250, 179, 64), "puddle": (89, 149, 255),
                                                      "not_road": (0, 0, 0)}
# A perceptually ordered ramp (dark blue → teal → yellow) for depth and the 0..1 masks.
_RAMP = np.array([(13, 8, 135), (84, 2, 163), (139, 10, 165), (185, 50, 137), (219, 92, 104), (244, 136, 73),
                  (254, 188, 43), (240, 249, 33)], np.float64)
DEPTH_RANGE_M = (1.0, 1000.0)  # the depth colours run logarithmically over this; sky is black


def ramp(t) -> np.ndarray:
    """uint8 RGB of the ramp at t in [0, 1] (clipped)."""
    t = np.clip(np.asarray(t, np.float64), 0.0, 1.0) * (len(_RAMP) - 1)
    i = np.minimum(np.floor(t).astype(int), len(_RAMP) - 2)
    f = (t - i)[..., None]
    return np.rint(_RAMP[i] * (1.0 - f) + _RAMP[i + 1] * f).astype(np.uint8)


def depth_colors(depth_m: np.ndarray) -> np.ndarray:
    lo, hi = DEPTH_RANGE_M
    finite = np.isfinite(depth_m)
    t = np.log(np.clip(np.where(finite, depth_m, hi), lo, hi) / lo) / np.log(hi / lo)
    return np.where(finite[..., None], ramp(t), np.uint8(0))


def mask_colors(mask: np.ndarray) -> np.ndarray:
    """A 0..1 mask: black where 0, then the ramp."""
    return np.where((mask > 0.0)[..., None], ramp(mask), np.uint8(0))


def _lookup(ids: np.ndarray, table: dict[int, tuple[int, int, int]]) -> np.ndarray:
    lut = np.zeros((256, 3), np.uint8)
    for i, rgb in table.items():
        lut[i] = rgb
    return lut[ids]


def class_colors(classes: np.ndarray) -> np.ndarray:
    return _lookup(classes, {CLASS_IDS[name]: rgb for name, rgb in CLASS_COLORS.items()})


def road_water_colors(road_water: np.ndarray) -> np.ndarray:
    return _lookup(road_water, {ROAD_WATER_IDS[name]: rgb for name, rgb in ROAD_WATER_COLORS.items()})
