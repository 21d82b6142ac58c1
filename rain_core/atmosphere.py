"""Moved to rain_core.effects.atmosphere (``model``, ``glow``, ``scattering``, ``effect``); this shim keeps the
earlier imports working (``rain_core.atmosphere.sky_overcast``, ``Atmosphere``, …)."""

from rain_core.effects.atmosphere.effect import AtmosphereEffect, NoAirEffect
from rain_core.effects.atmosphere.glow import MAX_BLUR_RADIUS, blur_radius, gaussian_weights, glow_reference
from rain_core.effects.atmosphere.model import (
    CLEAR_AIR_EXTINCTION_PER_M,
    CONTRAST_THRESHOLD,
    GLOW_SHARE,
    GLOW_SIGMA_GROWTH_RAD,
    GLOW_SIGMA_MIN_RAD,
    GLOW_SIGMA_REF_M,
    LAYER_M,
    NIGHT_AIRLIGHT_CD_M2,
    OVERCAST_HALF_RATE_MM_H,
    PHASE_BACK_G,
    PHASE_BACK_WEIGHT,
    PHASE_G,
    AtmosphereState,
    airlight,
    atmosphere_state,
    atmosphere_uniforms,
    extinction_per_m,
    glow_sigma_rad,
    medium_extinction_per_m,
    medium_uniforms,
    phase_hg,
    phase_rain,
    rain_extinction_per_m,
    rain_overcast,
    sky_overcast,
    transmittance,
    visibility_m,
)
from rain_core.effects.atmosphere.scattering import (
    SCATTER_MAX_M,
    SCATTER_SAMPLES,
    light_inscatter_reference,
    pixel_distances,
)

Atmosphere = AtmosphereEffect  # the earlier class name

__all__ = [
    "CLEAR_AIR_EXTINCTION_PER_M", "CONTRAST_THRESHOLD", "GLOW_SHARE", "GLOW_SIGMA_GROWTH_RAD", "GLOW_SIGMA_MIN_RAD",
    "GLOW_SIGMA_REF_M", "LAYER_M", "MAX_BLUR_RADIUS", "NIGHT_AIRLIGHT_CD_M2", "OVERCAST_HALF_RATE_MM_H",
    "PHASE_BACK_G", "PHASE_BACK_WEIGHT", "PHASE_G", "SCATTER_MAX_M", "SCATTER_SAMPLES", "Atmosphere",
    "AtmosphereEffect", "AtmosphereState", "NoAirEffect", "airlight", "atmosphere_state", "atmosphere_uniforms",
    "blur_radius", "extinction_per_m", "gaussian_weights", "glow_reference", "glow_sigma_rad",
    "light_inscatter_reference", "medium_extinction_per_m", "medium_uniforms", "phase_hg", "phase_rain",
    "pixel_distances", "rain_extinction_per_m", "rain_overcast", "sky_overcast", "transmittance", "visibility_m",
]
