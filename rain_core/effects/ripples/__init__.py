"""Interactive water (DESIGN §3, issue 5): a wave-equation heightfield around and ahead of the ego car that wheel
wakes and raindrops disturb, its normals for the road's water, and a tiled rain-ring normal map for far puddles.

GL-free (NumPy only): ``constants``, ``solver`` (the scheme and the float64 reference ``WaveSolver``),
``solver_f32`` (``WaveSolverF32``), ``raindrops`` (a frame's raindrops as a hash of the seed, the frame and
the drop's index: the NumPy twin of ``shaders/ripples/raindrops.glsl``, where the GPU solver makes them from a
few uniforms), ``wheels`` (``WheelSweep``, ``WheelBatch``: the wheels' contact paths), ``window``
(``field_grid``, ``window_centre_xz`` / ``window_offset_m``: where the window sits ahead of the car), ``field``
(``RippleField``). GL side: ``gpu``
(``WaveSolverGPU``), ``backend`` (``make_solver``, ``choose_backend``, ``make_field``), ``textures``
(``RippleTextures``: the field's height and slope textures), ``rain_tiles`` (``RainRippleTexture``), ``effect``
(``RipplesEffect``). The GL names are imported on first use, so the simulation imports and runs without
``moderngl``.
"""

from __future__ import annotations

import importlib

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
from rain_core.effects.ripples.field import CPU_SOLVERS, RippleField
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.wheels import FilmDepthFn, WheelBatch, WheelSweep
from rain_core.effects.ripples.window import field_grid, window_centre_xz, window_offset_m

_GL_NAMES = {
    "RipplesEffect": "effect",
    "WaveSolverGPU": "gpu", "REDUCE_BLOCK": "gpu",
    "choose_backend": "backend", "make_field": "backend", "make_solver": "backend",
    "RippleTextures": "textures",
    "RainRippleTexture": "rain_tiles", "RAIN_TILE_CYCLE_S": "rain_tiles", "RAIN_TILE_SLOPE_PER_MM": "rain_tiles",
    "RAIN_TILE_VISIBLE_D_MM": "rain_tiles",
}


def __getattr__(name: str):
    module = _GL_NAMES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


__all__ = ["BACKENDS", "CAPILLARY_SPEED_M_S", "CPU_SOLVERS", "CRATER_RADIUS_PER_D", "DEFAULT_DAMPING_PER_S",
           "DEFAULT_MAX_SUBSTEPS", "MAX_COURANT2", "MAX_IMPULSE_M", "MIN_FOOTPRINT_CELLS", "RAIN_DENT_M_PER_KG_M_S",
           "SLEEP_SLOPE", "WAKE_REF_SPEED_M_S", "FilmDepthFn", "RippleField", "WaveSolver", "WaveSolverF32",
           "WheelBatch", "WheelSweep", "field_grid", "window_centre_xz", "window_offset_m", *_GL_NAMES]
