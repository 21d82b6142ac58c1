"""Automatic exposure with eye adaptation: the float64 reference of the GPU meter (``rain_core.gfx.exposure``).

The hour's incident-light meter (``Lighting.ev100``) sets the exposure the HDR frame is rendered with: right for
an open street under the sky, but blind to where the camera looks. A driver's eye (and a camera on auto) meters
what it sees instead, and adapts over a second or two: a lamp-lit street at night reads, an underpass opens up
as the eye adapts, and it dims again on the way out.

The meter is a reflected-light meter (ISO 2720, calibration K = 12.5 cd·s/m², S = 100; Lagarde & de Rousiers,
"Moving Frostbite to PBR", 2014, §4.3): it maps the scene's average luminance to 12.5 / (1.2·100) ≈ 0.104 of
saturation, times 0.6, the input scale Narkowicz's ACES fit (the tone map) expects to match ACES: ``METER_KEY``
≈ 0.0625. The average is the geometric mean (the mean of log2 luminance: one
bright lamp must not dim the street), centre-weighted (a Gaussian on the road ahead, so the dark dashboard at the
frame's edge weighs little). The correction it asks for is relative to the hour's meter and limited to
``RANGE_EV`` stops: the eye does not make a dark night into day within seconds.

Adaptation is first order in EV: c ← c + (c* − c)·(1 − e^(−Δt/τ)), exact for any step, so no frame time can
overshoot. Every quantity is in stops (EV); luminances are pre-exposed (as in the HDR target).
"""

from __future__ import annotations

import math

import numpy as np

METER_KEY = 0.6 * 12.5 / (1.2 * 100.0)  # pre-exposed luminance the metered average maps to (K = 12.5, S = 100)
RANGE_EV = (-3.0, 3.0)  # stops the eye adapts beyond the hour's meter (darker, brighter)
METER_SIZE = (64, 32)  # texels (w, h) of the GPU meter; each averages 2×2 bilinear taps of the frame
METER_CENTRE = (0.5, 0.45)  # of the frame (u, v from the bottom): the road ahead, just below the horizon
METER_SIGMA = (0.3, 0.25)  # Gaussian width of the weight, as fractions of the frame's width and height
LOG2_FLOOR = -20.0  # log2 of the darkest luminance counted (a black pixel must not drive the mean to −∞)
_LUMA = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 luminance of linear RGB


def meter_taps(size=METER_SIZE) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) of every tap, each (h, w, 4): texel (i, j) of the meter samples the frame at
    ((i + (a + ½)/2)/w, (j + (b + ½)/2)/h) for a, b in {0, 1}; v counts from the bottom row as in GL."""
    w, h = size
    off = (np.arange(2) + 0.5) / 2.0
    u = (np.arange(w)[None, :, None, None] + off[None, None, :, None]) / w
    v = (np.arange(h)[:, None, None, None] + off[None, None, None, :]) / h
    u, v = np.broadcast_arrays(u, v)
    return u.reshape(h, w, 4), v.reshape(h, w, 4)


def meter_weights(size=METER_SIZE) -> np.ndarray:
    """Centre weight of each meter texel, (h, w), at the texel centre (exactly what the shader computes)."""
    w, h = size
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    du = (u[None, :] - METER_CENTRE[0]) / METER_SIGMA[0]
    dv = (v[:, None] - METER_CENTRE[1]) / METER_SIGMA[1]
    return np.exp(-0.5 * (du * du + dv * dv))


def _bilinear(image: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """GL LINEAR sampling with CLAMP_TO_EDGE of ``image`` (H, W, C), row 0 = the bottom row (v = 0)."""
    hgt, wid = image.shape[:2]
    x = np.clip(u * wid - 0.5, 0.0, wid - 1.0)
    y = np.clip(v * hgt - 0.5, 0.0, hgt - 1.0)
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    x1 = np.minimum(x0 + 1, wid - 1)
    y1 = np.minimum(y0 + 1, hgt - 1)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    top = image[y0, x0] * (1 - fx) + image[y0, x1] * fx
    bot = image[y1, x0] * (1 - fx) + image[y1, x1] * fx
    return top * (1 - fy) + bot * fy


def metered_log2_luminance(hdr: np.ndarray, size=METER_SIZE) -> float:
    """Centre-weighted mean of log2 luminance of a pre-exposed HDR frame (H, W, 3 linear RGB, top row first,
    as ``Renderer.hdr_image`` returns it), sampled as the GPU meter samples it. A tap that touches a NaN or inf
    pixel counts as black."""
    img = np.asarray(hdr, dtype=np.float64)[::-1, :, :3]  # bottom row first, as GL addresses it
    u, v = meter_taps(size)
    with np.errstate(invalid="ignore"):
        taps = _bilinear(img, u, v)  # a NaN or inf pixel spoils the taps that touch it, as on the GPU
    taps = np.where(np.isfinite(taps).all(axis=-1, keepdims=True), np.maximum(taps, 0.0), 0.0)
    lum = taps @ _LUMA
    log_lum = np.maximum(np.log2(np.maximum(lum, 2.0 ** LOG2_FLOOR)), LOG2_FLOOR).mean(axis=-1)
    weights = meter_weights(size)
    return float((weights * log_lum).sum() / weights.sum())


def target_correction_ev(mean_log2: float, compensation_ev: float = 0.0) -> float:
    """Stops (EV) to apply to the pre-exposed frame so its metered average reads ``METER_KEY``, plus the user's
    compensation, limited to ``RANGE_EV``."""
    wanted = math.log2(METER_KEY) - mean_log2 + compensation_ev
    return min(max(wanted, RANGE_EV[0]), RANGE_EV[1])


def adapt(current_ev: float, target_ev: float, dt_s: float, tau_s: float) -> float:
    """The eye's correction after ``dt_s`` (s) of adapting from ``current_ev`` towards ``target_ev`` with time
    constant ``tau_s`` (s). Exact for any step: never past the target, unchanged for dt_s = 0."""
    if dt_s <= 0.0:
        return current_ev
    return current_ev + (target_ev - current_ev) * -math.expm1(-dt_s / max(tau_s, 1e-6))
