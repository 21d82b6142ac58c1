"""The glow around lights in mist, in NumPy: the blur kernel the post pass uses and the full-resolution reference
the shaders (``shaders/atmosphere/glow_down.frag``, ``blur.frag``, ``composite.frag``) are tested against. No GL.

A pixel at distance d loses 1 − exp(−β_m·d) of its light to scattering; the share ``GLOW_SHARE``·glow of that
reaches the eye from nearby directions. So: c·w box-downsampled to the glow resolution, Gaussian-blurred with an
angular σ that widens with β_m (``model.glow_sigma_rad``: multiple scattering broadens the atmospheric
point-spread function), and blended back as hdr·(1 − k·w) + k·blur(c·w) (k at most 1/w, so no pixel loses more
than its own light): a uniform region is unchanged, bright lights spread into mist.
"""

from __future__ import annotations

import math

import numpy as np

MAX_BLUR_RADIUS = 128  # taps each side of one blur direction (σ is capped at a third of it)


def blur_radius(sigma_px: float) -> int:
    """Taps each side of the blur for σ (texels): ⌈3σ⌉, at most MAX_BLUR_RADIUS."""
    return int(min(MAX_BLUR_RADIUS, max(1, math.ceil(3.0 * sigma_px))))


def gaussian_weights(sigma_px: float) -> np.ndarray:
    """The blur's normalised discrete Gaussian (taps −r … r, r = blur_radius(σ)); σ in texels."""
    r = blur_radius(sigma_px)
    k = np.arange(-r, r + 1, dtype=np.float64)
    w = np.exp(-0.5 * k * k / max(sigma_px * sigma_px, 1e-6))
    return w / w.sum()


def glow_reference(color, weight, strength: float, sigma_px: float) -> np.ndarray:
    """The glow at full resolution in NumPy: color·(1 − k·w) + k·G_σ * (color·w), edges clamped.

    color (H, W, 3) pre-exposed HDR; weight (H, W) the scattered share w = 1 − exp(−β_m·d); σ in pixels.
    k is capped per pixel at 1/w (as in composite.frag): the halo never takes more than a pixel's own light, so
    the result stays ≥ 0 for a glow above 2 in dense rain."""
    c = np.asarray(color, dtype=np.float64)
    w = np.asarray(weight, dtype=np.float64)[..., None]
    src = c * w
    g = gaussian_weights(sigma_px)
    r = (len(g) - 1) // 2
    for axis in (1, 0):
        pad = [(0, 0)] * 3
        pad[axis] = (r, r)
        p = np.pad(src, pad, mode="edge")
        n = src.shape[axis]
        src = sum(g[i] * np.take(p, np.arange(i, i + n), axis=axis) for i in range(len(g)))
    k = np.minimum(strength, 1.0 / np.maximum(w, 1e-6))
    return c * (1.0 - k * w) + k * src
