"""Compiled kernels of the frame's lights (rain_core.jit).

``gather_nearest``: ``lighting.pack_nearest`` — each view's lights sorted by distance to its camera and gathered
into the frame block's three arrays — in one call instead of about ten small NumPy calls, for the main view and
the road's mirror view of every frame. Its NumPy twin stays in ``pack_nearest`` (the fallback and the oracle): the
same squared distances, summed in NumPy's order ((dx² + dy²) + dz²), the same stable sort, the same float32 rows:
the same bytes (tests/gfx/test_render_path.py).

``vehicle_lights``: the vehicles' head and tail lights of ``lighting.light_candidates`` (positions in the wrapped
frame, beam directions) in one call instead of about thirty NumPy calls on (n, 4) arrays, once a frame. Its twin
is the NumPy code there: the same operations in the same order on the same cosines (NumPy's, passed in).
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


@jit.kernel
def vehicle_lights(cos, sin, centre, local, shift_z, pitch_c, pitch_s, pos, dirs):
    """Into ``pos`` and ``dirs`` ((4n, 3): two heads then two tails per vehicle) the lens centres in the wrapped
    frame and the beam directions of n vehicles: ``cos``/``sin`` (n,) of their yaws, ``centre`` (n, 3) m,
    ``local`` (n, 4, 3) car-local lens centres, ``shift_z`` m, the headlights' pitch cosine and sine."""
    for i in range(cos.shape[0]):
        c, s = cos[i], sin[i]
        cx, cy, cz = centre[i, 0], centre[i, 1], centre[i, 2]
        # the twin's head_dir = fwd * pitch_c + (0, pitch_s, 0) with fwd = (−sin, 0, −cos); x + 0.0 kept (−0.0)
        hx, hy, hz = -s * pitch_c + 0.0, 0.0 * pitch_c + pitch_s, -c * pitch_c + 0.0
        for k in range(4):
            lx, ly, lz = local[i, k, 0], local[i, k, 1], local[i, k, 2]
            row = 4 * i + k
            pos[row, 0] = c * lx + s * lz + cx
            pos[row, 1] = ly + cy
            pos[row, 2] = (-s * lx + c * lz + cz) - shift_z
            if k < 2:
                dirs[row, 0], dirs[row, 1], dirs[row, 2] = hx, hy, hz
            else:  # −fwd = (sin, −0.0, cos): negating twice leaves every bit
                dirs[row, 0], dirs[row, 1], dirs[row, 2] = s, -0.0, c
