"""Kernel of the merge test: the pair search over the near grid and the touching groups (union-find) of
``merge_drops``. Twin: ``fast_merging.FastMerging._merge_moves`` with ``grid.PairFinder``. Units: m, s, kg."""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.windshield.constants import (
    MERGE_CELLS_MAX,
    MERGE_PAIRS_MAX,
)
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY, RB, TRAIL, A, M, S, T
from rain_core.effects.windshield.grid import _BOX_MARGIN_CELLS, NEAR_CELL_M
from rain_core.effects.windshield.kernels.common import _INF, _N0, _N1, _O0, _O1, _P1


@jit.kernel
def _root(parent, x):
    """The root of x in the union-find ``parent`` (path halving: a parent is never larger than its child)."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@jit.kernel
def _motion(x, buf, gcol, gidx):
    """Drop x's start s, t and displacement ds, dt (m) this step: ``gcol``'s if it slid (``gidx``), else its row."""
    g = gidx[x]
    if g >= 0:
        return gcol[0, g], gcol[1, g], gcol[2, g], gcol[3, g]
    return buf[x, S], buf[x, T], 0.0, 0.0


@jit.kernel
def _touch(x, y, buf, gcol, gidx):
    """Whether drops x and y touched during the step: the closest approach of their straight motions within the
    sum of their radii (merging.Merging's test, as FastMerging computes it)."""
    s0x, t0x, dsx, dtx = _motion(x, buf, gcol, gidx)
    s0y, t0y, dsy, dty = _motion(y, buf, gcol, gidx)
    ps = s0x - s0y
    pt = t0x - t0y
    qs = dsx - dsy
    qt = dtx - dty
    dd = max(qs * qs + qt * qt, 1e-300)
    tau = min(max(-(ps * qs + pt * qt) / dd, 0.0), 1.0)
    ps += tau * qs
    pt += tau * qt
    rr = buf[x, A] + buf[y, A]
    return ps * ps + pt * pt <= rr * rr


@jit.kernel
def _near(x, y, mid):
    """Whether the midpoints of the motions of x and y (``mid``: s, t and reach, m) lie within the sum of their reaches
    on both axes: a necessary condition of ``_touch`` (a point of a motion lies within half its length of its
    midpoint), with a margin far above rounding. Read from three small arrays, it spares most candidates the
    gathers of two drop rows."""
    r = (mid[2, x] + mid[2, y]) * (1.0 + 1e-6) + 1e-12
    return abs(mid[0, x] - mid[0, y]) <= r and abs(mid[1, x] - mid[1, y]) <= r


@jit.kernel
def _join(x, y, parent, nodes, k):
    """Union of x and y (the smaller root wins), their entries made on first sight (``nodes``: those seen, ``k``
    of them); returns the new count."""
    for z in (x, y):
        if parent[z] < 0:
            parent[z] = z
            nodes[k] = z
            k += 1
    rx = _root(parent, x)
    ry = _root(parent, y)
    if rx < ry:
        parent[ry] = rx
    elif ry < rx:
        parent[rx] = ry
    return k


@jit.kernel
def merge_drops(buf, n, n_moved, fresh, n_go, go, gcol, gidx, active, parent, nodes, mark, sums, count, head, nxt,
                owner, ekey, out, mid):
    """``FastMerging._merge_moves`` (with ``grid.PairFinder``'s search) on rows [:n]: of the first ``n_moved``,
    the ``n_go`` drops in ``go`` moved as ``gcol`` says (``move_drops``), the others stayed. Drops that touched
    during the step join into the smallest row of their group (mass-weighted means of S … TRAIL; the caller sets
    its radius from its mass, a cube root); ``fresh`` (bool) is updated as the twin does.

    Candidates as PairFinder finds them, with its work budget: all drops reaching ≤ NEAR_CELL_M / 2 from the 3 × 3
    near cells around each active one (past MERGE_PAIRS_MAX candidates the remaining lookups are deferred: those
    drops stay fresh); otherwise the drops sharing a near cell of their boxes. If those boxes pass the budget
    (MERGE_CELLS_MAX cells, MERGE_PAIRS_MAX pairs) nothing is changed and the result is -1: the caller runs the
    twin (its far grid). Scratch over the rows: ``gidx``, ``parent`` int64 (-1, left so), ``active`` bool,
    ``nodes`` int64, ``mark`` bool (False, left so), ``sums`` (7, ·); per near cell ``count`` (0) and ``head``
    (-1) int64, left so; per box cell ``nxt``, ``owner``, ``ekey`` int64; ``mid`` (3, ·) each drop's motion's
    midpoint s, t and reach (m), for ``_near``. Writes the groups' rows to ``out``:
    roots, then the rows joined into them (ascending). Returns (status, roots, joined)."""
    if n < 2:
        for x in range(n):
            fresh[x] = False
        return 0, 0, 0
    for g in range(n_go):
        gidx[go[g]] = g
    any_active = False
    all_near = True
    for x in range(n):
        g = gidx[x]
        act = fresh[x] and x < n_moved
        ms, mt, reach = buf[x, S], buf[x, T], buf[x, A]
        if g >= 0:
            act = act or gcol[2, g] != 0.0 or gcol[3, g] != 0.0
            ms = gcol[0, g] + 0.5 * gcol[2, g]
            mt = gcol[1, g] + 0.5 * gcol[3, g]
            reach += 0.5 * gcol[4, g]
        mid[0, x] = ms
        mid[1, x] = mt
        mid[2, x] = reach
        active[x] = act
        any_active = any_active or act
        all_near = all_near and reach <= 0.5 * NEAR_CELL_M
    status = 0
    k = 0  # drops in a touching pair
    n_def = 0  # deferred lookups (their rows, in out's tail)
    if any_active:
        inv = 1.0 / NEAR_CELL_M
        if all_near:
            # Near grid (PairFinder.pairs): every drop in the cell of its centre; each active one looks in the 3 × 3
            # cells around its own, in row order, until the budget runs out.
            for x in range(n):
                k0 = min(max(int((mid[0, x] - _O0) * inv), 0), _N0 - 1)
                k1 = min(max(int((mid[1, x] - _O1) * inv), 0), _N1 - 1)
                key = k0 * _P1 + (k1 + _P1 + 1)
                ekey[x] = key
                nxt[x] = head[key]
                head[key] = x
                count[key] += 1
            cum = 0
            for q in range(n):
                if not active[q]:
                    continue
                late = False
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        cell = ekey[q] + di * _P1 + dj
                        c = count[cell]
                        if c == 0:
                            continue
                        cum += c
                        if cum > MERGE_PAIRS_MAX:
                            late = True
                            continue
                        f = head[cell]
                        while f >= 0:
                            if (f != q and q < n_moved and f < n_moved and _near(q, f, mid)
                                    and _touch(q, f, buf, gcol, gidx)):
                                k = _join(q, f, parent, nodes, k)
                            f = nxt[f]
                if late:
                    out[n - 1 - n_def] = q
                    n_def += 1
            for x in range(n):
                head[ekey[x]] = -1
                count[ekey[x]] = 0
        else:
            # Boxes (PairFinder._box_pairs): every drop in each near cell its box (centre ± reach) touches; an active
            # drop's candidates are the drops sharing a cell with it.
            total = 0
            n_pairs = 0
            cap = min(MERGE_CELLS_MAX, nxt.shape[0])
            for x in range(n):
                cs = (mid[0, x] - _O0) * inv
                ct = (mid[1, x] - _O1) * inv
                rc = mid[2, x] * inv + _BOX_MARGIN_CELLS
                lo0 = int(min(max(cs - rc, 0.0), _N0 - 1.0))
                lo1 = int(min(max(ct - rc, 0.0), _N1 - 1.0))
                hi0 = int(min(max(cs + rc, 0.0), _N0 - 1.0))
                hi1 = int(min(max(ct + rc, 0.0), _N1 - 1.0))
                cells = (hi0 - lo0 + 1) * (hi1 - lo1 + 1)
                if total + cells > cap:
                    status = -1
                    break
                for c0 in range(lo0, hi0 + 1):
                    for c1 in range(lo1, hi1 + 1):
                        key = c0 * _N1 + c1
                        ekey[total] = key
                        owner[total] = x
                        nxt[total] = head[key]
                        head[key] = total
                        n_pairs += count[key]
                        count[key] += 1
                        total += 1
            if n_pairs > MERGE_PAIRS_MAX:
                status = -1
            if status == 0:
                for e in range(total):
                    x = owner[e]
                    if not active[x] or x >= n_moved:
                        continue
                    f = head[ekey[e]]
                    while f >= 0:
                        y = owner[f]
                        # A pair of active drops is found from the smaller one's side.
                        if (y != x and y < n_moved and not (active[y] and y < x) and _near(x, y, mid)
                                and _touch(x, y, buf, gcol, gidx)):
                            k = _join(x, y, parent, nodes, k)
                        f = nxt[f]
            for e in range(total):
                head[ekey[e]] = -1
                count[ekey[e]] = 0
    for g in range(n_go):
        gidx[go[g]] = -1
    if status < 0:
        return -1, 0, 0
    # The twin's bookkeeping of which drops the next merge test looks at.
    for x in range(n):
        fresh[x] = x >= n_moved
    for d in range(n_def):
        fresh[out[n - 1 - d]] = True
    if k == 0:
        return 0, 0, 0
    # Groups: each joins into its smallest row, the mass-weighted means added in row order (as the twin's
    # bincount and add.at add them).
    members = np.sort(nodes[:k])
    n_roots = 0
    for x in members:
        r = _root(parent, x)
        parent[x] = r
        if r != x and not mark[r]:
            mark[r] = True
            n_roots += 1
    n_gone = 0
    r_at = 0
    for x in members:
        r = parent[x]
        wm = buf[x, M]
        if r == x:
            out[r_at] = x
            r_at += 1
            for c in range(TRAIL + 1):
                sums[c, x] = 0.0 + buf[x, c] * wm
            sums[6, x] = 0.0 + wm
        else:
            out[n_roots + n_gone] = x
            n_gone += 1
            for c in range(TRAIL + 1):
                sums[c, r] += buf[x, c] * wm
            sums[6, r] += wm
    for q in range(n_roots):
        r = out[q]
        mark[r] = False
        g_mass = sums[6, r]
        for c in range(TRAIL + 1):
            buf[r, c] = sums[c, r] / g_mass
        buf[r, M] = g_mass
        buf[r, KEY] = _DIRTY
        buf[r, RB] = _INF
        fresh[r] = True
    for x in members:
        parent[x] = -1
    return 0, n_roots, n_gone
