"""Compiled kernels of the windshield's water pass (rain_core.jit): each builds, in one loop, what the effect
uploads every frame, instead of a chain of small NumPy calls.

Their NumPy twins stay the fallback and the oracle: ``splats.DropRows.rows`` (:func:`drop_rows`),
``splats.film_splats`` (:func:`film_rows`, :func:`impact_rows`) and the effect's coarse film bits,
``film_thickness_m`` × 1e6 through ``splats.half_bits`` (:func:`coarse_half_bits`, which divides by ρ × area
itself). The same float64 operations in the same order, each rounded to float32 once where the twin casts: the
same bits (tests/effects/windshield/test_render_kernels.py). Units: m, m/s, kg.
"""

from __future__ import annotations

import math

from rain_core import jit

_HALF_BIAS = (127 - 15) << 10  # splats._HALF_BIAS: float32's exponent bias over float16's, in a half's bit positions


@jit.kernel
def drop_rows(block, n, s_col, a_col, beads, w_scale, ends, frames, out):
    """The drop buffer's rows (``splats.DROP_ROW`` as (rows, 5) float32 ``out``), returns how many it wrote.

    Drops first: row i is ``block[i]``'s columns s_col … s_col + 3 (s, t m, vs, vt m/s: adjacent in the drop
    array) and a_col (contact radius m), for i < n. Then each bead bin (blade b, bin j, in that order) with water:
    its half-cylinder radius w = min(sqrt(beads[b, j] kg × w_scale[b]), 0.01) m, and if w > 0 a line from its
    ends (m along the blade, ``ends[b, j, 0:2]``) on the blade's frame ``frames[b]`` = (cos, sin of its angle,
    pivot s, t moved ahead m) and radius −w. ``out`` must hold n + beads.size rows."""
    for i in range(n):
        out[i, 0] = block[i, s_col]
        out[i, 1] = block[i, s_col + 1]
        out[i, 2] = block[i, s_col + 2]
        out[i, 3] = block[i, s_col + 3]
        out[i, 4] = block[i, a_col]
    row = n
    for b in range(beads.shape[0]):
        c = frames[b, 0]
        s = frames[b, 1]
        ps = frames[b, 2]
        pt = frames[b, 3]
        scale = w_scale[b]
        for j in range(beads.shape[1]):
            w = min(math.sqrt(beads[b, j] * scale), 0.01)
            if w > 0.0:
                e0 = ends[b, j, 0]
                e1 = ends[b, j, 1]
                out[row, 0] = e0 * c + ps
                out[row, 1] = e0 * s + pt
                out[row, 2] = e1 * c + ps
                out[row, 3] = e1 * s + pt
                out[row, 4] = -w
                row += 1
    return row


@jit.kernel
def film_rows(trails, impacts, min_width_m, trail_um, min_splash_m, max_splashes, seed0, out):
    """The film deposits' rows (``splats.film_splats``'s (rows, 8) float32 layout) into ``out``; returns how
    many it wrote. First a line per trail (``trails`` (k, 5): s0, t0, s1, t1 m, drop radius a m), at least
    ``min_width_m`` wide with the same water (``trail_um`` µm × a / width) and kind 1; then the splash of each
    impact (``impacts`` (m, 4): s, t m, splash radius m, film thickness m) with a radius of at least
    ``min_splash_m``, the first ``max_splashes`` of them, thickness in µm, kind 2, seed (seed0 + index) mod 65536.
    ``out`` must hold k + min(m, max_splashes) rows."""
    k = trails.shape[0]
    for i in range(k):
        out[i, 0] = trails[i, 0]
        out[i, 1] = trails[i, 1]
        out[i, 2] = trails[i, 2]
        out[i, 3] = trails[i, 3]
        a = trails[i, 4]
        a_vis = max(a, min_width_m)
        out[i, 4] = a_vis
        out[i, 5] = trail_um * a / a_vis
        out[i, 6] = 1.0
        out[i, 7] = 0.0
    row = k
    for i in range(impacts.shape[0]):
        if row - k >= max_splashes:
            break
        r = impacts[i, 2]
        if r >= min_splash_m:
            s = impacts[i, 0]
            t = impacts[i, 1]
            out[row, 0] = s
            out[row, 1] = t
            out[row, 2] = s
            out[row, 3] = t
            out[row, 4] = r
            out[row, 5] = impacts[i, 3] * 1e6
            out[row, 6] = 2.0
            out[row, 7] = (row - k + seed0) % 65536
            row += 1
    return row


@jit.kernel
def impact_rows(s, t, d_mm, splash, obj, a_obj, to_film, r_per_mm, rho_pi, min_splash_m, max_splashes, k, seed0,
                row, out):
    """``film_rows``' splash rows of one sub-step's impacts, from the columns the fast path keeps them as
    (``WindshieldSim.impact_columns``: s, t m, raindrop diameter mm, splash fraction, the rows ``obj``
    (ascending) that became drops with their radius ``a_obj`` m, film kg) instead of ``frame_impacts``' (m, 4)
    array: its splash radius (d_mm × ``r_per_mm``, or the drop's radius, × (1.5 + 4 splash)) and film thickness
    (kg / (``rho_pi`` × r × r)) with its operations. Rows from ``row`` on, ``k`` the trail rows before the
    splashes (the seed counts from there); returns the next row."""
    j = 0
    n_obj = obj.shape[0]
    for i in range(s.shape[0]):
        if row - k >= max_splashes:
            break
        if j < n_obj and obj[j] == i:
            r = a_obj[j]
            j += 1
        else:
            r = d_mm[i] * r_per_mm
        r *= 1.5 + 4.0 * splash[i]
        if r >= min_splash_m:
            out[row, 0] = s[i]
            out[row, 1] = t[i]
            out[row, 2] = s[i]
            out[row, 3] = t[i]
            out[row, 4] = r
            out[row, 5] = to_film[i] / (rho_pi * r * r) * 1e6
            out[row, 6] = 2.0
            out[row, 7] = (row - k + seed0) % 65536
            row += 1
    return row


@jit.kernel
def coarse_half_bits(film_kg, area_m2, rho, f32, u32, out):
    """The coarse film as the float16 bits (``out`` uint16) of its thickness in µm, at most 6e4 (half floats end
    at 65504): ``film_thickness_m``'s film_kg / (rho kg/m³ × area_m2) m, × 1e6, rounded to float32 in ``f32`` and
    then to the nearest half as ``splats.half_bits`` does on ``u32``, f32's bits (the same memory). All six flat,
    of one length. (The twin's (rho × area) table is a new array a frame, cold in the cache: here it is not.)"""
    for i in range(film_kg.shape[0]):
        f32[i] = min(film_kg[i] / (rho * area_m2[i]) * 1e6, 6e4)
        bits = (int(u32[i]) + 4096) >> 13  # half of the 13 dropped bits rounds to nearest (int: no wrapping)
        half = bits - _HALF_BIAS
        out[i] = half if half > 0 else 0
