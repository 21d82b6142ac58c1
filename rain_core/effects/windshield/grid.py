"""The spatial hash that finds drops close enough to merge, without an all-pairs test or a per-drop loop.

Two uniform grids over 2 m × 1.6 m of glass coordinates (s, t): a fine one (``GRID_CELL_M``) for the many small
drops, by their centres, and a coarse one (``COARSE_CELL_M``) for the few large or fast ones, in every cell
their box touches. ``components`` then joins chains of touching drops.

Two implementations of the same candidate search:

* ``grid_pairs`` (the reference): cell keys matched with a sort and two binary searches (``match``);
* ``PairFinder`` (the fast path): occupied cells written into tables that live as long as the simulation, so a
  lookup is one gather instead of a binary search, and a work budget per call (``MERGE_CELLS_MAX`` cells of
  swept boxes, ``MERGE_PAIRS_MAX`` pairs) so that no input, however fast or dense, can ask for unbounded work.
  When some drops reach far (a car at speed), every drop sits in the near cells its box touches and the drops
  sharing a cell are the candidates, instead of every drop looking in a far grid.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import MERGE_CELLS_MAX, MERGE_PAIRS_MAX

GRID_CELL_M = 4e-3  # fine merge-test grid; the drop arrays are kept sorted by this grid's cell of their centre
COARSE_CELL_M = 3.2e-2  # coarse grid for large or fast drops
_GRID_ORIGIN = np.array([-1.0, -0.2])  # m; the grids span 2 m × 1.6 m of glass coordinates


def _grid_shape(cell: float) -> tuple[int, int]:
    return int(math.ceil(2.0 / cell)), int(math.ceil(1.6 / cell))


def grid_keys(points: np.ndarray, cell: float = GRID_CELL_M) -> np.ndarray:
    """Cell key (row-major over (s, t)) of points (n, 2) m in a grid of ``cell`` m; off-grid points clip."""
    n0, n1 = _grid_shape(cell)
    k0 = np.minimum(np.maximum(((points[:, 0] - _GRID_ORIGIN[0]) / cell).astype(np.int64), 0), n0 - 1)
    k1 = np.minimum(np.maximum(((points[:, 1] - _GRID_ORIGIN[1]) / cell).astype(np.int64), 0), n1 - 1)
    return k0 * n1 + k1


def box_keys(points: np.ndarray, half: np.ndarray, ids: np.ndarray, cell: float) -> tuple[np.ndarray, ...]:
    """(cell key, id) entries for every cell of ``cell`` m that the box points ± half (m) touches."""
    n0, n1 = _grid_shape(cell)
    top = np.array([n0 - 1, n1 - 1])
    lo = np.minimum(np.maximum(np.floor((points - half[:, None] - _GRID_ORIGIN) / cell).astype(np.int64), 0), top)
    hi = np.minimum(np.maximum(np.floor((points + half[:, None] - _GRID_ORIGIN) / cell).astype(np.int64), 0), top)
    w0 = hi[:, 0] - lo[:, 0] + 1
    w1 = hi[:, 1] - lo[:, 1] + 1
    counts = w0 * w1
    total = int(counts.sum())
    owner = np.repeat(np.arange(len(ids)), counts)
    within = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
    d0, d1 = np.divmod(within, w1[owner])
    return (lo[owner, 0] + d0) * n1 + lo[owner, 1] + d1, ids[owner]


def match(t_keys: np.ndarray, t_ids: np.ndarray, q_keys: np.ndarray, q_ids: np.ndarray) -> tuple[np.ndarray, ...]:
    """All (query id, target id) pairs that share a cell key."""
    if len(t_keys) == 0 or len(q_keys) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    order = np.argsort(t_keys, kind="stable")  # cheap: the entries come nearly sorted
    sorted_keys, t_ids = t_keys[order], t_ids[order]
    first = np.searchsorted(sorted_keys, q_keys, "left")
    c = np.searchsorted(sorted_keys, q_keys, "right") - first
    has = c > 0
    c, q_ids, first = c[has], q_ids[has], first[has]
    total = int(c.sum())
    if total == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    base = np.repeat(first - (np.cumsum(c) - c), c)
    return np.repeat(q_ids, c), t_ids[base + np.arange(total)]


def grid_pairs(points: np.ndarray, reach: np.ndarray, active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs (i, j), i ≠ j, at least one of them ``active`` (bool mask), that include every such
    pair with |p_i − p_j| ≤ reach_i + reach_j (m). Pairs may repeat. No all-pairs test and no per-drop loop:

    * small points (reach ≤ half a fine cell) sit in the fine grid by their centre; each active small point
      looks up the fine cells of its box widened by half a cell (≤ 3 × 3 cells), which must hold the centre of
      any small point it can touch;
    * large or fast points sit in the coarse grid in every cell their box p ± reach touches; every point looks
      up the coarse cells of its own box widened by half a fine cell, which must meet the box of any large
      point it can touch. Pairs with neither point active are dropped.
    """
    n = len(points)
    if n < 2 or not active.any():
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    half = 0.5 * GRID_CELL_M
    big = reach > half
    small_ids = np.flatnonzero(~big)
    keys = grid_keys(points[small_ids])
    q = np.flatnonzero(active & ~big)
    qk, qi = box_keys(points[q], reach[q] + half, q, GRID_CELL_M)
    i1, j1 = match(keys, small_ids, qk, qi)
    if not big.any():
        keep = i1 != j1
        return i1[keep], j1[keep]
    big_ids = np.flatnonzero(big)
    bk, bi = box_keys(points[big_ids], reach[big_ids], big_ids, COARSE_CELL_M)
    everyone = np.arange(n)
    qk, qi = box_keys(points, reach + half, everyone, COARSE_CELL_M)
    i2, j2 = match(bk, bi, qk, qi)
    either = active[i2] | active[j2]
    i, j = np.concatenate([i1, i2[either]]), np.concatenate([j1, j2[either]])
    keep = i != j
    return i[keep], j[keep]


