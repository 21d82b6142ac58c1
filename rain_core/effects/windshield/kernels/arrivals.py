"""Kernels of the rain arriving on the glass: the arrival law and its table, sampling and landing arrivals,
and the full glass's surplus given to drops already there. Twins: ``arrivals``, ``sim._arrive_fast``,
``sim._give_to_drops``. Units: m, s, kg, mm for drop diameters."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield.constants import (
    M_OBJECT_MIN,
    SPLASH_MAX,
)
from rain_core.effects.windshield.drop_rows import CELL, KEY, RB, M, S, T
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.kernels.common import _INF, _KG_PER_MM3, _SLICES, _SPLASH_HI, _SPLASH_LO, film_cell


@jit.kernel
def sample_arrivals(u, n, cdf, coef, total, w0, dw, height, imp, cells, obj):
    """``WindshieldSim._arrive_fast``'s draws made arrivals: ``n`` raindrops from the uniform numbers ``u`` (3n:
    the size's quantile, then across and up the glass), the size law's CDF ``cdf`` over the diameter grid and
    ``coef`` (ArrivalTable._coef: per grid interval the diameter's slope, the CDF, the diameter, the closing
    speed's slope and the closing speed), ``total`` the CDF's end; the glass's width ``w0`` (m) at its bottom,
    growing by ``dw`` per metre up, ``height`` (m). Writes ``imp`` rows s, t (m), diameter (mm), splash
    fraction, mass and kept mass (kg), the film cell of each to ``cells`` and the rows of those that are
    objects (kept mass ≥ M_OBJECT_MIN) to ``obj``; returns how many are."""
    dwh = dw * height
    n_cdf = len(cdf)
    last = n_cdf - 2
    # ArrivalTable.sample's interval: the last grid point at or below x (cdf.searchsorted(x, "right") − 1), found
    # by a walk from the interval at the left edge of x's slice of the CDF (a table of _SLICES, made per call):
    # the walk goes down as well as up, so the answer is the search's whatever the rounding of the slice.
    slice_j = np.empty(_SLICES, np.int64)
    j = 0
    for b in range(_SLICES):
        edge = b * (total / _SLICES)
        while j + 1 < n_cdf and cdf[j + 1] <= edge:
            j += 1
        slice_j[b] = j
    n_obj = 0
    for k in range(n):
        x = u[k] * total
        j = slice_j[min(int(u[k] * _SLICES), _SLICES - 1)]
        while j > 0 and cdf[j] > x:
            j -= 1
        while j + 1 < n_cdf and cdf[j + 1] <= x:
            j += 1
        j = min(j, last)
        d = (x - coef[j, 1]) * coef[j, 0] + coef[j, 2]
        closing = (d - coef[j, 2]) * coef[j, 3] + coef[j, 4]
        m = _KG_PER_MM3 * (d * d * d)
        # GlassGeometry.sample_uniform: uniform over the trapezoid.
        q = u[n + k] * (w0 + 0.5 * dwh)
        up = 2.0 * q / (w0 + math.sqrt(w0 * w0 + 2.0 * dwh * q)) if dwh != 0 else q / w0
        t = min(max(up, 0.0), 1.0) * height
        s = (u[2 * n + k] - 0.5) * (w0 + dw * t)
        splash = min(max((closing - _SPLASH_LO) / (_SPLASH_HI - _SPLASH_LO), 0.0), 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        imp[0, k] = s
        imp[1, k] = t
        imp[2, k] = d
        imp[3, k] = splash
        imp[4, k] = m
        imp[5, k] = keep
        cells[k] = film_cell(s, t, w0, dw, height)
        if keep >= M_OBJECT_MIN:
            obj[n_obj] = k
            n_obj += 1
    return n_obj


@jit.kernel
def land_arrivals(flat, acc, cells, imp, n, obj, n_obj, room, placed):
    """What of ``sample_arrivals``' arrivals goes to the film (``flat``, kg per cell): all but the kept mass of
    the first ``room`` objects (``obj``) and of the others ``placed`` (bool, joined to a drop); written to
    ``imp`` row 6 and added per cell (``acc``: a zeroed scratch per cell, left zeroed) as the twin's bincount."""
    for k in range(n):
        imp[6, k] = 1.0  # (until below: 0 where it landed as a drop or on one)
    for q in range(n_obj):
        if q < room or placed[q - room]:
            imp[6, obj[q]] = 0.0
    for k in range(n):
        to_film = imp[4, k] - (imp[5, k] if imp[6, k] == 0.0 else 0.0)
        imp[6, k] = to_film
        acc[cells[k]] += to_film
    for c in range(flat.shape[0]):
        flat[c] += acc[c]
        acc[c] = 0.0


@jit.kernel
def drops_in_cells(buf, n, any_dirty, w0, dw, height, cells, mark, per_cell, start, hits, members, c_out, first_out,
                   placed, c_hit):
    """For ``WindshieldSim._give_to_drops``: the drops among rows [:n] in each of the film ``cells`` (flat
    indices), grouped by cell in row order into ``members``; per query its cell's count ``c_out`` and where its
    group starts ``first_out``, whether it has any (``placed``, bool) and the counts of those that have, in order,
    into ``c_hit``; returns how many have. The film cell of a row is its CELL column, or for a row placed this
    sub-step (KEY DIRTY; only looked at if ``any_dirty``) computed. ``mark``, ``per_cell``, ``start``: zeroed
    scratch per cell, left zeroed; ``hits`` (2, ·) int64 scratch over the rows."""
    k = len(cells)
    for q in range(k):
        mark[cells[q]] = 1
    m = 0  # the rows in a marked cell, in order, and their cells
    for i in range(n):
        if any_dirty and buf[i, KEY] == _DIRTY:
            c = film_cell(buf[i, S], buf[i, T], w0, dw, height)
        else:
            c = int(buf[i, CELL])
        if mark[c]:
            per_cell[c] += 1
            hits[0, m] = i
            hits[1, m] = c
            m += 1
    at = 0
    n_hit = 0
    for q in range(k):
        c = cells[q]
        if mark[c] == 1:
            mark[c] = 2
            start[c] = at
            at += per_cell[c]
        c_out[q] = per_cell[c]
        first_out[q] = start[c]
        placed[q] = per_cell[c] > 0
        if placed[q]:
            c_hit[n_hit] = per_cell[c]
            n_hit += 1
    for h in range(m):
        c = hits[1, h]
        members[start[c]] = hits[0, h]
        start[c] += 1
    for q in range(k):
        c = cells[q]
        mark[c] = 0
        per_cell[c] = 0
        start[c] = 0
    return n_hit


@jit.kernel
def give_to_drops(buf, fresh, members, first, c, u, mass, picks, pick_m):
    """Add each ``mass`` (kg) whose cell has drops (``c`` > 0) to a random one of them (``drops_in_cells``'
    ``members`` from ``first``; picked by the next uniform of ``u`` as ``constants.uniform_index`` picks), in
    order; the drop is tested again (RB) and fresh. Writes the rows to ``picks`` and their masses once all are
    added to ``pick_m``; returns how many. The caller sets their radius from their mass."""
    n_p = 0
    for q in range(len(c)):
        if c[q] > 0:
            i = members[first[q] + min(int(u[n_p] * c[q]), c[q] - 1)]
            buf[i, M] += mass[q]
            buf[i, RB] = _INF
            fresh[i] = True
            picks[n_p] = i
            n_p += 1
    for j in range(n_p):
        pick_m[j] = buf[picks[j], M]
    return n_p


@jit.kernel
def arrival_law(d_grid, v_grid, shape, n_up, a, closing, cdf, coef):
    """``WindshieldSimReference.arrival_rate_per_s``'s law and ``ArrivalTable``'s interpolation table in one loop
    over the diameter grid ``d_grid`` (mm; terminal speeds ``v_grid`` m/s, the size law's ``shape`` per diameter):
    for the glass's world normal's up component ``n_up`` and the air's closing offset ``a`` (m/s), the closing
    speed per diameter (m/s) into ``closing``, the flux-weighted CDF (trapezoid rule) into ``cdf``, and per grid
    interval the rows of ArrivalTable._coef into ``coef``."""
    k = d_grid.shape[0]
    for i in range(k):
        closing[i] = max(v_grid[i] * n_up - a, 0.0)
    cdf[0] = 0.0
    for i in range(k - 1):
        x = 0.5 * (shape[i + 1] * closing[i + 1] + shape[i] * closing[i]) * (d_grid[i + 1] - d_grid[i])
        cdf[i + 1] = x if i == 0 else cdf[i] + x
    for i in range(k - 1):
        dd = d_grid[i + 1] - d_grid[i]
        dc = cdf[i + 1] - cdf[i]
        coef[i, 0] = dd / dc if dc != 0.0 else _INF  # (a flat stretch: never selected)
        coef[i, 1] = cdf[i]
        coef[i, 2] = d_grid[i]
        coef[i, 3] = (closing[i + 1] - closing[i]) / dd
        coef[i, 4] = closing[i]
