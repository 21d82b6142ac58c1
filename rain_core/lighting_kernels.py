"""Compiled kernel of the per-view light packing (rain_core.jit): ``lighting.pack_nearest`` — each view's lights
sorted by distance to its camera and gathered into the frame block's three arrays — in one call instead of about
ten small NumPy calls, for the main view and the road's mirror view of every frame.

Its NumPy twin stays in ``pack_nearest`` (the fallback and the oracle): the same squared distances, summed in
NumPy's order ((dx² + dy²) + dz²), the same stable sort, the same float32 rows: the same bytes
(tests/gfx/test_render_path.py).
"""

from __future__ import annotations

import numpy as np

from rain_core import jit


@jit.kernel
def gather_nearest(position, camera, rows, out):
    """The rows (``rows``: (3, L, 4) float32, ``LightSet.packed_rows``) of the ``out.shape[1]`` lights of
    ``position`` ((L, 3) m) nearest to ``camera`` ((3,) m), nearest first, ties in index order, into ``out``
    ((3, max_lights, 4) float32; the rest zeroed); returns how many."""
    n = position.shape[0]
    cx, cy, cz = camera[0], camera[1], camera[2]
    d = np.empty(n)
    for i in range(n):
        dx = position[i, 0] - cx
        dy = position[i, 1] - cy
        dz = position[i, 2] - cz
        d[i] = dx * dx + dy * dy + dz * dz  # left to right: NumPy's sum over a row of three
    order = np.argsort(d, kind="mergesort")  # stable, as the twin's
    count = min(n, out.shape[1])
    for k in range(count):
        j = order[k]
        for r in range(3):
            for c in range(4):
                out[r, k, c] = rows[r, j, c]
    for r in range(3):
        for k in range(count, out.shape[1]):
            for c in range(4):
                out[r, k, c] = 0.0
    return count
