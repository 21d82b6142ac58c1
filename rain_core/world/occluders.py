"""What rain cannot pass, seen from above: a max-height raster of the occluder mesh (roofs, the bridge deck,
the canopy, awnings), fine near the road and coarse beyond."""


from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import layout

OCCLUDER_CELL_M = 0.25  # m, fine top-down roof grid cell
OCCLUDER_HALF_X_M = 48.0  # m, the fine grid covers |x| < this (road, sidewalks, buildings)
OCCLUDER_COARSE_CELL_M = 2.0  # m, coarse grid beyond (the railway embankment out to the ground's edge)

_P = layout.PERIOD_M


@dataclass(eq=False)
class OccluderMap:
    """A top-down raster of the occluder mesh: for each cell the height (m) of the highest occluder surface at
    the cell centre, ``-inf`` where there is none. Rows follow z from 0 (cell j covers [j·cell, (j+1)·cell)),
    columns follow x from ``x0_m``; z wraps with ``PERIOD_M``."""

    grid: np.ndarray  # float32 (nz, nx), m
    x0_m: float
    cell_m: float

    def lookup(self, x, z) -> tuple[np.ndarray, np.ndarray]:
        """Nearest-cell heights (m) at x, z (m) and a mask of the points that lie inside the grid's x range."""
        nz, nx = self.grid.shape
        i = np.floor((np.asarray(x, dtype=np.float64) - self.x0_m) / self.cell_m).astype(np.int64)
        j = np.floor(np.mod(np.asarray(z, dtype=np.float64), _P) / self.cell_m).astype(np.int64) % nz
        i, j = np.broadcast_arrays(i, j)
        inside = (i >= 0) & (i < nx)
        h = self.grid[j, np.clip(i, 0, nx - 1)].astype(np.float64)
        return np.where(inside, h, -np.inf), inside

    def height_at(self, x: float, z: float) -> float | None:
        """``lookup`` at one point (x, z) m in Python scalars (~50× cheaper than the array form for one point,
        for callers that ask every frame): the nearest cell's height (m), None outside the grid's x range."""
        nz, nx = self.grid.shape
        i = math.floor((x - self.x0_m) / self.cell_m)
        if not 0 <= i < nx:
            return None
        return float(self.grid[math.floor((z % _P) / self.cell_m) % nz, i])



# ----------------------------------------------------------------------------------------------------------------
# Occluder rasterisation


def _rasterise_top(tris: np.ndarray, x0: float, cell: float, nx: int) -> np.ndarray:
    """Max-height raster (m) of a triangle soup (T, 3, 3) on cells of ``cell`` m: rows z in [0, PERIOD_M) (the
    soup wraps), columns x from x0. A cell takes a triangle if its centre lies inside the triangle's xz shadow."""
    nz = int(round(_P / cell))
    grid = np.full((nz, nx), -np.inf, dtype=np.float32)
    a = tris[:, 1] - tris[:, 0]
    b = tris[:, 2] - tris[:, 0]
    # Only up-facing triangles: vertical faces cast no shadow, and under a closed solid's top the faces that
    # look down are never the highest (the occluders are closed boxes or up-facing slopes, wound outwards).
    tris = tris[a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2] > 1e-9]
    zmin, zmax = tris[:, :, 2].min(1), tris[:, :, 2].max(1)
    shift = np.array([0.0, 0.0, _P])
    tris = np.concatenate([tris, tris[zmin < 0] + shift, tris[zmax > _P] - shift])
    lo = np.floor((tris[:, :, [0, 2]].min(1) - (x0, 0.0)) / cell - 0.5).astype(np.int64) + 1
    hi = np.floor((tris[:, :, [0, 2]].max(1) - (x0, 0.0)) / cell - 0.5).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, (nx - 1, nz - 1))
    eps = 1e-7
    for t in np.nonzero((lo <= hi).all(1))[0]:
        (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = tris[t]
        i0, j0 = lo[t]
        i1, j1 = hi[t]
        cx = x0 + (np.arange(i0, i1 + 1) + 0.5) * cell
        cz = ((np.arange(j0, j1 + 1) + 0.5) * cell)[:, None]
        det = (z2 - z3) * (x1 - x3) + (x3 - x2) * (z1 - z3)
        l1 = ((z2 - z3) * (cx - x3) + (x3 - x2) * (cz - z3)) / det
        l2 = ((z3 - z1) * (cx - x3) + (x1 - x3) * (cz - z3)) / det
        l3 = 1.0 - l1 - l2
        inside = (l1 >= -eps) & (l2 >= -eps) & (l3 >= -eps)
        if not inside.any():
            continue
        y = l1 * y1 + l2 * y2 + l3 * y3
        sub = grid[j0:j1 + 1, i0:i1 + 1]
        np.maximum(sub, np.where(inside, y, -np.inf), out=sub)
    return grid

