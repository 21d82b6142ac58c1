"""What every windshield kernel shares: the twins' constants folded in the same order (so to the same bits)
and where a point of the glass lies (inside its outline, its film cell). Units: m, kg."""

from __future__ import annotations

import math

from rain_core import jit
from rain_core.effects.windshield.constants import (
    DRAG_CD,
    FILM_CELLS,
    FRONTAL_PER_RADIUS2,
    SPLASH_SPEED_M_S,
    TRAIL_FILM_M,
    VOLUME_PER_RADIUS3,
)
from rain_core.effects.windshield.grid import _GRID_ORIGIN, GRID_CELL_M, NEAR_CELL_M, _grid_shape
from rain_core.physics import RHO_AIR, RHO_WATER

# The twins' constants, folded in the same order (so to the same bits).
_DRAG_K = 0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2
_INV_MASS_PER_A3 = 1.0 / (RHO_WATER * VOLUME_PER_RADIUS3)
_WET_PER_AREA = RHO_WATER * TRAIL_FILM_M
_KG_PER_MM3 = RHO_WATER * math.pi / 6.0 * 1e-9  # a raindrop's mass over its diameter (mm) cubed
_SPLASH_LO, _SPLASH_HI = SPLASH_SPEED_M_S
_SLICES = 1024  # sample_arrivals: slices of the CDF, each starting a short walk to a sample's interval
_O0, _O1 = float(_GRID_ORIGIN[0]), float(_GRID_ORIGIN[1])
_G0, _G1 = _grid_shape(GRID_CELL_M)
_N0, _N1 = _grid_shape(NEAR_CELL_M)
_P1 = _N1 + 2  # PairFinder's padded near grid: a border of empty cells
NEAR_CELLS = (_N0 + 2) * _P1  # cells of the scratch tables merge_drops needs (the padded grid is the larger)
_INF = math.inf


@jit.kernel
def inside(s, t, w0, dw, height):
    """Whether the point (s, t) m lies on the glass (``WindshieldSim._inside``)."""
    return t >= 0.0 and t <= height and abs(s) <= 0.5 * (w0 + dw * t)


@jit.kernel
def film_cell(s, t, w0, dw, height):
    """The film cell (flat index) under the point (s, t) m (``WindshieldSim._cells``)."""
    u = s / (w0 + dw * t) * FILM_CELLS + 0.5 * FILM_CELLS
    if u > FILM_CELLS - 0.5:
        u = FILM_CELLS - 0.5
    v = t * (FILM_CELLS / height)
    if v > FILM_CELLS - 0.5:
        v = FILM_CELLS - 0.5
    return int(v) * FILM_CELLS + int(u)
