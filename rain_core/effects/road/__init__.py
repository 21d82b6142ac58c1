"""The wet road (DESIGN §3 "Wet road"): wet BRDF, water in cracks and puddles, wind waves, planar reflections.

One model, two implementations: the scalar parts in NumPy (float64, the reference) and in GLSL (what the scene
shader runs). tests/effects/road/ checks that the constants agree and that the film depth matches on a grid.

Where things live:

* ``rain_core.water_film`` — the standing water and the wet film (shared with the spray and the ripples, so it
  lives outside ``effects/``); GLSL twin ``shaders/road/film.glsl``.
* ``surface`` — the wet material, the water layer's coverage, the debug regions, the wind waves; GLSL twin
  ``shaders/road/surface.glsl``.
* ``mirror`` — the planar reflection's geometry (the road plane as a mirror, its clip plane).
* ``effect`` — ``RoadEffect``, the GL side: textures, the reflection pass (``Renderer.draw_mirror_view``), the
  scene shader's inputs. Imported on first use, so the NumPy modules import without moderngl.

Frames: x across the road (m, |x| ≤ 7 is asphalt), z along it (m, any world z: every map is periodic in
``layout.PERIOD_M``, so world z and the renderer's wrapped z give the same values).
"""

from __future__ import annotations

from rain_core.effects.road.mirror import (
    LIGHT_SOURCE_RADIANCE,
    MIRROR_CLIP_PLANE,
    MIRROR_CLIP_Y_M,
    MIRROR_LENS_FACTOR,
    MIRROR_Y,
    mirror_about_road,
)
from rain_core.effects.road.surface import (
    FILM_ROUGHNESS,
    LIGHT_MIN_ROUGHNESS,
    MACROTEXTURE_MM,
    MATERIAL_FILM,
    MATERIAL_POROSITY,
    MURK_TINT,
    REGION_COLORS,
    REGIONS,
    UNDERWATER_F0,
    WATER_F0,
    WATER_ROUGHNESS,
    WAVE_CALM_FRACTION,
    WAVE_FULL_WIND_M_S,
    WAVE_SLOPE_MAX,
    WET_ALBEDO_FACTOR,
    WET_MIN,
    WET_SMOOTHNESS_GAIN,
    road_regions,
    water_coverage,
    wave_parameters,
    wet_material,
)

__all__ = [
    "FILM_ROUGHNESS", "LIGHT_MIN_ROUGHNESS", "LIGHT_SOURCE_RADIANCE", "MACROTEXTURE_MM", "MATERIAL_FILM",
    "MATERIAL_POROSITY", "MIRROR_CLIP_PLANE", "MIRROR_CLIP_Y_M", "MIRROR_LENS_FACTOR", "MIRROR_Y", "MURK_TINT",
    "REGIONS", "REGION_COLORS", "UNDERWATER_F0", "WATER_F0", "WATER_ROUGHNESS", "WAVE_CALM_FRACTION",
    "WAVE_FULL_WIND_M_S", "WAVE_SLOPE_MAX", "WET_ALBEDO_FACTOR", "WET_MIN", "WET_SMOOTHNESS_GAIN", "RoadEffect",
    "mirror_about_road", "road_regions", "water_coverage", "wave_parameters", "wet_material",
]


def __getattr__(name: str):
    """``RoadEffect`` is imported on first use (the NumPy model imports and runs without moderngl)."""
    if name == "RoadEffect":
        from rain_core.effects.road.effect import RoadEffect

        return RoadEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
