"""The rainbow's optics, float64 NumPy (no GL): how much of the sunlight a rain medium extinguishes is scattered
into each angle around the antisolar point, as linear RGB.

The model, step by step (each step is a function below, tested on its own):

1. Water's refractive index n(λ): Quan & Fry (1995, Appl. Opt. 34(18)), fresh water at 20 °C.
2. Rays through a sphere with k internal reflections (k = 1 primary, k = 2 secondary) deviate by
   D(b) = 2(i − r) + k(π − 2r), sin i = b (impact parameter / radius), sin r = b/n. The rainbow ray is the
   stationary one, cos² i = (n² − 1)/(k(k + 2)) (Descartes); near it D ≈ D_R + h(b − b_R)², h = D''(b_R)/2.
3. Airy's theory of the rainbow (Airy 1838; in the semi-classical form of Nussenzveig 1992, "Diffraction effects
   in semiclassical scattering"): the phase of the ray with impact b is x·∫(D(b) − D)db (x = πd/λ, the size
   parameter), so near the rainbow angle the amplitude is an Airy function and
       dσ/dΩ(ε) = d² · G · 2π · √s · Ai²(−s·ε),   s = x^(2/3) / h^(1/3),
   where ε = D − D_R (rad) and G = b_R·T/(4·√h·|sin D_R|) is the geometric-optics intensity constant (Fresnel
   transmissions T averaged over the two polarisations). The prefactor makes the Airy intensity average to the
   geometric-optics caustic d²·G/√ε on the lit side: Ai²(−z) ~ 1/(2π√z) there.
4. Drop sizes: Marshall–Palmer (rain_core.physics), weighting each size by N(D)·D². The result is divided by the
   medium's extinction β = ∫N(D)·2·πD²/4 dD (extinction efficiency 2), so it is a phase function in 1/sr: the
   radiance of a rain column of optical depth τ lit by sun illuminance E is L = E·P(θ)·(1 − e^−τ) (single
   scattering; the sun's own dimming by the rain is left to the lighting's overcast).
5. Colour: P(θ, λ) integrated with the CIE 1931 colour-matching functions (the multi-lobe fit of Wyman, Sloan &
   Shirley 2013, JCGT 2(2)) → XYZ → linear sRGB, each channel normalised so a spectrally flat P is grey: the
   renderer multiplies by the sun's RGB illuminance, which already carries the sun's colour.
6. The sun is a disc of 0.53°: the bow is convolved with it.

θ is the angle from the antisolar point: θ = π − D for the primary (≈ 42°, red outside), θ = D − π for the
secondary (≈ 51°, colours reversed), and between them Alexander's dark band, where neither order sends light.
Large drops are oblate in reality, which flattens the top of the bow; the spheres here do not show that.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import physics

SUN_RADIUS_RAD = math.radians(0.2666)  # the sun's angular radius
WAVELENGTHS_NM = np.arange(380.0, 781.0, 20.0)  # 20 nm: 0.6 % of the peak from a 2 nm table (bench rainbow)
THETA_RANGE_DEG = (30.0, 62.0)  # the LUT's span of angles from the antisolar point
_XYZ_TO_SRGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])


def water_refractive_index(wavelength_nm, temperature_c: float = 20.0):
    """n of fresh water at ``wavelength_nm`` (nm, 400–700 fitted) and temperature (°C): Quan & Fry (1995), S = 0."""
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    t = float(temperature_c)
    return (1.31405 - 2.02e-6 * t * t + (15.868 - 0.00423 * t) / lam - 4382.0 / lam**2 + 1.1455e6 / lam**3)


# --- Airy function ------------------------------------------------------------------------------------------

_AI0 = 0.355028053887817239  # Ai(0)
_AIP0 = 0.258819403792806798  # −Ai'(0)


def airy_ai(z):
    """Ai(z) for real z, float64: the Maclaurin series for −8 ≤ z ≤ 4, the first terms of the asymptotic
    expansions beyond (DLMF §9.4, §9.7); |error| < 5e-6 everywhere (largest where the two meet at z = −8)."""
    z = np.asarray(z, dtype=np.float64)
    out = np.empty_like(z)
    mid = (z >= -8.0) & (z <= 4.0)
    if mid.any():
        zm = z[mid]
        z3 = zm**3
        f = np.ones_like(zm)
        g = zm.copy()
        tf, tg = np.ones_like(zm), zm.copy()
        for k in range(1, 60):
            tf = tf * z3 / ((3 * k - 1) * (3 * k))
            tg = tg * z3 / ((3 * k) * (3 * k + 1))
            f += tf
            g += tg
        out[mid] = _AI0 * f - _AIP0 * g
    neg = z < -8.0
    if neg.any():
        x = -z[neg]
        zeta = (2.0 / 3.0) * x**1.5
        # Ai(−x) = π^−½ x^−¼ [sin(ζ + π/4) P − cos(ζ + π/4) Q], P ≈ 1 − u2/ζ², Q ≈ u1/ζ (DLMF 9.7.9).
        u1, u2 = 5.0 / 72.0, 385.0 / 10368.0
        p = 1.0 - u2 / zeta**2
        q = u1 / zeta
        out[neg] = (np.sin(zeta + math.pi / 4) * p - np.cos(zeta + math.pi / 4) * q) / (math.sqrt(math.pi) * x**0.25)
    pos = z > 4.0
    if pos.any():
        x = z[pos]
        zeta = (2.0 / 3.0) * x**1.5
        out[pos] = np.exp(-zeta) / (2.0 * math.sqrt(math.pi) * x**0.25) * (1.0 - (5.0 / 72.0) / zeta)
    return out


# --- one drop -------------------------------------------------------------------------------------------------

def deviation_rad(b, n, k: int):
    """Total deviation D (rad) of the ray entering at impact parameter b (0–1) with k internal reflections."""
    b = np.asarray(b, dtype=np.float64)
    i = np.arcsin(b)
    r = np.arcsin(b / n)
    return 2.0 * (i - r) + k * (math.pi - 2.0 * r)


def rainbow_ray(n, k: int):
    """(b_R, D_R rad, h): the stationary (Descartes) ray of order k and the curvature of D(b) there."""
    n = np.asarray(n, dtype=np.float64)
    cos_i = np.sqrt((n * n - 1.0) / (k * (k + 2)))
    b = np.sqrt(1.0 - cos_i**2)
    d_r = deviation_rad(b, n, k)
    # D''(b) in closed form: d/db asin(b) = (1 − b²)^−½, so D'' = 2b(1 − b²)^−3/2 − 2(k + 1)·b/n³·(1 − b²/n²)^−3/2.
    d2 = 2.0 * b * (1.0 - b * b) ** -1.5 - 2.0 * (k + 1) * b / n**3 * (1.0 - (b / n) ** 2) ** -1.5
    return b, d_r, 0.5 * d2


def rainbow_angle_deg(wavelength_nm, k: int = 1):
    """The geometric-optics rainbow angle (deg) from the antisolar point: ≈ 42° (k = 1), ≈ 51° (k = 2)."""
    _, d_r, _ = rainbow_ray(water_refractive_index(wavelength_nm), k)
    return np.degrees(math.pi - d_r if k == 1 else d_r - math.pi) if np.ndim(d_r) == 0 else \
        np.degrees(np.where(k == 1, math.pi - d_r, d_r - math.pi))


def _fresnel(cos_i, n1, n2):
    """(R_s, R_p): Fresnel reflectances from medium n1 into n2 at incidence cosine cos_i."""
    sin_t = n1 / n2 * np.sqrt(np.maximum(1.0 - cos_i**2, 0.0))
    cos_t = np.sqrt(np.maximum(1.0 - sin_t**2, 0.0))
    rs = ((n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)) ** 2
    rp = ((n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)) ** 2
    return rs, rp


def rainbow_transmission(n, k: int):
    """T: the share of a rainbow ray's power that leaves after k internal reflections, averaged over the s and p
    polarisations: ½Σ (1 − R(i))·R(r)^k·(1 − R(r))."""
    b, _, _ = rainbow_ray(n, k)
    cos_i = np.sqrt(1.0 - b * b)
    rs_out, rp_out = _fresnel(cos_i, 1.0, n)
    cos_r = np.sqrt(1.0 - (b / n) ** 2)
    rs_in, rp_in = _fresnel(cos_r, n, 1.0)
    ts = (1.0 - rs_out) * rs_in**k * (1.0 - rs_in)
    tp = (1.0 - rp_out) * rp_in**k * (1.0 - rp_in)
    return 0.5 * (ts + tp)


def drop_cross_section_sr(theta_rad, diameter_mm, wavelength_nm, k: int):
    """dσ/dΩ (mm²/sr) of one drop of diameter_mm into the angle theta_rad from the antisolar point, order k only
    (Airy theory, see the module docstring). Broadcasts over its three inputs."""
    theta = np.asarray(theta_rad, dtype=np.float64)
    d = np.asarray(diameter_mm, dtype=np.float64)
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    n = water_refractive_index(lam)
    b, d_r, h = rainbow_ray(n, k)
    deviation = math.pi - theta if k == 1 else math.pi + theta
    eps = deviation - d_r
    x = math.pi * d * 1e6 / lam  # size parameter (d in nm / λ in nm)
    s = x ** (2.0 / 3.0) / np.cbrt(h)
    g = b * rainbow_transmission(n, k) / (4.0 * np.sqrt(h) * np.abs(np.sin(d_r)))
    return d * d * g * 2.0 * math.pi * np.sqrt(s) * airy_ai(-s * eps) ** 2


# --- colour ----------------------------------------------------------------------------------------------------

def _lobe(lam, mu, s1, s2):
    return np.exp(-0.5 * ((lam - mu) / np.where(lam < mu, s1, s2)) ** 2)


def cie_xyz_bar(wavelength_nm):
    """CIE 1931 2° colour-matching functions x̄, ȳ, z̄ (N, 3): Wyman, Sloan & Shirley (2013) multi-lobe fit."""
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    x = 1.056 * _lobe(lam, 599.8, 37.9, 31.0) + 0.362 * _lobe(lam, 442.0, 16.0, 26.7) \
        - 0.065 * _lobe(lam, 501.1, 20.4, 26.2)
    y = 0.821 * _lobe(lam, 568.8, 46.9, 40.5) + 0.286 * _lobe(lam, 530.9, 16.3, 31.1)
    z = 1.217 * _lobe(lam, 437.0, 11.8, 36.0) + 0.681 * _lobe(lam, 459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=-1)


def rgb_weights(wavelength_nm):
    """(N, 3) weights: Σ_λ P(λ)·w(λ) is P's linear-sRGB colour, each channel normalised so a flat P gives P·(1,1,1)."""
    rgb = cie_xyz_bar(wavelength_nm) @ _XYZ_TO_SRGB.T
    return rgb / rgb.sum(axis=0)


