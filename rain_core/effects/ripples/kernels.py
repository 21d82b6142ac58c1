"""Compiled kernels of the ripples' CPU work (rain_core.jit): each replaces a chain of NumPy calls of the float32
solver (``solver_f32.WaveSolverF32``), the raindrop twin (``raindrops.raindrops``) or the frame's sources with one
loop.

Their NumPy twins stay the fallback and the oracle: ``WaveSolverF32._advance`` (:func:`leapfrog`),
``WaveSolver._bumps`` + ``_footprint`` + ``_deposit`` of the float32 solver (:func:`deposit_bumps`),
``raindrops.raindrops`` (:func:`raindrop_bumps`), ``wakes.wake_bumps`` (:func:`wake_bumps`), ``_bumps`` + the GPU
solver's float32 instance rows (:func:`gpu_bump_rows`) and the spray droplets' dents of
``RippleField.add_droplet_impacts`` (:func:`droplet_dents`). The same operations in the same order: the stencil and the
raindrops are exact (integer hashes, + − × ÷ and float32 rounding as NumPy's); the footprints add the float32
values libm's cos gives (estimated by a polynomial where that provably rounds the same), which may differ from
NumPy's cos by an ulp (tests/effects/ripples/test_kernels.py states the tolerances).
Units: m, cells (ints), m for heights; grids are (n, n) [iz, ix], C-contiguous.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.ripples.cache_hints import prefetch

_M32 = 0xFFFFFFFF
# The bump deposit lists a chunk of candidate cells (in the order it adds them), then evaluates and adds them in
# passes over the list: the cosines vectorised, the adds fetched ahead while the list was made.
DEPOSIT_CHUNK_CELLS = 2048
# A bound on |estimate − exact| / |peak| of a cell's deposit ½(1 + cos πd/r)·peak, where the estimate takes
# _cos_pi's polynomial instead of libm's cos: the two cosines differ by < 4e-16 on [0, π] (measured; a priori,
# libm's is within an ulp of the truth and the polynomial within 3e-15: truncation < 1e-19, roundings), and the
# value's own roundings add a few ulps: a ≥ 30-fold margin.
PROFILE_ERROR = 1e-13


@jit.kernel
def leapfrog(z, zp, mask, use_mask, k, alpha, kc2):
    """``k`` leapfrog sub-steps of the float32 (n, n) levels ``z`` (current) and ``zp`` (previous), in place:
    zp ← z + α(z − zp) + k_c²(Σ 4 neighbours − 4z) on the interior (× ``mask``, bool or 0/1, where
    ``use_mask``), then the two swap roles. The twin's float32 operations in its order. Returns whether the
    levels ended swapped (k odd: the new current level is in the array passed as ``zp``)."""
    n = z.shape[0]
    a = np.float32(alpha)
    kk = np.float32(kc2)
    four = np.float32(4.0)
    zero = np.float32(0.0)
    cur, prev = z, zp
    for _ in range(k):
        for i in range(1, n - 1):
            up = cur[i - 1]
            row = cur[i]
            down = cur[i + 1]
            out = prev[i]
            for j in range(1, n - 1):
                c = row[j]
                p = c - out[j]
                p = p * a
                p = p + c
                s = up[j] + down[j]
                s = s + row[j - 1]
                s = s + row[j + 1]
                s = s - c * four
                s = s * kk
                p = p + s
                if use_mask:
                    p = p * np.float32(mask[i, j])  # × exactly 0 or 1, in float32 as the twin
                out[j] = p
            out[0] = zero
            out[n - 1] = zero
        cur, prev = prev, cur
    return k % 2 == 1


@jit.kernel
def _cos_pi(rel):
    """cos(π·rel) for rel ∈ [0, 1] by its Taylor polynomial on [0, π/2] (to x²², truncation < 1e-19), reflected
    about π/2 (π − x is exact there): branch-free, so a loop of it vectorises. Within 4e-16 of libm's cos
    (tests/effects/ripples/test_kernels.py); an estimate only (see PROFILE_ERROR)."""
    x = np.pi * rel
    y = min(x, np.pi - x)
    u = y * y
    c = 1.0 + u * (-1.0 / 2 + u * (1.0 / 24 + u * (-1.0 / 720 + u * (1.0 / 40320 + u * (
        -1.0 / 3628800 + u * (1.0 / 479001600 + u * (-1.0 / 87178291200 + u * (1.0 / 20922789888000 + u * (
            -1.0 / 6402373705728000 + u * (1.0 / 2432902008176640000 + u * (-1.0 / 1124000727777607680000)))))))))))
    return c if x <= 0.5 * np.pi else -c


@jit.kernel
def _deposit_listed(zf, pf, mf, use_mask, cells, values, count):
    """The deposit of ``count`` listed cells, in their order (``deposit_bumps``): d / r, and the value
    ½(1 + cos πd/r)·peak estimated for all of them in one vectorised pass (rows of ``values``: d² → d / r, radius,
    peak, → estimate); then each cell inside the rim gets its value rounded to float32 (× the mask) and added to
    both levels. The estimate is used where it is certain to round to the same float32 as libm's cos would give
    (it lies more than PROFILE_ERROR·|peak| from 0 and from every float32 rounding boundary); otherwise (rarely:
    cells on the rim, or within 1e-13 of a float32 boundary) libm's cos decides. Returns the cells whose (exact)
    value is nonzero before the mask."""
    rel = values[0]
    radius = values[1]
    peak = values[2]
    estimate = values[3]
    for t in range(count):
        # np.divide: IEEE ÷ as `/`, without Numba's zero-division check, which stops the loop's vectorisation
        rel[t] = np.divide(math.sqrt(rel[t]), radius[t])
        estimate[t] = 0.5 * (1.0 + _cos_pi(rel[t])) * peak[t]
    deposited = 0
    for t in range(count):
        if not rel[t] < 1.0:
            continue
        cell = cells[t]
        m = np.float64(mf[cell]) if use_mask else 1.0
        v = estimate[t]
        err = abs(peak[t]) * PROFILE_ERROR
        certain = abs(v) > err  # the exact value is nonzero and of the estimate's sign
        if certain:
            v = v * m
            err = err * abs(m) + abs(v) * 1e-15  # the product's roundings
            f = np.float32(v)
            certain = np.float32(v - err) == np.float32(v + err)
        if not certain:
            v = 0.5 * (1.0 + math.cos(np.pi * rel[t])) * peak[t]
            if v == 0.0:
                continue
            f = np.float32(v * m) if use_mask else np.float32(v)
        deposited += 1
        zf[cell] += f
        pf[cell] += f
    return deposited


@jit.kernel
def deposit_bumps(z, zp, mask, use_mask, xs, zs, radii, amounts, cell_m, min_radius_m, length_m, batch_cells,
                  scratch, order, starts):
    """Raised-cosine bumps (centres ``xs``, ``zs`` m from cell (0, 0), radii m, peaks m) added to both float32
    levels ``z`` and ``zp`` (n, n) on the interior cells (× ``mask`` where ``use_mask``): the float32 solver's
    ``_bumps`` (widened to ``min_radius_m`` with the volume kept, off-grid and zero bumps dropped), its
    footprint (bumps by reach, stably; each bump's cells row by row; values ½(1 + cos πd/r)·peak in float64,
    with libm's cos: see _deposit_listed) and its deposit (each value rounded to float32 and added in that order:
    the twin's sums). ``batch_cells``:
    the twin's bound on a batch (bumps wider than it are clipped to the grid there: the same cells). Returns
    the number of cells that got a nonzero value before the mask (the twin's footprint size). Scratch (the
    cells' list is allocated per call): ``scratch`` float64 (2, ≥ K), ``order`` int64 (2, ≥ K), ``starts``
    int64 (≥ n + 2); −1, with nothing added, when the reaches span more levels than ``starts`` holds."""
    n = z.shape[0]
    h = cell_m
    count = xs.size
    r_eff = scratch[0]
    peak = scratch[1]
    reach = order[1]
    lo_reach, hi_reach = 1 << 62, -1
    for b in range(count):
        r = max(radii[b], min_radius_m)
        q = radii[b] / r
        a = amounts[b] * (q * q)
        r_eff[b] = r
        peak[b] = a
        x, y = xs[b], zs[b]
        if x > -r and x < length_m + r and y > -r and y < length_m + r and a != 0.0:
            reach[b] = np.int64(math.ceil(r / h))
            lo_reach = min(lo_reach, reach[b])
            hi_reach = max(hi_reach, reach[b])
        else:
            reach[b] = -1
    if hi_reach < 0:
        return 0
    # A stable counting sort by reach (the twin's argsort(kind="stable")).
    levels = hi_reach - lo_reach + 1
    if levels + 1 > starts.size:  # radii beyond the span (the callers' contract): the caller takes the twin
        return -1
    starts[:levels + 1] = 0
    for b in range(count):
        if reach[b] >= 0:
            starts[reach[b] - lo_reach + 1] += 1
    for v in range(levels):
        starts[v + 1] += starts[v]
    kept = starts[levels]
    sorted_bumps = order[0]
    for b in range(count):
        if reach[b] >= 0:
            slot = reach[b] - lo_reach
            sorted_bumps[starts[slot]] = b
            starts[slot] += 1
    zf = z.reshape(-1)
    pf = zp.reshape(-1)
    mf = mask.reshape(-1)
    # The list: each candidate's cell, d² (d / r once evaluated), radius and peak (a row never splits across chunks).
    cap = max(DEPOSIT_CHUNK_CELLS, n)
    cells = np.empty(cap, np.int64)
    values = np.empty((4, cap))
    deposited = 0
    listed = 0
    for o in range(kept):
        b = sorted_bumps[o]
        x, y, r, a, w = xs[b], zs[b], r_eff[b], peak[b], reach[b]
        c0 = np.int64(math.floor(x / h))
        r0 = np.int64(math.floor(y / h))
        if (2 * w + 1) * (2 * w + 1) > batch_cells:  # the twin's clipped window: the cells the rim can reach
            col_lo, col_hi = max(1, math.floor((x - r) / h)), min(n - 2, math.ceil((x + r) / h))
            row_lo, row_hi = max(1, math.floor((y - r) / h)), min(n - 2, math.ceil((y + r) / h))
        else:
            # The cell w before the centre's lies ≥ w cells off: outside a rim clearly inside w cells (the float32
            # twin's 2·w window; a rim within rounding of w cells keeps the reference's 2·w + 1).
            first = w if r > (w - 1e-6) * h else w - 1
            col_lo, col_hi = max(1, c0 - first), min(n - 2, c0 + w)
            row_lo, row_hi = max(1, r0 - first), min(n - 2, r0 + w)
        near = r * r * (1.0 + 1e-9)  # the reference's pre-test: sqrt and ÷ only for cells about inside the rim
        for row in range(row_lo, row_hi + 1):
            if listed + (col_hi - col_lo + 1) > cap:
                deposited += _deposit_listed(zf, pf, mf, use_mask, cells, values, listed)
                listed = 0
            start = row * n
            # The row's cells are added a few hundred bumps from now: fetch them on the way (a hint only).
            prefetch(zf, start + col_lo)
            prefetch(zf, start + col_hi)
            prefetch(pf, start + col_lo)
            prefetch(pf, start + col_hi)
            if use_mask:
                prefetch(mf, start + col_lo)
                prefetch(mf, start + col_hi)
            dz = row * h - y
            dz2 = dz * dz
            for col in range(col_lo, col_hi + 1):  # listed without a branch: the next slot is kept if about inside
                dx = col * h - x
                d2 = dx * dx + dz2
                cells[listed] = start + col
                values[0, listed] = d2
                values[1, listed] = r
                values[2, listed] = a
                listed += d2 <= near
    deposited += _deposit_listed(zf, pf, mf, use_mask, cells, values, listed)
    return deposited


@jit.kernel
def _pcg(v):
    """The PCG hash of one uint32 held in an int64 (``raindrops.pcg_int``; every product fits in 63 bits)."""
    state = (v * 747796405 + 2891336453) & _M32
    word = (((state >> ((state >> 28) + 4)) ^ state) * 277803737) & _M32
    return (word >> 22) ^ word


@jit.kernel
def _interior_cell(hsh, n):
    """``raindrops._interior_cell`` of one hash: 1 + ⌊k·(n − 2) / 2^24⌋, k its top 24 bits."""
    k = hsh >> 8
    m = n - 2
    q = ((k >> 12) * m + (((k & 0xFFF) * m) >> 12)) & _M32
    return (q >> 12) + 1


# The raindrops' inverse CDF starts its search from a table over the quantile's top QUANTILE_BUCKET_BITS bits
# (of 24): a bucket of u spans about one CDF node, so the search takes a step or two instead of its 9 halvings
# (dependent loads, a ~50 ns chain per drop).
QUANTILE_BUCKET_BITS = 10


@jit.kernel
def _quantile_buckets(cdf, first):
    """``first[j]`` (j = 0 … 2^QUANTILE_BUCKET_BITS) the last node with cdf ≤ j / 2^QUANTILE_BUCKET_BITS (0 where
    none is): a quantile u of bucket j, in [cdf[0], cdf[−1]), has its node (the last with cdf ≤ u) in
    [first[j], first[j + 1]]. A CDF that ever decreases gets the whole range in every bucket (the full search)."""
    nodes = cdf.size
    buckets = first.size - 1
    i = 0
    for j in range(buckets + 1):
        edge = j / buckets  # exact: a power of two
        while i + 1 < nodes and cdf[i + 1] <= edge:
            i += 1
        first[j] = i
    for i in range(nodes - 1):
        if cdf[i + 1] < cdf[i]:
            first[:buckets] = 0
            first[buckets] = nodes - 1
            break


@jit.kernel
def raindrop_bumps(key, count, n, cell_m, water, use_water, cdf, grid, p_d, dp_d, d_min_mm, d_max_mm,
                   crater_m_per_mm, peak_per_momentum, out, wet):
    """``raindrops.raindrops`` of a batch without its index: the rows of ``out`` (float64 (4, ≥ count)) take
    (x m, z m, crater radius m, dent m) of the candidates 0 … count − 1 of stream ``key`` whose centre's cell
    holds water (``water`` (n, n) bool or 0/1: > 0.5, where ``use_water``), in index order; returns how many. The
    same integer hashes, np.interp's inverse CDF (``cdf`` → ``grid``, mm) and the momentum table (``p_d``,
    ``dp_d`` kg·m/s over [d_min_mm, d_max_mm]), operation for operation. ``wet``: bool scratch of ≥ count."""
    xs = out[0]
    zs = out[1]
    radii = out[2]
    dents = out[3]
    wf = water.reshape(-1)
    nodes = cdf.size
    per_mm = (p_d.size - 1) / (d_max_mm - d_min_mm)
    top = p_d.size - 2
    scale = 1.0 / (1 << 12)
    half = 1 << 11
    first = np.empty((1 << QUANTILE_BUCKET_BITS) + 1, np.int64)
    _quantile_buckets(cdf, first)
    # First which candidates land on water, without a branch: the mask's reads (scattered over n² cells) then
    # overlap instead of waiting one by one behind a mispredicted branch. The centres' cells in a loop of their
    # own: integer arithmetic only, which the compiler vectorises (the mask's byte reads would stop it).
    wet[:count] = True
    if use_water:
        cells = np.empty(count, np.int64)
        for index in range(count):
            h1 = _pcg(_pcg((index & _M32) ^ key))
            cells[index] = _interior_cell(_pcg(h1), n) * n + _interior_cell(h1, n)
        for index in range(count):
            wet[index] = wf[cells[index]] > 0.5
    m = 0
    for index in range(count):
        if not wet[index]:
            continue
        h0 = _pcg((index & _M32) ^ key)
        h1 = _pcg(h0)
        h2 = _pcg(h1)
        ix = _interior_cell(h1, n)
        iz = _interior_cell(h2, n)
        h3 = _pcg(h2)
        x = ix + ((h3 & 0xFFF) - half) * scale
        z = iz + (((h3 >> 12) & 0xFFF) - half) * scale
        # np.interp(u, cdf, grid): the last node with cdf ≤ u, then its slope (NumPy's formula and branches).
        k = h0 >> 8
        u = k * (1.0 / 16777216.0)
        if u < cdf[0]:
            diam = grid[0]
        elif u > cdf[nodes - 1]:
            diam = grid[nodes - 1]
        else:
            lo, hi = 0, nodes - 1
            if u >= cdf[hi]:
                lo = hi
            else:
                bucket = k >> (24 - QUANTILE_BUCKET_BITS)  # the node lies in [first[bucket], first[bucket + 1]]
                lo, hi = first[bucket], min(first[bucket + 1] + 1, hi)
                while hi - lo > 1:  # cdf[lo] ≤ u < cdf[hi]
                    mid = (lo + hi) >> 1
                    if cdf[mid] <= u:
                        lo = mid
                    else:
                        hi = mid
            if lo == nodes - 1 or cdf[lo] == u:
                diam = grid[lo]
            else:
                slope = (grid[lo + 1] - grid[lo]) / (cdf[lo + 1] - cdf[lo])
                diam = slope * (u - cdf[lo]) + grid[lo]
        t = (diam - d_min_mm) * per_mm
        i = min(np.int64(t), top)
        t -= i
        xs[m] = x * cell_m
        zs[m] = z * cell_m
        radii[m] = crater_m_per_mm * diam
        dents[m] = peak_per_momentum * (p_d[i] + t * dp_d[i])
        m += 1
    return m


@jit.kernel
def wake_bumps(wheels, ox, oz, length_m, cell_m, max_radius_m, wake_gain, min_radius_m, wake_ref_m_s):
    """Twin: ``wakes.wake_bumps`` (with ``clip_segments``). W wheels, rows (x0, z0, x1, z1 world m, speed m/s, film
    depth mm, tyre width m), for a window whose cell (0, 0) is at world (ox, oz) m: the trough bumps of every
    wheel, then the crests on one side, then the other (the twin's order), as (x m, z m from cell (0, 0),
    radius m, peak m), and the bumps laid per wheel. The twin's operations in its order (np.hypot is libm's)."""
    w = wheels.shape[0]
    seg = np.empty((w, 10))  # ax, az, dx, dz, length, radius, peak, nx, nz, count (of the live wheels)
    counts = np.zeros(w, np.int64)
    troughs = 0
    crests = 0
    for i in range(w):
        radius = min(0.5 * wheels[i, 6], max_radius_m)
        trough = wake_gain * wheels[i, 5] * 1e-3 * wheels[i, 4] / wake_ref_m_s
        ax, az = wheels[i, 0] - ox, wheels[i, 1] - oz
        bx, bz = wheels[i, 2] - ox, wheels[i, 3] - oz
        # Liang–Barsky against the window grown by radius + 2 cells (the twin's four edges, flat ones included).
        pad = radius + 2.0 * cell_m
        lo, hi = -pad, length_m + pad
        dx, dz = bx - ax, bz - az
        t0, t1 = 0.0, 1.0
        inside = True
        for e in range(4):
            if e == 0:
                p, q = -dx, ax - lo
            elif e == 1:
                p, q = dx, hi - ax
            elif e == 2:
                p, q = -dz, az - lo
            else:
                p, q = dz, hi - az
            if p == 0.0:
                if q < 0.0:
                    inside = False
            elif p < 0.0:
                t0 = max(t0, q / p)
            else:
                t1 = min(t1, q / p)
        if not (inside and t0 <= t1) or trough == 0.0:
            continue
        ax, az, bx, bz = ax + t0 * dx, az + t0 * dz, ax + t1 * dx, az + t1 * dz
        dx, dz = bx - ax, bz - az
        length = math.hypot(dx, dz)
        count = max(1, np.int64(math.ceil(length / cell_m)))
        moving = length > 0.0
        spacing = length / count if moving else radius
        peak = -trough * min(spacing / radius, 1.0)
        reach = max(radius, min_radius_m)
        nx = (-dz / length if moving else 0.0) * 2.0 * reach
        nz = (dx / length if moving else 0.0) * 2.0 * reach
        seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4] = ax, az, dx, dz, length
        seg[i, 5], seg[i, 6], seg[i, 7], seg[i, 8], seg[i, 9] = radius, peak, nx, nz, count
        counts[i] = count * (3 if moving else 1)
        troughs += count
        if moving:
            crests += count
    total = troughs + 2 * crests
    xs, zs, radii, peaks = np.empty(total), np.empty(total), np.empty(total), np.empty(total)
    k = 0
    c = troughs
    for i in range(w):
        if counts[i] == 0:
            continue
        ax, az, dx, dz, length = seg[i, 0], seg[i, 1], seg[i, 2], seg[i, 3], seg[i, 4]
        radius, peak, nx, nz, count = seg[i, 5], seg[i, 6], seg[i, 7], seg[i, 8], seg[i, 9]
        moving = length > 0.0
        for b in range(np.int64(count)):
            t = (b + 0.5) / count
            x, z = ax + t * dx, az + t * dz
            xs[k], zs[k], radii[k], peaks[k] = x, z, radius, peak
            k += 1
            if moving:
                crest = -0.5 * peak
                xs[c], zs[c], radii[c], peaks[c] = x + nx, z + nz, radius, crest
                xs[c + crests], zs[c + crests], radii[c + crests], peaks[c + crests] = x - nx, z - nz, radius, crest
                c += 1
    return xs, zs, radii, peaks, counts


@jit.kernel
def shift_rows(a, dz):
    """``scroll.shift_in_place(a, 0, dz, fill)`` of a C-contiguous 2-D array before the fill: a[iz] = a[iz + dz]
    for the rows that stay, row by row in the direction that reads each row before it is overwritten (NumPy
    copies an overlapping move through a temporary: a fresh n² buffer every scroll)."""
    n_z, n_x = a.shape
    if dz > 0:
        for i in range(n_z - dz):
            src = a[i + dz]
            dst = a[i]
            for j in range(n_x):
                dst[j] = src[j]
    elif dz < 0:
        for i in range(n_z - 1, -dz - 1, -1):
            src = a[i + dz]
            dst = a[i]
            for j in range(n_x):
                dst[j] = src[j]


@jit.kernel
def gpu_bump_rows(xs, zs, radii, amounts, min_radius_m, length_m, inv_h, out):
    """Twin: ``WaveSolver._bumps`` and ``WaveSolverGPU``'s instance rows. K bumps (x, z m, radius m, peak m):
    those that touch the grid, widened to ``min_radius_m`` with their volume kept, written in order into ``out``
    ((≥ K, 4) float32: x, z, radius in cells (× ``inv_h``), peak m, each rounded from float64 as NumPy casts).
    Returns the rows written."""
    k = 0
    for i in range(xs.shape[0]):
        r = radii[i]
        r_eff = max(r, min_radius_m)
        q = r / r_eff
        a = amounts[i] * (q * q)  # the twin's (radii / r_eff) ** 2: NumPy squares by one multiplication
        x = xs[i]
        z = zs[i]
        if x > -r_eff and x < length_m + r_eff and z > -r_eff and z < length_m + r_eff and a != 0.0:
            out[k, 0] = np.float32(x * inv_h)
            out[k, 1] = np.float32(z * inv_h)
            out[k, 2] = np.float32(r_eff * inv_h)
            out[k, 3] = np.float32(a)
            k += 1
    return k


@jit.kernel
def droplet_dents(impacts, ox, oz, dent_per_momentum, max_dent_m, radius_m, out):
    """Twin: ``RippleField.add_droplet_impacts``'s arithmetic. N droplets (x m, z m world, momentum kg·m/s):
    the rows without NaN or inf, in order, written into ``out`` ((4, ≥ N): x, z m from cell (0, 0) at world
    (ox, oz), ``radius_m``, dent = clamp(dent_per_momentum × |momentum|, ±max_dent_m) m). Returns the rows."""
    k = 0
    for i in range(impacts.shape[0]):
        x = impacts[i, 0]
        z = impacts[i, 1]
        p = impacts[i, 2]
        if not (math.isfinite(x) and math.isfinite(z) and math.isfinite(p)):
            continue
        out[0, k] = x - ox
        out[1, k] = z - oz
        out[2, k] = radius_m
        out[3, k] = min(max(dent_per_momentum * abs(p), -max_dent_m), max_dent_m)
        k += 1
    return k
