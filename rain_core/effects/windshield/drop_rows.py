"""The fast path's drop array (``sim.WindshieldSim``): one preallocated (capacity, COLS) float64 array, a row a
drop, so appending writes rows, removing drops is one compaction and sorting one gather. The column indices are
shared by the simulation and its merge and wipe mixins (``fast_merging``, ``fast_wiping``)."""

from __future__ import annotations

import numpy as np

# Columns of the drop array (CELL: the film cell under the drop, kept with its position).
S, T, VS, VT, M, TRAIL, A, CELL = range(8)
COLS = 8
ROW = np.dtype((np.void, 8 * COLS))  # one element a drop: whole-row gathers
