"""What a falling drop shows: the geometric optics of a water sphere (Garg & Nayar 2004, "Photometric model of a
rain drop"; 2007, "Vision and Rain" §3), as a fixed quadrature that ``shaders/rainfall/env.frag`` sums over the
sky for every view direction (the GL twin of ``drop_environment`` below); and the coverage of a streak. NumPy
only, no GL.

A ray from the eye hits the drop's disc at impact parameter b = sin θi (uniform in b² over the disc's area) and
leaves towards the source direction s at an angle γ from the view direction v (eye → drop), the ray's total
deviation (geometric optics of a sphere, as in Garg & Nayar's drop model):

    p = 0 (specular reflection)        γ = π − 2θi                  weight F(θi)
    p = 1 (refraction, 2 surfaces)     γ = 2(θi − θt)               weight (1 − F)²
    p = 2 (one internal reflection)    γ = π + 2θi − 4θt            weight (1 − F)²·F

with sin θt = sin θi / n (n = 1.333) and F the unpolarised Fresnel reflectance. p = 1 spans γ ∈ [0°, 82.8°], the
drop's ~165° field of view: the drop is a fish-eye that shows, inverted, mostly what lies behind it (half of the
disc shows directions within 26° of v), and its rim brings in the sky. Summed over the disc the three terms
carry ``TOTAL_WEIGHT`` ≈ 0.99 of the light (the rest is higher orders): refraction 0.88, reflection 0.063,
internal reflection 0.045 (Garg & Nayar: the drop's field of view holds ~94 % of its light, reflection the rest).

The environment is the one the camera sees: the sky through the rain layer, as the sky pass draws it (so the
drops and the atmosphere's far rain share one sky), and the lit ground through the rain below a drop
``ENV_HEIGHT_M`` up. The drop's luminance is then L_d(v) = Σ_k w_k · L_env(rotate(v, γ_k, φ_k)), with the
azimuths φ_k on a golden-angle sequence (a fixed quasi-random sample, identical on the GPU and here). Against a
dark façade a drop shows the bright horizon just behind it and the sky in its rim, so it is brighter than what it
covers (Garg & Nayar: the intensity change a drop makes is positive, ΔI = τ/T·(E_d − E_b) > 0); against the
bright sky it is a little darker, i.e. faint.
"""

from __future__ import annotations

import math

import numpy as np

WATER_N = 1.333
N_REFRACT, N_REFLECT, N_INTERNAL = 40, 16, 8  # quadrature nodes per order (p = 1, 0, 2)
N_NODES = N_REFRACT + N_REFLECT + N_INTERNAL  # keep = RAIN_OPTIC_NODES in shaders/rainfall/env.frag
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))
ENV_HEIGHT_M = 1.5  # m: env.frag sees the ground through the rain below a drop this high (RAIN_ENV_HEIGHT_M)


def fresnel_unpolarised(cos_i, n: float = WATER_N):
    """Fresnel reflectance of unpolarised light from air onto water (exact, both polarisations averaged)."""
    c = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    ct = np.sqrt(np.maximum(1.0 - (s / n) ** 2, 0.0))
    rs = (c - n * ct) / (c + n * ct)
    rp = (n * c - ct) / (n * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def _order(p: int, count: int, offset: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    b = np.sqrt((np.arange(count) + 0.5) / count)  # midpoints in disc area
    theta_i = np.arcsin(b)
    theta_t = np.arcsin(b / WATER_N)
    f = fresnel_unpolarised(np.cos(theta_i))
    if p == 0:
        gamma, w = math.pi - 2.0 * theta_i, f
    elif p == 1:
        gamma, w = 2.0 * (theta_i - theta_t), (1.0 - f) ** 2
    else:
        gamma, w = math.pi + 2.0 * theta_i - 4.0 * theta_t, (1.0 - f) ** 2 * f
    gamma = np.abs(np.mod(gamma + math.pi, 2.0 * math.pi) - math.pi)  # a deviation folded into [0, π]
    phi = np.mod(offset + GOLDEN_ANGLE * np.arange(count), 2.0 * math.pi)
    return gamma, phi, w / count


def drop_optics() -> np.ndarray:
    """The quadrature, (N_NODES, 4) float64: cos γ, sin γ, φ (rad), weight — refraction, reflection, internal."""
    rows = [np.stack(_order(p, n, off), axis=1) for p, n, off in ((1, N_REFRACT, 0.0), (0, N_REFLECT, 0.5),
                                                                  (2, N_INTERNAL, 1.0))]
    g = np.concatenate(rows)
    return np.stack([np.cos(g[:, 0]), np.sin(g[:, 0]), g[:, 1], g[:, 2]], axis=1)


OPTICS = drop_optics()
TOTAL_WEIGHT = float(OPTICS[:, 3].sum())
REFRACT_WEIGHT = float(OPTICS[:N_REFRACT, 3].sum())
REFLECT_WEIGHT = float(OPTICS[N_REFRACT:N_REFRACT + N_REFLECT, 3].sum())


def optics_uniforms() -> dict:
    """The env.frag uniforms: u_optic_dir (cos γ, sin γ, cos φ, sin φ) and u_optic_w, float32."""
    o = OPTICS
    dirs = np.stack([o[:, 0], o[:, 1], np.cos(o[:, 2]), np.sin(o[:, 2])], axis=1).astype(np.float32)
    return {"u_optic_dir": dirs, "u_optic_w": o[:, 3].astype(np.float32)}


def _basis(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (a, b) frame env.frag builds around d (same helper axis, same order)."""
    helper = np.where((np.abs(d[..., 1]) < 0.95)[..., None], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    a = np.cross(d, helper)
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    return a, np.cross(a, d)


def sample_directions(view_dirs) -> np.ndarray:
    """(…, N_NODES, 3) unit source directions the quadrature reads for unit view directions (…, 3)."""
    d = np.asarray(view_dirs, dtype=np.float64)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    a, b = _basis(d)
    o = optics_uniforms()["u_optic_dir"].astype(np.float64)
    c, s, cp, sp = (o[:, i] for i in range(4))
    out = (d[..., None, :] * c[:, None] + (a[..., None, :] * cp[:, None] + b[..., None, :] * sp[:, None])
           * s[:, None])
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def drop_environment(view_dirs, env) -> np.ndarray:
    """Luminance (…, 3) of a drop seen along unit view_dirs (eye → drop), float64, for an environment
    ``env(dirs (…, 3)) -> radiance (…, 3)``: the twin of rainfall/env.frag's texels."""
    w = optics_uniforms()["u_optic_w"].astype(np.float64)
    return np.einsum("...kc,k->...c", env(sample_directions(view_dirs)), w)


def streak_coverage(light_px2, length_px, height_px, width_px):
    """Opacity of a streak (the fraction of each pixel it covers, averaged over the exposure), for a drop whose
    projected area × weight is ``light_px2`` (px²), moving ``length_px`` during the exposure, ``height_px`` its
    mean chord along the motion (area / width) and ``width_px`` the drawn width (≥ the 1 px floor).

    The drop covers area A of the image plane at each instant; a pixel on its path is covered for the fraction
    τ/T of the exposure in which the drop is over it, so the pixel's mean coverage is A·(τ/T)/(pixel area), and
    the streak's footprint is width × (length + height): α = A / (w·(ℓ + h)). Its integral over the image is A
    whatever the motion (light is conserved). Twin of the streak record's formula
    (shaders/rainfall/streak_record.vert)."""
    return np.asarray(light_px2, dtype=np.float64) / (np.asarray(width_px) * (np.asarray(length_px)
                                                                            + np.asarray(height_px)))
