"""The wet road surface: the wet material, the water layer's coverage and regions, the wind waves on standing water.

NumPy twin of ``shaders/road/surface.glsl`` (tests/effects/road/test_surface.py checks the constants agree).
GL-free.

* **Wet material** (every lit surface the rain reaches; Lagarde's game-engine form): albedo × lerp(1, 0.3, w·p)
  with p the material's porosity (asphalt 1, painted markings and metal much less), smoothness × lerp(1, 2.5, w)
  capped at 1. w is the weather's wetness times the surface's exposure: up-facing 1, vertical 0.4, facing down
  0, and 0 under a roof (the bridge deck, the fuel-station canopy; from the world's occluder map).
* **Water film**: on a wet surface a thin water layer (F0 = 0.02, roughness :data:`FILM_ROUGHNESS` — it follows
  the asphalt's macrotexture) covers a fraction w·c of it (c per material). Under water the base's own
  specular is that of an asphalt–water interface (F0 ≈ 0.004). The layer is added energy-correctly:
  L = (1 − c·F)·L_base + c·(F·L_reflected + specular of the lights), F the split-sum Fresnel of the layer.
  Under standing water (``rain_core.water_film``) the asphalt is soaked: the wet material uses max(w, coverage).
* **Coverage**: standing water shallower than the asphalt's macrotexture (:data:`MACROTEXTURE_MM`) only fills
  the pores (the *drenched* margin: darker, glossier, still textured); deeper water is a full water surface
  (the *puddle*: normal up + wind waves + ripples, a mirror). Coverage = clamp(standing / MACROTEXTURE_MM, 0, 1),
  so every puddle has a soft margin whose width follows the ground's slope.
* The four regions (the debug view colours them): dry, wet (film only), drenched (0 < coverage < 1), puddle
  (coverage 1).
* Murky water: under standing water the base is tinted by MURK_TINT^(depth/10 mm) (brownish grey, low
  saturation) and darker with depth; the reflection is only the Fresnel share — puddles stay dull rather than
  shiny and colourful.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.mesh import (
    MAT_ASPHALT,
    MAT_CAR_PAINT,
    MAT_CONCRETE,
    MAT_EMISSIVE,
    MAT_FOLIAGE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_PAINT,
    MAT_RUBBER,
)
from rain_core.water_film import default_world, sample_road_map, shelter_map_for, water_depths_mm

# shaders/road/surface.glsl holds the same numbers.
WET_ALBEDO_FACTOR = 0.3  # albedo × lerp(1, this, w·porosity)
WET_SMOOTHNESS_GAIN = 2.5  # smoothness × lerp(1, this, w), capped at 1
WATER_F0 = 0.02  # water surface, IOR 1.33
UNDERWATER_F0 = 0.004  # asphalt/binder (IOR ~1.5) under water (IOR 1.33): ((1.5 − 1.33)/(1.5 + 1.33))²
FILM_ROUGHNESS = 0.32  # the wet film follows the asphalt macrotexture: calibrated for ×5–10 peak specular
WATER_ROUGHNESS = 0.04  # standing water: suspended dirt and micro-ripples keep it from a perfect mirror
LIGHT_MIN_ROUGHNESS = 0.1  # the lights' highlight on water: a point light has no size, the lamp lens has
MACROTEXTURE_MM = 2.0  # mm, asphalt mean texture depth: deeper water is a full water surface
MURK_TINT = (0.62, 0.57, 0.50)  # transmittance of 10 mm of rain-water with road dirt (brownish grey)
WAVE_SLOPE_MAX = 0.07  # slope of the wind waves at wave_strength 1 in a WAVE_FULL_WIND_M_S wind
WAVE_FULL_WIND_M_S = 8.0  # m/s
WAVE_CALM_FRACTION = 0.2  # waves left in still air (rain, passing traffic)

# Per material: porosity (share of the wet darkening) and the water film coverage at full wetness.
MATERIAL_POROSITY = {MAT_GENERIC: 0.6, MAT_ASPHALT: 1.0, MAT_PAINT: 0.2, MAT_CONCRETE: 0.7, MAT_METAL: 0.0,
                     MAT_GLASS: 0.0, MAT_FOLIAGE: 0.4, MAT_EMISSIVE: 0.0, MAT_CAR_PAINT: 0.0, MAT_RUBBER: 0.3}
MATERIAL_FILM = {MAT_GENERIC: 0.5, MAT_ASPHALT: 1.0, MAT_PAINT: 1.0, MAT_CONCRETE: 0.8, MAT_METAL: 0.6,
                 MAT_GLASS: 0.0, MAT_FOLIAGE: 0.3, MAT_EMISSIVE: 0.0, MAT_CAR_PAINT: 0.6, MAT_RUBBER: 0.5}

REGIONS = ("dry", "wet", "drenched", "puddle")
REGION_COLORS = ((0.55, 0.45, 0.25), (0.15, 0.55, 0.15), (0.95, 0.45, 0.05), (0.10, 0.30, 1.00))
WET_MIN = 0.02  # wetness below this counts as dry in the region view


def wet_material(albedo, roughness, wetness, material: int = MAT_ASPHALT) -> tuple[np.ndarray, np.ndarray]:
    """Albedo (linear RGB, any shape ending in 3 or scalar) and perceptual roughness of a surface at wetness w
    in [0, 1]: albedo × lerp(1, 0.3, w·porosity), smoothness = 1 − roughness × lerp(1, 2.5, w) capped at 1
    (roughness floored at 0.02 like the scene shader). The twin of road_wet_material in surface.glsl."""
    w = np.clip(np.asarray(wetness, dtype=np.float64), 0.0, 1.0)
    p = MATERIAL_POROSITY.get(int(material), MATERIAL_POROSITY[MAT_GENERIC])
    alb = np.asarray(albedo, dtype=np.float64) * (1.0 + (WET_ALBEDO_FACTOR - 1.0) * w * p)
    smooth = np.minimum(1.0, (1.0 - np.asarray(roughness, dtype=np.float64)) * (1.0 + (WET_SMOOTHNESS_GAIN - 1) * w))
    return alb, np.maximum(1.0 - smooth, 0.02)


def water_coverage(standing_mm) -> np.ndarray:
    """Share of the surface under a continuous water surface, from the standing depth (mm): the water drowns
    the asphalt macrotexture linearly up to MACROTEXTURE_MM."""
    return np.clip(np.asarray(standing_mm, dtype=np.float64) / MACROTEXTURE_MM, 0.0, 1.0)


def road_regions(x_m, z_m, wetness, cracks, puddles, puddle_amount=0.5, seed=0, world=None) -> np.ndarray:
    """Region index per point (0 dry, 1 wet, 2 drenched, 3 puddle; see REGIONS), as the debug view colours
    the road surface."""
    standing, _ = water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount, seed, world, wetness)
    world = world if world is not None else default_world()
    shelter = sample_road_map(shelter_map_for(world), x_m, z_m)
    cover = water_coverage(standing)
    wet = float(wetness) * (1.0 - shelter) >= WET_MIN
    return np.where(cover >= 1.0, 3, np.where(cover > 0.0, 2, np.where(wet, 1, 0))).astype(np.int8)


def wave_parameters(wind_velocity_m_s, wave_strength: float) -> tuple[float, float, float]:
    """Wind ripples on standing water: (drift x, drift z) in m/s and the slope amplitude, for a wind velocity
    (m/s, world x, y, z) and settings.road.wave_strength in [0, 1]. Small ripples drift at a fraction of the
    wind (at most 0.35 m/s, the speed of capillary-gravity waves); the slope grows with the wind up to
    WAVE_FULL_WIND_M_S, and a calm share remains (rain, traffic)."""
    vx, _, vz = (float(v) for v in wind_velocity_m_s)
    speed = math.hypot(vx, vz)
    drift = min(0.35, 0.05 + 0.04 * speed)
    ux, uz = (vx / speed, vz / speed) if speed > 1e-6 else (0.0, -1.0)
    amp = float(wave_strength) * WAVE_SLOPE_MAX * (WAVE_CALM_FRACTION + (1.0 - WAVE_CALM_FRACTION)
                                                   * min(1.0, speed / WAVE_FULL_WIND_M_S))
    return ux * drift, uz * drift, amp
