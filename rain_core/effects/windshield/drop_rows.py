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
# They are written lazily: a drop placed during a step gets KEY = -1 (``DIRTY``), and the simulation fills the
# columns of all such drops at once before they are read (``WindshieldSim._flush_placed``).
# EV and RB hold for the air of the last step (``fast_motion``): EV the air's factor on the drop's evaporation,
# sqrt(1 + |air| / EVAP_AIR_M_S); RB an upper bound on (driving force) / (static pinning) that holds for as long
# as the drop rests where it is and only loses water, or +inf when the drop must be tested this step (it moves,
# was placed or grew, or the air changed).
S, T, VS, VT, M, TRAIL, A, CELL, UP, Q, BL, GS, GT, KEY, EV, RB = range(16)
COLS = 16
DIRTY = -1.0  # KEY of a drop whose position columns are still to be written
PLACED = slice(CELL, KEY + 1)  # the position's columns, in this order
ROW = np.dtype((np.void, 8 * COLS))  # one element a drop: whole-row gathers