def components(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected-component label (the smallest member index) of each of n nodes joined by edges (i, j)."""
    labels = np.arange(n)
    for _ in range(64):
        lo = np.minimum(labels[i], labels[j])
        new = labels.copy()
        np.minimum.at(new, i, lo)
        np.minimum.at(new, j, lo)
        new = new[new]  # pointer jumping: chains collapse in O(log) rounds
        if np.array_equal(new, labels):
            break
        labels = new
    return labels


def small_components(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``components`` for the few edges of one merge test (tens a step): a union-find in Python, ~5× faster than
    the NumPy rounds at that size (their ufunc.at and per-round calls dominate). Each root is its component's
    smallest member (a larger root always joins a smaller one, so a parent is never larger than its child), the
    labels ``components`` gives. Many edges go to ``components``."""
    if len(i) > SMALL_COMPONENTS_EDGES:
        return components(n, i, j)
    parent = list(range(n))
    for a, b in zip(i.tolist(), j.tolist(), strict=True):
        while parent[a] != a:
            parent[a] = a = parent[parent[a]]  # path halving: keeps parent ≤ child
        while parent[b] != b:
            parent[b] = b = parent[parent[b]]
        if a < b:
            parent[b] = a
        elif b < a:
            parent[a] = b
    for x in range(n):  # a parent is smaller, so already points at its root
        parent[x] = parent[parent[x]]
    return np.array(parent)


SMALL_COMPONENTS_EDGES = 512  # up to this many edges small_components loops in Python
_EMPTY_I = np.zeros(0, np.int64)
NEAR_CELL_M = 1.6e-2  # PairFinder's grid: drops reaching ≤ half of this are found by their centres
FAR_CELL_M = 6.4e-2  # PairFinder's grid for the few drops that reach further (fast or very large)
# PairFinder._box_pairs: a box's cells are widened by this (in cells, 16 nm) so that rounding in their bounds
# never leaves out a cell the exact box touches.
_BOX_MARGIN_CELLS = 1e-6


def _expand(query_ids: np.ndarray, counts: np.ndarray, heads: np.ndarray, members: np.ndarray):
    """Pairs (query id, member) for queries that each meet ``counts`` members stored from ``heads`` on in
    ``members``."""
    total = int(np.add.reduce(counts))
    if total == len(counts):  # one member each: the common case
        return query_ids, members.take(heads)
    at = np.arange(len(counts)).repeat(counts)  # (repeat copies element by element: the rest are gathers)
    shift = (heads - (counts.cumsum() - counts)).take(at)
    shift += np.arange(total)
    return query_ids.take(at), members.take(shift)


def _box_cells(lo0, lo1, hi0, hi1, ids: np.ndarray, n1: int) -> tuple[np.ndarray, np.ndarray]:
    """(cell key, id) for every cell of the boxes lo…hi (inclusive cell indices, per axis)."""
    w1 = hi1 - lo1 + 1
    counts = (hi0 - lo0 + 1) * w1
    total = int(counts.sum())
    if total == len(ids):
        return lo0 * n1 + lo1, ids
    owner = np.arange(len(ids)).repeat(counts)
    within = np.arange(total) - (counts.cumsum() - counts).repeat(counts)
    d0, d1 = np.divmod(within, w1[owner])
    return (lo0[owner] + d0) * n1 + lo1[owner] + d1, ids[owner]


class PairFinder:
    """The fast candidate search (see the module docstring); one per simulation.

    Drops that reach ≤ NEAR_CELL_M / 2 (nearly all) sit in a grid of NEAR_CELL_M cells by their centres, in a
    table of occupied cells (16-bit keys, so the sort is a radix sort, and a lookup is a gather); an active one
    looks in the 3 × 3 cells around its own. When some drops reach further (fast or very large), every drop
    sits in each near cell its box touches instead and drops sharing a cell are the candidates
    (``_box_pairs``); past the work budget, the far-reaching ones sit in a FAR_CELL_M grid in every cell of
    their swept box widened by NEAR_CELL_M / 2, and every drop looks there by its centre's cell, a far-reaching
    one by its box.

    ``pairs(s, t, reach, active, end_s, end_t, radius)`` (1-D columns, m) returns (i, j, deferred): candidate
    pairs i ≠ j, at least one of them active, that include every such pair with |p_i − p_j| ≤ reach_i + reach_j,
    as ``grid_pairs`` does — unless the work budget ran out: then the drops with the largest swept boxes are
    looked up around their ``end`` point with their ``radius`` instead, and ``deferred`` (bool, n, or None when
    nothing was deferred) marks the drops whose lookups were left for the next sub-step.
    """

    def __init__(self):
        self._n0, self._n1 = _grid_shape(NEAR_CELL_M)
        self._p1 = self._n1 + 2  # a border of empty cells: a neighbour never wraps to another row
        size = (self._n0 + 2) * self._p1
        assert size < 2**15  # keys fit 16 bits
        self._head = np.zeros(size, np.int64)
        self._count = np.zeros(size, np.int64)
        p1 = self._p1
        self._around = np.array([di * p1 + dj for di in (-1, 0, 1) for dj in (-1, 0, 1)], np.int16)
        self._f0, self._f1 = _grid_shape(FAR_CELL_M)
        self._box_top = np.array([[self._n0 - 1], [self._n1 - 1], [self._n0 - 1], [self._n1 - 1]], float)
        self._ar = np.arange(4096)

    def _box_pairs(self, s, t, reach, active):
        """Candidate pairs when some drops reach far (fast or large): every drop sits in each cell of the near
        grid that its box (s, t) ± reach touches, and two drops whose boxes share a cell are a candidate — boxes
        of drops within reach of each other overlap, so they share the cells of the overlap. One table for near
        and far drops (no far grid, no lookups around each drop), and far fewer candidates than the 3 × 3
        lookups give. Returns (i, j) (i ≠ j, at least one active; a pair may repeat), or None when the boxes'
        cells or the pairs would pass the work budget (``pairs`` then defers work)."""
        n = len(s)
        inv = 1.0 / NEAR_CELL_M
        bounds = np.empty((4, n))  # lo0, lo1, hi0, hi1 in cells
        cs = s - float(_GRID_ORIGIN[0])
        cs *= inv
        ct = t - float(_GRID_ORIGIN[1])
        ct *= inv
        rc = reach * inv
        rc += _BOX_MARGIN_CELLS
        np.subtract(cs, rc, out=bounds[0])
        np.subtract(ct, rc, out=bounds[1])
        np.add(cs, rc, out=bounds[2])
        np.add(ct, rc, out=bounds[3])
        np.maximum(bounds, 0.0, out=bounds)
        np.minimum(bounds, self._box_top, out=bounds)  # clipped to the grid first: truncation is then floor
        lo0, lo1, hi0, hi1 = bounds.astype(np.int64)
        w1 = hi1 - lo1
        w1 += 1
        count = hi0 - lo0
        count += 1
        count *= w1
        key = lo0 * self._n1
        key += lo1
        total = int(np.add.reduce(count))
        if total > MERGE_CELLS_MAX:
            return None
        ar = self._arange(max(total, n))
        if total == n:
            owner = ar[:n]
        else:
            owner = ar[:n].repeat(count)  # (repeat copies element by element: the others are gathers by owner)
            first = count.cumsum()
            first -= count
            within = ar[:total] - first.take(owner)
            d0, d1 = np.divmod(within, w1.take(owner))
            d0 *= self._n1
            d0 += d1
            key = key.take(owner)
            key += d0
        key = key.astype(np.int16)
        order = key.argsort(kind="stable")  # 16-bit keys: a radix sort
        key = key[order]
        owner = owner[order]
        # Each entry pairs with the entries after it in its cell's run.
        brk = (key[1:] != key[:-1]).nonzero()[0]
        ends = np.empty(len(brk) + 1, np.int64)  # where each cell's run ends, and its length
        ends[:-1] = brk
        ends[:-1] += 1
        ends[-1] = total
        runs = ends.copy()
        runs[1:] -= ends[:-1]
        after = ends.repeat(runs)
        after -= ar[:total]
        after -= 1
        n_pairs = int(np.add.reduce(after))
        if n_pairs > MERGE_PAIRS_MAX:
            return None
        if n_pairs == 0:
            return _EMPTY_I, _EMPTY_I
        ar = self._arange(n_pairs)
        pi = ar[:total].repeat(after)
        first = after.cumsum()
        first -= after
        pj = ar[:n_pairs] - first.take(pi)
        pj += pi
        pj += 1
        i = owner.take(pi)
        j = owner.take(pj)
        keep = (active.take(i) | active.take(j)).nonzero()[0]
        return i.take(keep), j.take(keep)

    def _arange(self, n: int) -> np.ndarray:
        """0, 1, … at least n long (kept: most steps need the same few thousand)."""
        if len(self._ar) < n:
            self._ar = np.arange(max(n, 2 * len(self._ar)))
        return self._ar

    def pairs(self, s, t, reach, active, end_s, end_t, radius):
        n = len(s)
        deferred = None
        budget = MERGE_PAIRS_MAX
        near = reach <= 0.5 * NEAR_CELL_M
        out_i, out_j = [], []
        near_ids = near.nonzero()[0]
        all_near = len(near_ids) == n
        if not all_near:
            boxed = self._box_pairs(s, t, reach, active)
            if boxed is not None:
                return boxed[0], boxed[1], None
        if len(near_ids):
            ns, nt = (s, t) if all_near else (s[near_ids], t[near_ids])
            inv = 1.0 / NEAR_CELL_M
            k0 = np.minimum(np.maximum(((ns - _GRID_ORIGIN[0]) * inv).astype(np.int16), 0), self._n0 - 1)
            k1 = np.minimum(np.maximum(((nt - _GRID_ORIGIN[1]) * inv).astype(np.int16), 0), self._n1 - 1)
            keys = k0 * np.int16(self._p1) + (k1 + np.int16(self._p1 + 1))
            order = keys.argsort(kind="stable")  # 16-bit keys: a radix sort
            sorted_keys = keys[order]
            members = order if all_near else near_ids[order]
            # Runs of equal keys: where each starts and ends in the sorted order.
            brk = (sorted_keys[1:] != sorted_keys[:-1]).nonzero()[0] + 1
            starts = np.empty(len(brk) + 1, np.int64)
            starts[0] = 0
            starts[1:] = brk
            ends = np.empty_like(starts)
            ends[:-1] = brk
            ends[-1] = len(sorted_keys)
            run_cells = sorted_keys[starts]
            self._head[run_cells] = starts
            self._count[run_cells] = ends - starts
            if all_near:
                q = active.nonzero()[0]
                qk = keys[q]
            else:
                q = (active & near).nonzero()[0]
                at = np.empty(n, keys.dtype)  # the near drops' keys by drop index (a search of near_ids costs more)
                at[near_ids] = keys
                qk = at[q]
            looked = (qk[:, None] + self._around).ravel()
            c = self._count.take(looked)
            hit = c.nonzero()[0]
            self._count[run_cells] = 0
            if len(hit):
                c = c[hit]
                qid = q[hit // 9]
                if int(np.add.reduce(c)) > budget:
                    over = c.cumsum() > budget
                    if deferred is None:
                        deferred = np.zeros(n, bool)
                    deferred[qid[over]] = True
                    keep = ~over
                    hit, c, qid = hit[keep], c[keep], qid[keep]
                i, j = _expand(qid, c, self._head.take(looked.take(hit)), members)
                budget -= len(i)
                out_i.append(i)
                out_j.append(j)

        if not all_near:
            far_ids = (~near).nonzero()[0]
            fs, ft, fr = s[far_ids], t[far_ids], reach[far_ids]
            c0, c1 = self._f0, self._f1
            widen = 0.5 * NEAR_CELL_M

            def box(ps, pt, half):
                """Inclusive cell ranges (lo0, lo1, hi0, hi1) of the boxes (ps, pt) ± half, clipped to the grid."""
                cs, ct, hc = (ps - _GRID_ORIGIN[0]) / FAR_CELL_M, (pt - _GRID_ORIGIN[1]) / FAR_CELL_M, half / FAR_CELL_M
                b = np.floor(np.stack([cs - hc, ct - hc, cs + hc, ct + hc]))
                b = np.minimum(np.maximum(b, 0.0), top).astype(np.int64)
                return b[0], b[1], b[2], b[3]

            top = np.array([[c0 - 1], [c1 - 1], [c0 - 1], [c1 - 1]], float)
            lo0, lo1, hi0, hi1 = box(fs, ft, fr + widen)
            cover = (hi0 - lo0 + 1) * (hi1 - lo1 + 1)
            if 2 * int(cover.sum()) > MERGE_CELLS_MAX:
                # Over budget: the drops with the largest boxes are looked up where they end, with their size.
                order = (-cover).argsort(kind="stable")
                left = 2 * (int(cover.sum()) - cover[order].cumsum()) + 18 * np.arange(1, len(order) + 1)
                fits = left <= MERGE_CELLS_MAX
                shrink = order[: int(np.argmax(fits)) + 1 if fits.any() else len(order)]
                fs, ft, fr = fs.copy(), ft.copy(), fr.copy()
                fs[shrink] = end_s[far_ids[shrink]]
                ft[shrink] = end_t[far_ids[shrink]]
                fr[shrink] = radius[far_ids[shrink]]
                lo0, lo1, hi0, hi1 = box(fs, ft, fr + widen)
            reg_keys, reg_ids = _box_cells(lo0, lo1, hi0, hi1, far_ids, c1)
            order = reg_keys.argsort(kind="stable")
            reg_keys, reg_ids = reg_keys[order], reg_ids[order]
            per_cell = np.bincount(reg_keys, minlength=c0 * c1)
            head = per_cell.cumsum() - per_cell
            # Queries: every near drop by its centre's cell; a far-reaching one by the cells it sits in (its
            # widened box, a superset of its own box).
            q_keys, q_ids = reg_keys, reg_ids
            if len(near_ids):
                ns, nt = s[near_ids], t[near_ids]
                kc = (((ns - _GRID_ORIGIN[0]) * (1.0 / FAR_CELL_M)).astype(np.int64) * c1
                      + ((nt - _GRID_ORIGIN[1]) * (1.0 / FAR_CELL_M)).astype(np.int64))
                q_keys = np.concatenate([kc, q_keys])
                q_ids = np.concatenate([near_ids, q_ids])
            c = per_cell[q_keys]
            hit = c.nonzero()[0]
            if len(hit):
                c, qid = c[hit], q_ids[hit]
                if int(c.sum()) > max(budget, 0):
                    over = c.cumsum() > max(budget, 0)
                    if deferred is None:
                        deferred = np.zeros(n, bool)
                    deferred[qid[over]] = True
                    keep = ~over
                    hit, c, qid = hit[keep], c[keep], qid[keep]
                i, j = _expand(qid, c, head[q_keys[hit]], reg_ids)
                # A far pair is found from both sides: keep one. A pair neither of which is active is not new.
                keep = (i != j) & ((i < j) | near[i]) & (active[i] | active[j])
                out_i.append(i[keep])
                out_j.append(j[keep])
        if not out_i:
            return _EMPTY_I, _EMPTY_I, deferred
        if deferred is not None and not np.count_nonzero(deferred):
            deferred = None
        i = np.concatenate(out_i) if len(out_i) > 1 else out_i[0]
        j = np.concatenate(out_j) if len(out_j) > 1 else out_j[0]
        keep = i != j
        return i[keep], j[keep], deferred
