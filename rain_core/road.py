"""Moved to ``rain_core.effects.road`` (the GL effect, the wet surface, the mirror) and ``rain_core.water_film``
(the standing water and the wet film); kept so earlier imports (``rain_core.road.film_depth_mm``) still work."""

from rain_core.effects.road import *  # noqa: F403
from rain_core.effects.road import __all__ as _moved
from rain_core.water_film import (  # noqa: F401  (re-exported below)
    CRACK_DEPTH_SPAN,
    CRACK_LEVEL,
    CRACK_MAX_MM,
    PUDDLE_DEPTH_SPAN,
    PUDDLE_GROUND_SIGMA_M,
    PUDDLE_LEVEL_EXPONENT,
    PUDDLE_LEVEL_MAX,
    PUDDLE_MAP_CELL_M,
    PUDDLE_MAX_MM,
    PUDDLE_NOISE_WEIGHT,
    ROAD_HALF_WIDTH_M,
    SHELTER_MIN_HEIGHT_M,
    WET_FILM_MM,
    crack_level,
    film_depth_mm,
    puddle_level,
    puddle_noise,
    sample_road_map,
    shelter_map,
    smooth_heightmap,
    water_depths_mm,
)

__all__ = [*_moved, "CRACK_DEPTH_SPAN", "CRACK_LEVEL", "CRACK_MAX_MM", "PUDDLE_DEPTH_SPAN", "PUDDLE_GROUND_SIGMA_M",
           "PUDDLE_LEVEL_EXPONENT", "PUDDLE_LEVEL_MAX", "PUDDLE_MAP_CELL_M", "PUDDLE_MAX_MM", "PUDDLE_NOISE_WEIGHT",
           "ROAD_HALF_WIDTH_M", "SHELTER_MIN_HEIGHT_M", "WET_FILM_MM", "crack_level", "film_depth_mm",
           "puddle_level", "puddle_noise", "sample_road_map", "shelter_map", "smooth_heightmap", "water_depths_mm"]