# --- the medium ------------------------------------------------------------------------------------------------

def _size_weights(rate_mm_h: float, nodes: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Drop diameters (mm) and weights ∝ N(D)·D²·ΔD (Marshall–Palmer at rate_mm_h, mm/h), normalised to 1."""
    d = np.geomspace(0.1, 6.0, nodes)
    widths = np.gradient(d)
    w = np.asarray(physics.marshall_palmer(d, rate_mm_h), dtype=np.float64) * d * d * widths
    return d, w / w.sum()


def bow_phase_rgb(theta_rad, rate_mm_h: float, orders=(1, 2), wavelengths_nm=WAVELENGTHS_NM,
                  size_nodes: int = 32):
    """P(θ) (1/sr, (N, 3) linear sRGB): the share of the light a rain medium at rate_mm_h (mm/h) extinguishes that
    its drops scatter per steradian into the angle θ (rad) from the antisolar point, summed over ``orders``
    (1 primary, 2 secondary). Not convolved with the sun's disc (see ``bow_lut``)."""
    if not (math.isfinite(rate_mm_h) and rate_mm_h > 0.0):
        raise ValueError(f"rate_mm_h must be > 0 mm/h, got {rate_mm_h}")
    theta = np.atleast_1d(np.asarray(theta_rad, dtype=np.float64))
    diam, w = _size_weights(rate_mm_h, size_nodes)
    weights = rgb_weights(wavelengths_nm)
    out = np.zeros((theta.size, 3))
    for j, lam in enumerate(wavelengths_nm):
        spectral = np.zeros(theta.size)
        for k in orders:
            sigma = drop_cross_section_sr(theta[:, None], diam[None, :], lam, k)  # mm²/sr per drop
            spectral += (sigma / (diam * diam)[None, :]) @ w  # ⟨dσ/dΩ⟩ / ⟨D²⟩ over the size distribution
        out += spectral[:, None] * weights[j][None, :]
    # ⟨dσ/dΩ⟩/⟨D²⟩ divided by the extinction cross-section per D², 2·π/4.
    return out / (math.pi / 2.0)


def sun_disc_kernel(step_rad: float) -> np.ndarray:
    """Weights of the sun's disc projected on one angle (∝ √(R² − δ²)), sampled every step_rad, summing to 1."""
    half = max(1, int(math.ceil(SUN_RADIUS_RAD / step_rad)))
    delta = np.arange(-half, half + 1) * step_rad
    w = np.sqrt(np.maximum(SUN_RADIUS_RAD**2 - delta**2, 0.0))
    if w.sum() <= 0.0:
        w = np.zeros_like(delta)
        w[half] = 1.0
    return w / w.sum()


def bow_lut(rate_mm_h: float, samples: int = 512, theta_range_deg=THETA_RANGE_DEG, wavelengths_nm=WAVELENGTHS_NM,
            size_nodes: int = 32) -> np.ndarray:
    """(samples, 3) float64: P(θ) (1/sr, linear sRGB) at θ evenly spaced over theta_range_deg (deg, endpoints
    included), convolved with the sun's disc. Outside the range the shader reads 0 (the geometric tail inside
    the bow fades to 0 at its low end: the Airy form is only valid near the rainbow angle)."""
    lo, hi = (math.radians(a) for a in theta_range_deg)
    theta = np.linspace(lo, hi, samples)
    step = theta[1] - theta[0]
    kernel = sun_disc_kernel(step)
    pad = len(kernel) // 2
    fine = np.linspace(lo - pad * step, hi + pad * step, samples + 2 * pad)
    p = bow_phase_rgb(fine, rate_mm_h, wavelengths_nm=wavelengths_nm, size_nodes=size_nodes)
    conv = np.stack([np.convolve(p[:, c], kernel, mode="valid") for c in range(3)], axis=-1)
    # Fade the far tail inside the primary smoothly to 0 at the LUT's low end (no edge in the sky).
    fade = np.clip((np.degrees(theta) - theta_range_deg[0]) / 6.0, 0.0, 1.0)
    return np.maximum(conv, 0.0) * (fade * fade * (3.0 - 2.0 * fade))[:, None]
