"""Light scattered by the rain from lamps and headlights, in NumPy: the eye ray of every pixel from a depth buffer
(twin of ``shaders/common/depth.glsl``) and a dense single-scattering quadrature, the reference of the
composite pass (``shaders/atmosphere/composite.frag``). No GL.

The post pass traces the nearest lights per pixel up to the depth buffer (σ_s = β_m × the user's scale, the
medium's phase function ``model.phase_rain``), integrated with an equiangular substitution that is exact for the
1/r² peak; spot cones (headlights) show as beams.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.atmosphere.model import phase_rain

SCATTER_SAMPLES = 8  # quadrature nodes per light and pixel
SCATTER_MAX_M = 300.0  # m, where rays into the sky stop gathering light
# Exposed radiance (the tone map's input) that the lights a pixel skips may add up to, together: the composite
# pass skips a light whose bound on its quadrature fits in what is left. The display value (ACES fit, then sRGB)
# moves at most 6.4 per unit of exposed radiance (its steepest, near black), times 2^4 for the largest stops the
# tone map applies (the exposure's correction: ±3 EV automatic, ±4 EV compensation by hand): a quarter of an
# 8-bit step at most, so a skipped light changes no displayed pixel by more than rounding does.
SCATTER_SKIP = 0.25 / 255.0 / (6.4 * 2.0**4)
# On top of that, a share of the pixel's own light (what it keeps of its exposed radiance, its dimmest channel, the
# least of its glow block): the display value moves at most 72.9 8-bit steps per unit of relative change of
# exposed radiance (L·dV/dL of the ACES fit then sRGB, steepest at L ≈ 0.17; the exposure's stops scale L and leave
# it as it is). A quarter of a step again, less the half float's rounding of the stored light (2^-11).
SCATTER_SKIP_RELATIVE = 0.25 / 72.9 * (1.0 - 2.0**-10)


def _spot(light, to_light) -> np.ndarray:
    """Twin of spot_factor in shaders/common/lighting.glsl; to_light (…, 3) unit vectors towards the light."""
    if light.cos_outer <= -1.0:
        return np.ones(to_light.shape[:-1])
    x = np.clip((-(to_light @ light.direction) - light.cos_outer) / (light.cos_inner - light.cos_outer), 0.0, 1.0)
    f = x * x * (3.0 - 2.0 * x)
    if getattr(light, "low_beam", False):
        below_deg = np.degrees(np.arcsin(np.clip(to_light[..., 1], -1.0, 1.0)))
        f = f * np.exp(-np.maximum(below_deg - 1.5, 0.0) / 3.0)
    return f


def light_inscatter_reference(eye, view_dirs, t_max, light, extinction_per_m: float, scatter_per_m: float,
                              n: int = 20000) -> np.ndarray:
    """Single scattering (cd/m², RGB) from ``light`` (a rain_core.lighting.Light, position in the same frame as
    ``eye``, m) along unit ``view_dirs`` (…, 3) from ``eye`` up to ``t_max`` (…) m, by a dense midpoint rule in
    t (float64): ∫ σ_s·p·I·spot·window·exp(−β(t + r)) / r² dt, r clamped ≥ 0.15 m as in the shader."""
    v = np.asarray(view_dirs, dtype=np.float64)
    tm = np.broadcast_to(np.asarray(t_max, dtype=np.float64), v.shape[:-1])
    tm = np.minimum(tm, np.linalg.norm(light.position - eye) + light.range_m)  # nothing reaches further
    s = (np.arange(n) + 0.5) / n
    t = tm[..., None] * s  # (…, n)
    x = eye + v[..., None, :] * t[..., None]
    d = light.position - x
    r2 = np.maximum(np.sum(d * d, axis=-1), 0.15**2)
    r = np.sqrt(r2)
    lvec = d / r[..., None]
    window = np.clip(1.0 - (r2 / light.range_m**2) ** 2, 0.0, 1.0) ** 2
    spot = _spot(light, lvec)
    mu = np.sum(lvec * v[..., None, :], axis=-1)
    f = phase_rain(mu) * spot * window * np.exp(-extinction_per_m * (t + r)) / r2
    integral = f.mean(axis=-1) * tm * scatter_per_m
    return integral[..., None] * (np.asarray(light.color, dtype=np.float64) * light.intensity_cd)


def pixel_distances(depth, view_proj, eye, sky_m: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) and unit eye ray (wrapped frame) of every pixel of a depth buffer (H, W) in [0, 1], bottom
    row first as GL stores it, for the camera ``view_proj`` (4×4) at ``eye`` (m); sky pixels (depth 1) get sky_m.
    Twin of atmosphere_pixel_ray in shaders/common/depth.glsl."""
    depth = np.asarray(depth, dtype=np.float64)
    h, w = depth.shape
    x, y = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, (np.arange(h) + 0.5) / h * 2 - 1)
    sky = depth >= 1.0
    clip = np.stack([x, y, np.where(sky, 1.0, depth * 2 - 1), np.ones_like(x)], axis=-1)
    p = clip @ np.linalg.inv(np.asarray(view_proj, dtype=np.float64)).T
    d = p[..., :3] / p[..., 3:] - np.asarray(eye, dtype=np.float64)
    dist = np.linalg.norm(d, axis=-1)
    return np.where(sky, sky_m, dist), d / dist[..., None]
