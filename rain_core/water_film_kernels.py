"""Compiled twins (rain_core.jit) of ``rain_core.water_film``'s sampling: the same IEEE operations point by point,
so the same bits (no transcendentals); the NumPy code there stays the fallback and the oracle. Split from
water_film by concern (the module had reached its size); it imports the model's constants from there, and
water_film imports this module after defining them."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.gutter import CROSS_SLOPE, GUTTER_MAX_MM
from rain_core.water_film import (
    CRACK_DEPTH_SPAN,
    CRACK_MAX_MM,
    PUDDLE_DEPTH_SPAN,
    PUDDLE_MAX_MM,
    PUDDLE_NOISE_WEIGHT,
    ROAD_HALF_WIDTH_M,
)


@jit.kernel
def _clamp01(v):
    """np.minimum(np.maximum(v, 0.0), 1.0) of one float64 (NaN kept, as NumPy's)."""
    v = v if (v >= 0.0 or v != v) else 0.0
    return v if (v <= 1.0 or v != v) else 1.0


@jit.kernel
def _wrap(i, size):
    """i mod size (the floor modulo of NumPy's int64 %) of an integer-valued float64, as a float: one float
    division instead of an integer one (several times slower), exact below 2^52; beyond, int64's own %, and for
    NaN and ±inf that of the int64 NumPy casts them to, so a row index is always inside the table."""
    if abs(i) < 4503599627370496.0:
        r = i - math.floor(i / size) * size
        if r < 0.0:
            r += size
        elif r >= size:
            r -= size
        return r
    if abs(i) < 9223372036854775808.0:
        return float(np.int64(i) % np.int64(size))
    # What NumPy's astype(int64) gives beyond int64 and for NaN on x86 (the samples there are NaN or meaningless,
    # but a row inside the table all the same).
    return float(np.int64(-9223372036854775807 - 1) % np.int64(size))


@jit.kernel
def _texel_cell(x, z, half_x, ext_x, ext_z, nx, nz, top_col, offset, row_len):
    """(table row, tx, tz) of a bilinear sample at x, z (m) on one grid: ``_PackedGrids.sample``'s arithmetic
    (x on the asphalt: finite)."""
    fx = (x + half_x) / ext_x * nx - 0.5
    fz = z / ext_z * nz - 0.5
    i0 = np.floor(fx)
    j0 = np.floor(fz)
    column = np.int64(min(max(i0, -1.0), top_col) + offset)
    return np.int64(_wrap(j0, nz)) * row_len + column, fx - i0, fz - j0


@jit.kernel
def _lerp(t0, t1, t2, t3, tx, tz):
    """The bilinear blend of four float32 taps with float64 weights, in the twin's order."""
    ux = 1.0 - tx
    top = np.float64(t0) * ux + np.float64(t1) * tx
    bot = np.float64(t2) * ux + np.float64(t3) * tx
    return top * (1.0 - tz) + bot * tz


@jit.kernel
def _standing_mm(table, a, b, tx, tz, tx_b, tz_b, crack_at, puddle_at):
    """(standing water mm, shelter) of one point from its texels' table rows ``a`` (heightmap grid) and ``b``
    (puddle-map grid) and its weights: ``_road_depths``' formulas before the kerb streams, in its order."""
    h = _lerp(table[a, 0], table[a, 1], table[a, 2], table[a, 3], tx, tz)
    h_smooth = _lerp(table[a, 4], table[a, 5], table[a, 6], table[a, 7], tx, tz)
    n = _lerp(table[b, 0], table[b, 1], table[b, 2], table[b, 3], tx_b, tz_b)
    sh = _lerp(table[b, 4], table[b, 5], table[b, 6], table[b, 7], tx_b, tz_b)
    crack = CRACK_MAX_MM * _clamp01((crack_at - h) / CRACK_DEPTH_SPAN)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * h_smooth + PUDDLE_NOISE_WEIGHT * n
    puddle = PUDDLE_MAX_MM * _clamp01((puddle_at - ground) / PUDDLE_DEPTH_SPAN)
    wet = crack if (crack >= puddle or crack != crack) else puddle
    return wet * (1.0 - sh), sh


# Points whose two table rows _standing_points copies out before it uses any: the table (17 MB) is cold in a frame,
# and a loop that loads and then computes point by point waits for each cache miss in turn (~4× the warm time).
_GATHER_CHUNK = 64


@jit.kernel
def _standing_points(table, fc, fi, x, z, index, m, crack_at, puddle_at, standing, shelter):
    """``_road_depths`` before the kerb streams at on-road points x, z (float64 m): the standing water (mm) and the
    shelter into ``standing`` and ``shelter``, at points ``index[:m]`` (all points when m < 0). Both grids of
    ``_PackedGrids.sample`` (constants ``fc``, ``fi`` by grid) and the formulas, the twin's operations in its
    order (the helpers take scalars only: one taking arrays costs more per call than a point). Chunk by chunk,
    the texels of every point are gathered first (independent loads, so their misses overlap), then blended."""
    count = x.size if m < 0 else m
    rows = np.empty((_GATHER_CHUNK, 2), np.int64)
    weights = np.empty((_GATHER_CHUNK, 4))
    for start in range(0, count, _GATHER_CHUNK):
        stop = min(start + _GATHER_CHUNK, count)
        touched = np.float32(0.0)
        for j in range(start, stop):
            k = j if m < 0 else index[j]
            xk = x[k]
            zk = z[k]
            q = j - start
            a, tx, tz = _texel_cell(xk, zk, fc[0, 0], fc[0, 1], fc[0, 2], fc[0, 3], fc[0, 4], fc[0, 5], fc[0, 6],
                                    fi[0, 1])
            b, tx_b, tz_b = _texel_cell(xk, zk, fc[1, 0], fc[1, 1], fc[1, 2], fc[1, 3], fc[1, 4], fc[1, 5],
                                        fc[1, 6], fi[1, 1])
            touched += table[a, 0] + table[b, 0]
            rows[q, 0] = a
            rows[q, 1] = b
            weights[q, 0] = tx
            weights[q, 1] = tz
            weights[q, 2] = tx_b
            weights[q, 3] = tz_b
        if touched != touched:  # (keeps the loads: their value is not needed)
            weights[0, 0] = weights[0, 0]
        for j in range(start, stop):
            k = j if m < 0 else index[j]
            q = j - start
            a, b = rows[q, 0], rows[q, 1]
            tx, tz, tx_b, tz_b = weights[q, 0], weights[q, 1], weights[q, 2], weights[q, 3]
            standing[k], shelter[k] = _standing_mm(table, a, b, tx, tz, tx_b, tz_b, crack_at, puddle_at)


@jit.kernel
def _standing_where_wet_kernel(table, fc, fi, floors, crack_at, puddle_at, kerb, row_scale, col_scale, cols,
                               cells, max_rows, x, z, out, shelter, scratch):
    """``_standing_where_wet`` before the kerb streams: standing water (mm) into ``out`` (zeros on entry) at the
    points of x, z (float64 (k,) m) that the dry-cell table does not rule out; the indices of the on-road points
    beyond ``kerb`` (m, where the kerb streams may run) into ``scratch[1]``. Returns how many, or −1 when an
    on-road point lies beyond ``max_rows`` puddle-map rows of z = 0 (the caller then samples everything).
    ``shelter``: float64 scratch of ≥ k; ``scratch``: int64 (2, ≥ k)."""
    maybe = scratch[0]
    near = scratch[1]
    m = 0
    wet = 0
    for k in range(x.size):
        xk = x[k]
        ax = abs(xk)
        if not ax <= ROAD_HALF_WIDTH_M:
            continue
        rows = z[k] * row_scale
        if not (-max_rows < rows and rows < max_rows):
            return -1
        col = min(math.floor((xk + ROAD_HALF_WIDTH_M) * col_scale), cols - 1.0)
        cell = np.int64(_wrap(math.floor(rows) * cols + col, cells))
        if ax > kerb:
            near[m] = k
            m += 1
        elif not (floors[0, cell] < crack_at or floors[1, cell] < puddle_at):
            continue
        maybe[wet] = k
        wet += 1
    _standing_points(table, fc, fi, x, z, maybe, wet, crack_at, puddle_at, out, shelter)
    return m


@jit.kernel
def film_points(table, fc, fi, x, z, crack_at, puddle_at, wet, kerb, standing, film, shelter, index):
    """``water_film._depths`` before the kerb streams at float64 x, z (m, flat): the standing water and the film
    (mm; +0 off the asphalt) into ``standing`` and ``film``, the indices of the on-road points into ``index[0]``
    and of those beyond ``kerb`` (m, where the kerb streams may run) into ``index[1]``. Returns both counts.
    ``shelter``: float64 scratch of ≥ x.size; ``index``: int64 (2, ≥ x.size)."""
    on = index[0]
    near = index[1]
    m = 0
    b = 0
    for k in range(x.size):
        ax = abs(x[k])
        if ax <= ROAD_HALF_WIDTH_M:
            on[m] = k
            m += 1
            if ax > kerb:
                near[b] = k
                b += 1
        else:
            standing[k] = 0.0
            film[k] = 0.0
    _standing_points(table, fc, fi, x, z, on, m, crack_at, puddle_at, standing, shelter)
    for j in range(m):
        k = on[j]
        film[k] = wet * (1.0 - shelter[k])
    return m, b


@jit.kernel
def _standing_grid_kernel(table, fc, fi, floors, crack_at, puddle_at, kerb, row_scale, col_scale, cols, cells,
                          max_rows, xc, zr, spread, out):
    """``_standing_where_wet_kernel`` and the kerb streams on a grid: x = xc[c] (m) along the columns, z = zr[r] (m)
    along the rows, standing water (mm) into ``out`` (len(zr), len(xc)), zeros on entry. A grid's points share
    their column's and their row's halves of the arithmetic (the coordinates' divisions, floors and wraps), done
    once per column and per row, with the same operations, so the same bits. ``spread``: (2, len(zr)) the kerb
    streams' spread T = k·L^(3/8) (m) of each row at the −x and the +x kerb (``gutter_depth_mm``'s, unused when
    kerb ≥ ROAD_HALF_WIDTH_M). Returns 0, or −1 as that kernel (the caller then samples everything)."""
    nr, nc = zr.size, xc.size
    # Per column: [cell column (float), tx, tx_b, s = distance from the kerb face] and [on the road, column of
    # each grid, at the kerb: 0 no, 1 the −x kerb, 2 the +x kerb].
    cf = np.empty((4, nc))
    ci = np.empty((4, nc), np.int64)
    on_road = 0
    for c in range(nc):
        xk = xc[c]
        ax = abs(xk)
        ci[0, c] = 0
        if not ax <= ROAD_HALF_WIDTH_M:
            continue
        ci[0, c] = 1
        on_road += 1
        cf[0, c] = min(math.floor((xk + ROAD_HALF_WIDTH_M) * col_scale), cols - 1.0)
        for g in range(2):
            fx = (xk + fc[g, 0]) / fc[g, 1] * fc[g, 3] - 0.5
            i0 = np.floor(fx)
            ci[1 + g, c] = np.int64(min(max(i0, -1.0), fc[g, 5]) + fc[g, 6])
            cf[1 + g, c] = fx - i0
        cf[3, c] = ROAD_HALF_WIDTH_M - ax
        ci[3, c] = 0 if not ax > kerb else (2 if xk >= 0.0 else 1)
    if on_road == 0:
        return 0
    # Per row: [tz, tz_b] and [the dry-cell table's cell of column 0, table row of each grid].
    rf = np.empty((2, nr))
    ri = np.empty((3, nr), np.int64)
    for r in range(nr):
        zk = zr[r]
        rows = zk * row_scale
        if not (-max_rows < rows and rows < max_rows):
            return -1
        # The cell (floor(rows)·cols + column) mod cells of the point kernel: the row's part wrapped here (a
        # multiple of cols, as cells is), the column's (0 … cols − 1) added below (integers below 2^52: exact).
        ri[0, r] = np.int64(_wrap(math.floor(rows) * cols, cells))
        for g in range(2):
            fz = zk / fc[g, 2] * fc[g, 4] - 0.5
            j0 = np.floor(fz)
            ri[1 + g, r] = np.int64(_wrap(j0, fc[g, 4])) * fi[g, 1]
            rf[g, r] = fz - j0
    for r in range(nr):
        base, row_a, row_b, tz, tz_b = ri[0, r], ri[1, r], ri[2, r], rf[0, r], rf[1, r]
        for c in range(nc):
            if ci[0, c] == 0:
                continue
            side = ci[3, c]
            if side == 0:
                cell = base + np.int64(cf[0, c])
                if not (floors[0, cell] < crack_at or floors[1, cell] < puddle_at):
                    continue
            depth, _ = _standing_mm(table, row_a + ci[1, c], row_b + ci[2, c], cf[1, c], tz, cf[2, c], tz_b,
                                    crack_at, puddle_at)
            if side != 0:
                # gutter_depth_mm's S_x·(T − s) capped, and np.maximum with the standing water, NaN as NumPy's
                d = spread[side - 1, r] - cf[3, c]
                d = d if (d >= 0.0 or d != d) else 0.0
                stream = CROSS_SLOPE * d * 1000.0
                stream = stream if (stream <= GUTTER_MAX_MM or stream != stream) else GUTTER_MAX_MM
                depth = depth if (depth >= stream or depth != depth) else stream
            out[r, c] = depth
    return 0
