"""Moved to rain_core.effects.ripples (the solvers, the field, the GPU path, the effect: one module each);
kept so earlier imports (``rain_core.ripples.WaveSolver``, ``RippleField``, ``RipplesEffect``, ...) still work."""

from rain_core.effects.ripples.backend import choose_backend, make_field, make_solver
from rain_core.effects.ripples.constants import (
    BACKENDS,
    CAPILLARY_SPEED_M_S,
    CRATER_RADIUS_PER_D,
    DEFAULT_DAMPING_PER_S,
    DEFAULT_MAX_SUBSTEPS,
    MAX_COURANT2,
    MAX_IMPULSE_M,
    MIN_FOOTPRINT_CELLS,
    RAIN_DENT_M_PER_KG_M_S,
    SLEEP_SLOPE,
    WAKE_REF_SPEED_M_S,
)
from rain_core.effects.ripples.effect import RipplesEffect
from rain_core.effects.ripples.field import FilmDepthFn, RippleField, WheelSweep
from rain_core.effects.ripples.gpu import REDUCE_BLOCK, WaveSolverGPU
from rain_core.effects.ripples.rain_tiles import (
    RAIN_TILE_CYCLE_S,
    RAIN_TILE_SLOPE_PER_MM,
    RAIN_TILE_VISIBLE_D_MM,
    RainRippleTexture,
)
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.textures import RippleTextures

__all__ = ["BACKENDS", "CAPILLARY_SPEED_M_S", "CRATER_RADIUS_PER_D", "DEFAULT_DAMPING_PER_S", "DEFAULT_MAX_SUBSTEPS",
           "MAX_COURANT2", "MAX_IMPULSE_M", "MIN_FOOTPRINT_CELLS", "RAIN_DENT_M_PER_KG_M_S", "RAIN_TILE_CYCLE_S",
           "RAIN_TILE_SLOPE_PER_MM", "RAIN_TILE_VISIBLE_D_MM", "REDUCE_BLOCK", "SLEEP_SLOPE", "WAKE_REF_SPEED_M_S",
           "FilmDepthFn", "RainRippleTexture", "RippleField", "RippleTextures", "RipplesEffect", "WaveSolver",
           "WaveSolverF32", "WaveSolverGPU", "WheelSweep", "choose_backend", "make_field", "make_solver"]
