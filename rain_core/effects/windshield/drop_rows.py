"""The fast path's drop array (``sim.WindshieldSim``): one preallocated (capacity, COLS) float64 array, a row a
drop, so appending writes rows, removing drops is one compaction and sorting one gather. The column indices are
shared by the simulation and its merge and wipe mixins (``fast_merging``, ``fast_wiping``)."""

from __future__ import annotations

import numpy as np

# Columns of the drop array. CELL … KEY are functions of the position alone, written where a drop is placed
# (born, moved, merged) so a step need not recompute them for the many drops at rest: CELL the film cell under
# the drop; UP and Q the air's factors there (along the glass head·UP, across |up|·FLOW_SPREAD·Q + the
# crosswind's); BL ν_air·(BL_RUN_UP_M + t), the boundary layer's run; GS, GT gravity per unit mass along the
# curved glass (GlassGeometry.gravity); KEY the merge grid's cell (grid.grid_keys), the order the drops are kept in.
S, T, VS, VT, M, TRAIL, A, CELL, UP, Q, BL, GS, GT, KEY = range(14)
COLS = 14
PLACED = slice(CELL, KEY + 1)  # the position's columns, in this order
ROW = np.dtype((np.void, 8 * COLS))  # one element a drop: whole-row gathers
