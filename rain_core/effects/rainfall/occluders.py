"""Static occlusion: the roofs as a top-down height map, and the march of a drop's straight path through it that
settles where its life ends (package docstring, "Occlusion")."""

from __future__ import annotations

import numpy as np

from rain_core.effects.rainfall.constants import (
    BACKWARD_MAX_M,
    FINE_BLOCK_M,
    GROUND_Y_M,
    MARCH_MAX_SAMPLES,
    MARCH_STEP_M,
    REFINE_STEPS,
    SKIP_BLOCK_M,
)


class OccluderField:
    """The static roofs as a top-down height map (``world.occluder_height``: the occluder mesh rendered once, 0.25 m
    cells, −inf where open) and a max-pooled copy (SKIP_BLOCK_M cells, dilated by one cell) that tells which
    stretches of a path cannot meet a roof. ``heights`` reads the fine map's array directly (the same values as
    ``world.occluder_height``, a few times faster) and defers to the world beyond the fine map's x range."""

    def __init__(self, world):
        self.world = world
        fine = world.occluder_map
        coarse = world.occluder_map_coarse
        finite = [g[np.isfinite(g)] for g in (fine.grid, coarse.grid)]
        self.max_height = max((float(f.max()) for f in finite if f.size), default=-np.inf)
        self._grid = np.ascontiguousarray(fine.grid, dtype=np.float32)
        self._x0, self._cell = float(fine.x0_m), float(fine.cell_m)
        self._span_z = self._grid.shape[0] * self._cell
        self._pooled = self._unified_pool(fine, coarse)
        self._pooled_fine = self._pool(fine, FINE_BLOCK_M)
        self._pooled_fine[0][:, [0, -1]] = np.inf  # its edge blocks cannot see roofs beyond the fine map

    @staticmethod
    def _pool(occ_map, block_m: float = SKIP_BLOCK_M):
        """Block max of a map's grid over block_m cells, dilated by one block (z periodic)."""
        k = max(1, int(round(block_m / occ_map.cell_m)))
        nz, nx = occ_map.grid.shape
        bz, bx = -(-nz // k), -(-nx // k)
        grid = np.full((bz * k, bx * k), -np.inf, dtype=np.float64)
        grid[:nz, :nx] = occ_map.grid
        grid[nz:, :nx] = occ_map.grid[: bz * k - nz]  # z wraps
        blocks = grid.reshape(bz, k, bx, k).max(axis=(1, 3))
        dil = blocks.copy()
        for dz in (-1, 0, 1):
            rolled = np.roll(blocks, dz, axis=0)
            dil = np.maximum(dil, rolled)
            dil[:, 1:] = np.maximum(dil[:, 1:], rolled[:, :-1])
            dil[:, :-1] = np.maximum(dil[:, :-1], rolled[:, 1:])
        return dil, float(occ_map.x0_m), occ_map.cell_m * k, nz * occ_map.cell_m

    @classmethod
    def _unified_pool(cls, fine, coarse):
        """One pooled grid over the coarse map's extent, raised to the fine map's pooled values where that one
        reaches (the 2 m raster can miss roofs narrower than a cell; the fine one misses nothing)."""
        grid_c, x0_c, cell, span_z = cls._pool(coarse)
        grid_f, x0_f, cell_f, _ = cls._pool(fine)
        offset = (x0_f - x0_c) / cell
        if abs(cell_f - cell) > 1e-9 or abs(offset - round(offset)) > 1e-9 or grid_f.shape[0] != grid_c.shape[0]:
            raise ValueError("the fine and coarse occluder maps do not share the pooled block lattice")
        i0 = int(round(offset))
        grid = grid_c.copy()
        grid[:, i0: i0 + grid_f.shape[1]] = np.maximum(grid[:, i0: i0 + grid_f.shape[1]], grid_f)
        return grid, x0_c, cell, span_z

    def near_max(self, x, z, fine: bool = False) -> np.ndarray:
        """Highest roof (m) within at least SKIP_BLOCK_M (fine: FINE_BLOCK_M) of (x, z) (m). Outside the map:
        −inf for the coarse map (there is nothing), +inf for the fine one (it does not know: march)."""
        grid, x0, cell, span_z = self._pooled_fine if fine else self._pooled
        fx = (x - x0) / cell
        inside = (fx >= 0.0) & (fx < grid.shape[1])
        i = np.clip(fx, 0, grid.shape[1] - 1).astype(np.int64)
        j = (np.mod(z, span_z) / cell).astype(np.int64) % grid.shape[0]
        return np.where(inside, grid[j, i], np.inf if fine else -np.inf)

    @staticmethod
    def _ragged(t_a, t_b, counts):
        """Sample times of ragged series: counts[i] evenly spaced times from t_a[i] to t_b[i] (counts ≥ 2).
        Returns (owner index, local index, times, starts)."""
        idx = np.repeat(np.arange(counts.size), counts)
        starts = np.zeros(counts.size, dtype=np.int64)
        np.cumsum(counts[:-1], out=starts[1:])
        local = np.arange(idx.size) - starts[idx]
        tau = t_a[idx] + (t_b - t_a)[idx] * (local / (counts[idx] - 1))
        return idx, local, tau, starts

    def _risky_stretch(self, p, u, t_a, t_b, spacing_m, fine):
        """For paths p + u·τ over [t_a, t_b], the stretch [first, last] between samples ≤ spacing_m apart that
        may meet a roof, judged on a pooled map. Returns (indices of risky paths, their t_a, their t_b)."""
        speed_h = np.hypot(u[:, 0], u[:, 2])
        counts = np.minimum(np.ceil(speed_h * (t_b - t_a) / spacing_m).astype(np.int64), 62) + 2
        idx, local, tau, starts = self._ragged(t_a, t_b, counts)
        near = self.near_max(p[idx, 0] + u[idx, 0] * tau, p[idx, 2] + u[idx, 2] * tau, fine)
        y = p[idx, 1] + u[idx, 1] * tau
        nxt = np.minimum(np.arange(idx.size) + 1, idx.size - 1)
        risky = (local < counts[idx] - 1) & (y[nxt] < np.maximum(near, near[nxt]))
        big = int(counts.max()) + 1
        first = np.minimum.reduceat(np.where(risky, local, big), starts)
        final = np.maximum.reduceat(np.where(risky, local, -1), starts)
        sel = np.flatnonzero(first < big)
        step = (t_b - t_a)[sel] / (counts[sel] - 1)
        return sel, t_a[sel] + step * first[sel], t_a[sel] + step * (final[sel] + 1)

    def heights(self, x, z) -> np.ndarray:
        """Roof height (m) over (x, z) (m), −inf where open: ``world.occluder_height``."""
        nz, nx = self._grid.shape
        fx = (x - self._x0) / self._cell
        inside = (fx >= 0.0) & (fx < nx)
        i = np.clip(fx, 0, nx - 1).astype(np.int64)
        j = (np.mod(z, self._span_z) / self._cell).astype(np.int64) % nz
        h = self._grid[j, i].astype(np.float64)
        if not inside.all():
            miss = ~inside
            h[miss] = np.asarray(self.world.occluder_height(x[miss], z[miss]))
        return h

    def fate(self, p0: np.ndarray, u: np.ndarray, life: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """March the straight paths p0 + u·τ (m, m/s; u_y < 0) through the roof map, from BACKWARD_MAX_M above
        the drop (at most the highest roof) down to the ground. Returns (keep, life): keep is False where the
        path meets a roof before τ = 0 (under a roof or in its rain shadow); life (s) is cut at the first roof
        after. A drop under the roof of its own column is refused at once; for the others a coarse pass on the
        pooled map finds the stretch of the path that can meet a roof, and only that stretch is marched, every
        MARCH_STEP_M of horizontal travel (at most MARCH_MAX_SAMPLES samples), a block of samples at a time so
        that drops leave the march at their first roof."""
        n = len(p0)
        keep = np.ones(n, dtype=bool)
        life = life.copy()
        if n == 0 or not np.isfinite(self.max_height):
            return keep, life
        keep = self.heights(p0[:, 0], p0[:, 2]) <= p0[:, 1]
        rest = np.flatnonzero(keep)
        if rest.size == 0:
            return keep, life
        p, uu = p0[rest], u[rest]
        fall = -uu[:, 1]
        y_top = np.maximum(p[:, 1], np.minimum(self.max_height, p[:, 1] + BACKWARD_MAX_M)) + 0.01
        tau0 = -(y_top - p[:, 1]) / fall  # ≤ 0: when the drop was at y_top
        tau1 = (p[:, 1] - GROUND_Y_M) / fall  # when it reaches the ground
        # Two passes on pooled maps narrow the stretch that can meet a roof: samples ≤ 2·block apart keep every
        # point of the path within one block of a sample, which the dilation covers; a stretch between two
        # samples is safe when the path's lower end is above both pooled maxima.
        cand, t_a, t_b = self._risky_stretch(p, uu, tau0, tau1, 2.0 * SKIP_BLOCK_M, fine=False)
        if cand.size == 0:
            return keep, life
        sub, t_a, t_b = self._risky_stretch(p[cand], uu[cand], t_a, t_b, 2.0 * FINE_BLOCK_M, fine=True)
        cand = cand[sub]
        if cand.size == 0:
            return keep, life
        speed_h = np.hypot(uu[cand, 0], uu[cand, 2])
        nf = np.clip(np.ceil(speed_h * (t_b - t_a) / MARCH_STEP_M).astype(np.int64) + 1, 2,
                     MARCH_MAX_SAMPLES)
        step = (t_b - t_a) / (nf - 1)
        pc, uc = p[cand], uu[cand]
        tau_hit = np.full(cand.size, np.inf)
        active = np.arange(cand.size)
        block = 16
        for k0 in range(0, int(nf.max()), block):
            active = active[nf[active] > k0]
            if active.size == 0:
                break
            ks = k0 + np.arange(block)
            tau_k = t_a[active, None] + step[active, None] * ks[None, :]  # (m, block)
            valid = ks[None, :] < nf[active, None]
            yk = pc[active, 1, None] + uc[active, 1, None] * tau_k
            hk = self.heights((pc[active, 0, None] + uc[active, 0, None] * tau_k).ravel(),
                              (pc[active, 2, None] + uc[active, 2, None] * tau_k).ravel()).reshape(tau_k.shape)
            below = valid & (yk < hk)
            found = below.any(axis=1)
            if found.any():
                rows = np.flatnonzero(found)
                col = np.argmax(below[rows], axis=1)
                drops = active[rows]
                hi = tau_k[rows, col]
                lo = np.where(k0 + col > 0, hi - step[drops], hi)
                for _ in range(REFINE_STEPS):  # bisect to where the path enters the roof's column
                    mid = 0.5 * (lo + hi)
                    under = (pc[drops, 1] + uc[drops, 1] * mid
                             < self.heights(pc[drops, 0] + uc[drops, 0] * mid, pc[drops, 2] + uc[drops, 2] * mid))
                    hi = np.where(under, mid, hi)
                    lo = np.where(under, lo, mid)
                h_hit = self.heights(pc[drops, 0] + uc[drops, 0] * hi, pc[drops, 2] + uc[drops, 2] * hi)
                t_cross = (h_hit - pc[drops, 1]) / uc[drops, 1]  # when y(τ) = that roof's height
                tau_hit[drops] = np.clip(t_cross, lo, hi)
                active = active[~found]
        hit = np.isfinite(tau_hit)
        drops = rest[cand[hit]]
        keep[drops] = tau_hit[hit] > 0.0
        life[drops] = np.minimum(life[drops], np.maximum(tau_hit[hit], 0.0))
        return keep, life
