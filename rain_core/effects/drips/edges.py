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


def _label(mask: np.ndarray) -> np.ndarray:
    """4-connected component labels of ``mask`` (−1 outside): minimum-label propagation with pointer jumping."""
    flat = np.where(mask.ravel(), np.arange(mask.size), -1)
    labels = flat.reshape(mask.shape).copy()
    big = mask.size
    work = np.where(mask, labels, big)
    while True:
        before = work.copy()
        for axis in (0, 1):
            for step in (1, -1):
                shifted = np.roll(work, step, axis=axis)
                edge = np.zeros_like(mask)
                if axis == 0:
                    edge[0 if step == 1 else -1, :] = True
                else:
                    edge[:, 0 if step == 1 else -1] = True
                shifted = np.where(edge, big, shifted)
                work = np.where(mask, np.minimum(work, shifted), big)
        # Pointer jumping: a cell takes the label of the cell its label names (labels are flat indices).
        inside = work < big
        idx = np.where(inside, work, 0)
        work = np.where(inside, np.minimum(work, work.ravel()[idx.ravel()].reshape(work.shape)), big)
        if np.array_equal(work, before):
            break
    return np.where(mask, work, -1)


def find_drip_sites(grid: np.ndarray, x0_m: float, cell_m: float, seed: int = 0,
                    street_half_x_m: float = layout.BUILDING_SETBACK_M) -> DripSites:
    """Drip sites on an occluder height grid (rows z from 0, columns x from x0_m, cells of cell_m m, −inf where
    open), deterministic for ``seed``. Rows wrap in z (the world is periodic). A roof's water leaves over all its
    edges; only the sites over the street (|x| < street_half_x_m, m: the road and the sidewalks) are kept."""
    h = np.asarray(grid, dtype=np.float64)
    low = np.isfinite(h) & (h >= MIN_ROOF_M) & (h <= MAX_ROOF_M)
    rows = np.flatnonzero(low.any(axis=1))
    empty = np.zeros(0)
    if rows.size == 0:
        return DripSites(empty, empty, empty, empty, np.zeros(0, np.int64), empty, empty, np.zeros(0, np.int64),
                         empty)
    labels = np.full(h.shape, -1, dtype=np.int64)
    # Label in bands of consecutive rows (plus a margin), so the work scales with the roofs, not the tile.
    breaks = np.flatnonzero(np.diff(rows) > 1)
    starts = np.concatenate([[rows[0]], rows[breaks + 1]])
    ends = np.concatenate([rows[breaks], [rows[-1]]]) + 1
    for a, b in zip(starts, ends, strict=True):
        band = _label(low[a:b])
        labels[a:b] = np.where(band >= 0, band + a * h.shape[1], -1)
    ids, roof_of = np.unique(labels[labels >= 0], return_inverse=True)
    roof_index = np.full(h.shape, -1, dtype=np.int64)
    roof_index[labels >= 0] = roof_of
    area = np.bincount(roof_of, minlength=len(ids)) * cell_m * cell_m

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
    perimeter = np.maximum(np.bincount(s[:, 4].astype(np.int64), minlength=len(ids)), 1) * cell_m
    drain = area / perimeter / FILM_SPEED_M_S
    # Water leaves an edge where it gathers, at low points about every metre, not evenly along it.
    rng = np.random.default_rng([seed, 0xD41B])
    s = s[rng.random(len(s)) < cell_m / SITE_SPACING_M]
    edges = np.bincount(s[:, 4].astype(np.int64), minlength=len(ids))
    s = s[np.abs(s[:, 0]) < street_half_x_m]
    roof = s[:, 4].astype(np.int64)
    phase = rng.random(len(s))
    return DripSites(s[:, 0], s[:, 1], s[:, 2], s[:, 3], roof, phase, area, edges, drain)
