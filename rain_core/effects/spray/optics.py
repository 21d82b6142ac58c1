"""How spray drops scatter and hide light: phase function and extinction of water drops much larger than the
wavelength, and the constants the spray shaders share with this module (``shader_defines``)."""

from __future__ import annotations

import math

import numpy as np

from rain_core import layout, physics
from rain_core.effects.spray.water import SPLASH_MIN_MM

EXTINCTION_EFFICIENCY = 2.0  # Q_ext of drops much larger than the wavelength

# Optics: half of the extinction is diffraction (a narrow forward lobe), the other half geometric: refraction
# (a forward Henyey–Greenstein lobe) and external reflection, F(i)/(4π) per unit geometric cross-section.
WATER_IOR = 1.333
G_DIFFRACTION = 0.95
G_REFRACTION = 0.8
GLINT_CHANCE = 0.03  # share of sparkle cells (about a pixel each) holding a glint; they carry 1/chance × the lobe

# How droplet parcels are drawn (shaders/spray/spray.frag): this share of a parcel's optical depth shows as
# streaks about a pixel wide, one per drop clump, each of opacity about STREAK_ALPHA (× 0.5…1.5); the rest is a
# smooth veil of drops too fine to see. Splash parcels (D ≥ SPLASH_MIN_MM) are sheets for SHEET_S per mm of drop
# size after they leave the tyre, then break into streaks.
STREAK_SHARE = 0.8
STREAK_ALPHA = 0.55
SHEET_S = 0.025


def henyey_greenstein(mu, g: float) -> np.ndarray:
    """Henyey–Greenstein phase function (1/sr) at mu = cos(scattering angle) (1 = straight on)."""
    mu = np.asarray(mu, dtype=np.float64)
    d = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))


def fresnel_reflection(cos_i, n: float = WATER_IOR) -> np.ndarray:
    """Unpolarised Fresnel reflectance of water seen from air at incidence cos_i."""
    ci = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    st2 = (1.0 - ci * ci) / (n * n)
    ct = np.sqrt(np.maximum(1.0 - st2, 0.0))
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return 0.5 * (rs * rs + rp * rp)


def reflection_lobe(mu) -> np.ndarray:
    """External reflection off a sphere, per unit geometric cross-section and steradian: F(i)/(4π), with the
    incidence i = (π − θ)/2 for scattering angle θ (mu = cos θ)."""
    cos_i = np.sqrt(np.clip((1.0 - np.asarray(mu, dtype=np.float64)) / 2.0, 0.0, 1.0))
    return fresnel_reflection(cos_i) / (4.0 * math.pi)


def _reflection_share() -> float:
    mu = np.linspace(-1.0, 1.0, 20001)
    f = reflection_lobe(mu)
    return float(2.0 * math.pi * np.sum((f[1:] + f[:-1]) / 2.0 * np.diff(mu)))


REFLECTION_SHARE = _reflection_share()  # ≈ 0.066: the reflected share of the geometric cross-section


def phase_function(mu, glint: float = 1.0) -> np.ndarray:
    """Phase function (1/sr, integrates to 1 over the sphere for glint = 1) of water drops ≫ λ, per unit
    extinction: ½ diffraction + ½ (refraction + reflection); ``glint`` scales the reflection lobe (sparkle)."""
    return 0.5 * henyey_greenstein(mu, G_DIFFRACTION) + 0.5 * (
        (1.0 - REFLECTION_SHARE) * henyey_greenstein(mu, G_REFRACTION) + glint * reflection_lobe(mu))


def light_lobe(mu) -> np.ndarray:
    """What a point light of illuminance E adds to the radiance of spray per unit of its opacity (1/sr; × E in
    lux gives cd/m²), at mu = cos(scattering angle): refraction's wide lobe and the Fresnel reflection, the
    diffracted half (within ~λ/D of the beam) left out. The NumPy twin of ``spray_light_lobe``
    (shaders/spray/optics.glsl)."""
    return 0.5 * ((1.0 - REFLECTION_SHARE) * henyey_greenstein(mu, G_REFRACTION) + reflection_lobe(mu))


def radiance_bound(sky_zenith, sky_horizon, sun_illum, sun_dir, ground_albedo, mu_max: float = 1.0,
                   airlight=None) -> np.ndarray:
    """Upper bound (cd/m², RGB) of the radiance per unit opacity that spray may have, lit by the sky and the sun
    only (shaders/spray/shading.glsl): the brightest of the environment it transmits and reflects (zenith,
    horizon, lit ground: spray_environment is a mean of these) plus the sun's lobe at its largest for
    scattering cosines up to ``mu_max`` (the view's nearest approach to the sun), and the airlight if given (the
    atmosphere mixes it in). Spray radiance above this would be light the drops cannot have scattered."""
    zen, hor, sun = (np.asarray(a, dtype=np.float64) for a in (sky_zenith, sky_horizon, sun_illum))
    ground = float(ground_albedo) / math.pi * (sun * max(float(sun_dir[1]), 0.0) + math.pi * 0.5 * (zen + hor))
    env = np.maximum(np.maximum(zen, hor), ground)
    if airlight is not None:
        env = np.maximum(env, np.asarray(airlight, dtype=np.float64))
    mu = np.linspace(-1.0, float(mu_max), 2001)
    return env + sun * float(light_lobe(mu).max())


def extinction_area_m2(mass_kg, d_mm) -> np.ndarray:
    """Extinction cross-section (m²) of mass_kg of water in drops of diameter d_mm (mm): Q·(3/2)·m/(ρ_w·D)."""
    return EXTINCTION_EFFICIENCY * 1.5 * np.asarray(mass_kg, dtype=np.float64) / (
        physics.RHO_WATER * np.asarray(d_mm, dtype=np.float64) * 1e-3)



def shader_defines() -> dict[str, str]:
    """The model constants the shaders share with this module (one source of truth)."""
    return {"SPRAY_G_DIFFRACTION": repr(G_DIFFRACTION), "SPRAY_G_REFRACTION": repr(G_REFRACTION),
            "SPRAY_REFLECTION_SHARE": repr(REFLECTION_SHARE), "SPRAY_WATER_IOR": repr(WATER_IOR),
            "SPRAY_GLINT_CHANCE": repr(GLINT_CHANCE), "SPRAY_PERIOD_M": repr(float(layout.PERIOD_M)),
            "SPRAY_STREAK_SHARE": repr(STREAK_SHARE), "SPRAY_STREAK_ALPHA": repr(STREAK_ALPHA),
            "SPRAY_SHEET_S": repr(SHEET_S), "SPRAY_SPLASH_MIN_MM": repr(float(SPLASH_MIN_MM))}
