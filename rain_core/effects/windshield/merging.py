"""Merging drops (mixed into ``WindshieldSim``).

Touching drops join, judged by the closest approach of the two drops' motions within the step (so fast drops
cannot tunnel through others); mass, momentum and centre of mass are conserved, and chains resolve as
connected components. Candidate pairs come from the spatial hash in ``grid``.
"""

from __future__ import annotations

import numpy as np

from rain_core.effects.windshield.grid import components, grid_pairs


class Merging:
    """The merge part of ``WindshieldSim`` (its state: ``pos``, ``vel``, ``mass``, ``trail``, ``fresh``)."""

    def _merge(self, start: np.ndarray, disp: np.ndarray) -> None:
        """Join drops that touched during the step (closest approach of their motions ≤ sum of radii).

        Only drops that moved, grew or were born can start touching, so only they are looked up in the grid;
        a merged drop counts as new in the next sub-step (it may now reach a neighbour)."""
        n = self.count
        if n < 2:
            self.fresh = np.zeros(n, bool)
            return
        born = np.zeros(n, bool)
        if len(start) < n:  # trail droplets born during the step: tested from the next sub-step on
            born[len(start) :] = True
            start = np.concatenate([start, self.pos[len(start) :]])
            disp = np.concatenate([disp, np.zeros((n - len(disp), 2))])
        moved = (disp[:, 0] != 0.0) | (disp[:, 1] != 0.0)
        active = (moved | self.fresh) & ~born
        self.fresh = born.copy()
        if not active.any():
            return
        a = self.radius()
        mid = start + 0.5 * disp
        reach = a + 0.5 * np.sqrt(disp[:, 0] ** 2 + disp[:, 1] ** 2)
        i, j = grid_pairs(mid, reach, active)
        if born.any():
            keep = ~(born[i] | born[j])
            i, j = i[keep], j[keep]
        if len(i) == 0:
            return
        p = start[i] - start[j]
        d = disp[i] - disp[j]
        dd = np.einsum("ij,ij->i", d, d)
        tau = np.clip(-np.einsum("ij,ij->i", p, d) / np.maximum(dd, 1e-300), 0.0, 1.0)
        q = p + tau[:, None] * d
        touch = np.einsum("ij,ij->i", q, q) <= (a[i] + a[j]) ** 2
        if not touch.any():
            return
        labels = components(n, i[touch], j[touch])
        roots, inv, sizes = np.unique(labels, return_inverse=True, return_counts=True)
        if len(roots) == n:
            return
        mass = np.bincount(inv, weights=self.mass)
        pos = np.stack([np.bincount(inv, weights=self.mass * self.pos[:, k]) for k in range(2)], axis=1)
        vel = np.stack([np.bincount(inv, weights=self.mass * self.vel[:, k]) for k in range(2)], axis=1)
        trail = np.bincount(inv, weights=self.mass * self.trail)
        self.pos = pos / mass[:, None]
        self.vel = vel / mass[:, None]
        self.trail = trail / mass
        self.mass = mass
        self.fresh = (sizes > 1) | (np.bincount(inv, weights=self.fresh.astype(float)) > 0)
        self.merges += n - len(roots)
