"""The spatial hash that finds drops close enough to merge, without an all-pairs test or a per-drop loop.

Two uniform grids over 2 m × 1.6 m of glass coordinates (s, t): a fine one (``GRID_CELL_M``) for the many small
drops, by their centres, and a coarse one (``COARSE_CELL_M``) for the few large or fast ones, in every cell
their box touches. Cell keys are matched with a sort and two binary searches (``match``); ``components`` then
joins chains of touching drops.
"""

from __future__ import annotations

import math

import numpy as np

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
