"""Where water drips: the edges of the low roofs rain cannot pass (the bridge deck, the fuel-station canopy,
awnings, the kiosk), found on the world's top-down occluder map (NumPy, no GL).

A low roof is a connected region of the fine occluder map whose height lies between ``MIN_ROOF_M`` and
``MAX_ROOF_M`` (taller roofs — the buildings — drain through gutters and downpipes, not over their edges). Its
edge cells are the roof cells with a 4-neighbour more than ``MIN_FALL_M`` lower (or open to the ground); drips
leave from about one in every ``SITE_SPACING_M`` of edge (water gathers at low points), at the cell's outer
side. What a roof catches (its area × the rain rate) leaves over its sites in equal shares: a flat roof drains
to every side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rain_core import layout

MIN_ROOF_M = 1.5  # m: lower "roofs" (kerbs, steps) are not overhangs
MAX_ROOF_M = 8.0  # m: taller roofs have gutters
MIN_FALL_M = 0.5  # m: a drop falls at least this far from an edge site
HANG_OUT_M = 0.04  # m, drops hang this far out from the face under an edge
SITE_SPACING_M = 1.0  # m of edge per drip site, on average
FILM_SPEED_M_S = 0.05  # m/s, sheet flow over a wet flat roof (sets how long it keeps dripping)


@dataclass(frozen=True)
class DripSites:
    """Drip sites of one world tile, sorted by z. Per site (N,): ``x``, ``z`` (m, world, z in [0, PERIOD_M)),
    ``edge_y`` (m, where the drop hangs), ``land_y`` (m, where it lands: the ground or a lower roof),
    ``roof`` (index of its roof), ``phase`` (0…1, when in its cycle it lets go). Per roof (R,): ``area_m2``,
    ``edges`` (its site count), ``drain_s`` (the time constant of its drainage: mean path to an edge over the
    sheet-flow speed)."""

    x: np.ndarray
    z: np.ndarray
    edge_y: np.ndarray
    land_y: np.ndarray
    roof: np.ndarray
    phase: np.ndarray
    area_m2: np.ndarray
    edges: np.ndarray
    drain_s: np.ndarray

    def __len__(self) -> int:
        return len(self.x)


def _roofs(mask: np.ndarray) -> tuple[np.ndarray, int]:
    """(index of each cell's 4-connected component, −1 outside ``mask``; the number of components), numbered in
    the order of their first cell (row-major). Union-find over the rows' runs of cells: a run joins the runs of
    the row above that share a column; a component's first run (its root) holds its first cell."""
    rows = mask.shape[0]
    rows_of, cols_of = np.diff(mask, axis=1, prepend=False, append=False).nonzero()  # runs' starts and ends
    run_row = rows_of[0::2]
    start, stop = cols_of[0::2], cols_of[1::2]
    parent = list(range(run_row.size))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = i = parent[parent[i]]
        return i

    # Two consecutive rows' runs walked together in column order: each overlapping pair joins, under the lower.
    row_first = np.searchsorted(run_row, np.arange(rows + 1)).tolist()
    s, e = start.tolist(), stop.tolist()
    for r in range(1, rows):
        a, a_end = row_first[r - 1], row_first[r]
        b, b_end = a_end, row_first[r + 1]
        while a < a_end and b < b_end:
            if s[a] < e[b] and s[b] < e[a]:
                ra, rb = root(a), root(b)
                if ra < rb:
                    parent[rb] = ra
                elif rb < ra:
                    parent[ra] = rb
            if e[a] <= e[b]:
                a += 1
            else:
                b += 1
    roots = np.array([root(i) for i in range(run_row.size)], dtype=np.int64)
    is_root = roots == np.arange(run_row.size)
    rank = np.cumsum(is_root) - 1  # roots in run order are components in the order of their first cells
    index = np.full(mask.shape, -1, dtype=np.int64)
    index[mask] = np.repeat(rank[roots], stop - start)  # the mask's cells in row-major order are the runs'
    return index, int(is_root.sum())


def find_drip_sites(grid: np.ndarray, x0_m: float, cell_m: float, seed: int = 0,
                    street_half_x_m: float = layout.BUILDING_SETBACK_M) -> DripSites:
    """Drip sites on an occluder height grid (rows z from 0, columns x from x0_m, cells of cell_m m, −inf where
    open), deterministic for ``seed``. Rows wrap in z (the world is periodic). A roof's water leaves over all its
    edges; only the sites over the street (|x| < street_half_x_m, m: the road and the sidewalks) are kept."""
    h = np.asarray(grid, dtype=np.float64)
    low = np.isfinite(h) & (h >= MIN_ROOF_M) & (h <= MAX_ROOF_M)
    empty = np.zeros(0)
    if not low.any():
        return DripSites(empty, empty, empty, empty, np.zeros(0, np.int64), empty, empty, np.zeros(0, np.int64),
                         empty)
    roof_index, roofs = _roofs(low)
    area = np.bincount(roof_index[low], minlength=roofs) * cell_m * cell_m

    nz, nx = h.shape
    sites = []
    lower = np.where(np.isfinite(h), h, 0.0)  # open cells: the ground (the road is at ~0 m)
    for dz, dx in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        neighbour = np.roll(lower, (-dz, -dx), axis=(0, 1))
        valid = np.ones_like(low)
        if dx == 1:
            valid[:, -1] = False
        elif dx == -1:
            valid[:, 0] = False
        j, i = np.nonzero(low & valid & (neighbour < h - MIN_FALL_M))
        land = neighbour[j, i]
        # At the cell's outer side, a little beyond the face below the edge (drops hang clear of it).
        sites.append(np.stack([x0_m + (i + 0.5 + 0.5 * dx) * cell_m + dx * HANG_OUT_M,
                               (j + 0.5 + 0.5 * dz) * cell_m + dz * HANG_OUT_M,
                               h[j, i], land, roof_index[j, i]], axis=1))
    s = np.concatenate(sites)
    s[:, 1] %= nz * cell_m
    s = s[np.argsort(s[:, 1], kind="stable")]
    # Mean path to an edge ≈ area / perimeter (m); over the sheet-flow speed: the drainage time constant.
    perimeter = np.maximum(np.bincount(s[:, 4].astype(np.int64), minlength=roofs), 1) * cell_m
    drain = area / perimeter / FILM_SPEED_M_S
    # Water leaves an edge where it gathers, at low points about every metre, not evenly along it.
    rng = np.random.default_rng([seed, 0xD41B])
    s = s[rng.random(len(s)) < cell_m / SITE_SPACING_M]
    edges = np.bincount(s[:, 4].astype(np.int64), minlength=roofs)
    s = s[np.abs(s[:, 0]) < street_half_x_m]
    roof = s[:, 4].astype(np.int64)
    phase = rng.random(len(s))
    return DripSites(s[:, 0], s[:, 1], s[:, 2], s[:, 3], roof, phase, area, edges, drain)
