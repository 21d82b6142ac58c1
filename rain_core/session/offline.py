"""Offline quality (``--quality offline``): N sub-frames across the shutter, averaged in linear light. GL-free.

A camera integrates light while its shutter is open; one rendered instant cannot show a wiper's sweep blurred
or edges anti-aliased. ``Session.step(dt_s, subframes=N)`` steps the simulation through the frame's shutter time
(``camera.exposure_s``, at most the frame interval, ending at the frame's time) in N equal sub-steps, rendering
each with the exposure set to its slice (the streaks' analytic motion blur then covers only that slice, so the
sum covers the shutter once) and averages the N pictures here. The average is taken of the tone-mapped sRGB
output converted to linear light: exact for light below the tone curve's shoulder, an approximation in
highlights (the renderer's HDR target is not accumulated).
"""

from __future__ import annotations

import numpy as np

MAX_SUBFRAMES = 256


def srgb_to_linear(rgb_u8: np.ndarray) -> np.ndarray:
    """uint8 sRGB → float64 linear [0, 1] (IEC 61966-2-1)."""
    c = np.asarray(rgb_u8, dtype=np.float64) / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(linear: np.ndarray) -> np.ndarray:
    """float linear [0, 1] → uint8 sRGB, rounded to nearest."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    c = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.rint(c * 255.0).astype(np.uint8)


class Accumulator:
    """Sum of sub-frame pictures in linear light; ``result()`` is their mean as uint8 sRGB."""

    def __init__(self):
        self.total: np.ndarray | None = None
        self.count = 0

    def add(self, rgb_u8: np.ndarray) -> None:
        lin = srgb_to_linear(rgb_u8)
        self.total = lin if self.total is None else self.total + lin
        self.count += 1

    def result(self) -> np.ndarray:
        if self.count == 0:
            raise ValueError("no sub-frame was added")
        return linear_to_srgb(self.total / self.count)


def check_subframes(subframes) -> int:
    if not isinstance(subframes, int | np.integer) or isinstance(subframes, bool) or not (
            1 <= subframes <= MAX_SUBFRAMES):
        raise ValueError(f"subframes must be an integer in [1, {MAX_SUBFRAMES}], got {subframes!r}")
    return int(subframes)
