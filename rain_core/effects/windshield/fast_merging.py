"""Merging drops on the fast path (mixed into ``sim.WindshieldSim`` ahead of the reference's ``merging.Merging``):
the same rule and sums, with candidate pairs from ``grid.PairFinder``'s tables and the groups formed on the
drops that touch only."""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.constants import drop_radius
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import RB as _RB
from rain_core.effects.windshield.drop_rows import TRAIL as _TRAIL
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.grid import small_components


class FastMerging:
    """``merging.Merging._merge`` on the drop array (its state: ``_buf``, ``_n``, ``_pairs``, ``_fresh_buf``)."""

    def _merge(self, start: np.ndarray, disp: np.ndarray) -> None:
        """Join drops that touched during the step (closest approach of their motions ≤ sum of radii); see
        ``merging``: ``start`` and ``disp`` (k, 2) m for the first k drops (the reference's form)."""
        k = len(start)
        self._merge_moves(k, np.arange(k), start[:, 0], start[:, 1], disp[:, 0], disp[:, 1])
        self._remove_merged()

    def _remove_merged(self) -> None:
        """Remove the drops the last merge joined into others (``_merge_moves`` leaves their rows in place)."""
        gone = self._merged_away
        if gone is not None:
            self._merged_away = None
            keep = np.ones(self._n, bool)
            keep[gone] = False
            self._keep(keep)

    def _merge_compiled(self, n_moved: int, go, s_g, t_g, ds_g, dt_g, step_len) -> bool:
        """``_merge_moves`` by ``kernels.merge_drops``; False (nothing done) where its candidate search would pass
        the work budget: the twin then runs, with its far grid."""
        n = self._n
        n_go = len(go)
        ks = self._scratch()
        if n_go and go.base is not ks.go:  # the motion's columns from elsewhere than _move's kernel: copied in
            ks.go[:n_go] = go
            g = ks.gcol
            g[0, :n_go], g[1, :n_go], g[2, :n_go], g[3, :n_go] = s_g, t_g, ds_g, dt_g
            g[4, :n_go] = np.sqrt(ds_g * ds_g + dt_g * dt_g) if step_len is None else step_len
        status, n_roots, n_gone = kernels.merge_drops(
            self._buf, n, n_moved, self._fresh_buf, n_go, ks.go, ks.gcol, ks.gidx, ks.active, ks.parent, ks.nodes,
            ks.mark, ks.sums, ks.count, ks.head, ks.nxt, ks.owner, ks.ekey, ks.out, ks.mid)
        if status < 0:
            return False
        if n_roots:
            r = ks.out[:n_roots]
            d = self._buf
            d[r, _A] = drop_radius(d[r, _M])
            self._dirty = True
            self._merged_away = ks.out[n_roots : n_roots + n_gone].copy()
            self.merges += n_gone
        return True

    def _merge_moves(self, n_moved: int, go, s_g, t_g, ds_g, dt_g, step_len=None) -> None:
        """``_merge`` with the step's motion as columns (``_move``): of the first ``n_moved`` drops, those in
        ``go`` started at (s_g, t_g) and moved by (ds_g, dt_g) m (``step_len``: its length, if the caller has
        it); the others stayed where they are. Candidate pairs come from ``grid.PairFinder``; the groups are
        formed on the drops that touch only."""
        if jit.active() and self._merge_compiled(n_moved, go, s_g, t_g, ds_g, dt_g, step_len):
            return
        n = self._n
        fresh = self._fresh_buf[:n]
        if n < 2:
            fresh[:] = False
            return
        d = self._buf[:n]
        a = d[:, _A].copy()  # contiguous: gathered per pair below
        # Dense columns of the motion (trail droplets born during the step, from n_moved on, rest this time
        # and are tested from the next sub-step on). What did not move keeps its own position and reach.
        s0, t0, reach = d[:, _S].copy(), d[:, _T].copy(), a.copy()
        ds, dt_ = np.zeros(n), np.zeros(n)
        active = fresh.copy()
        active[n_moved:] = False
        fresh[:n_moved] = False
        fresh[n_moved:] = True
        mid_s, mid_t = s0.copy(), t0.copy()
        if len(go):
            s0[go], t0[go], ds[go], dt_[go] = s_g, t_g, ds_g, dt_g
            active[go[(ds_g != 0.0) | (dt_g != 0.0)]] = True
            if step_len is None:
                step_len = np.sqrt(ds_g * ds_g + dt_g * dt_g)
            reach[go] = a.take(go) + 0.5 * step_len
            mid_s[go] = s_g + 0.5 * ds_g
            mid_t[go] = t_g + 0.5 * dt_g
        if not np.count_nonzero(active):
            return
        i, j, deferred = self._pairs.pairs(mid_s, mid_t, reach, active, d[:, _S], d[:, _T], d[:, _A])
        if deferred is not None:  # over the work budget: those drops are tested again next sub-step
            deferred[n_moved:] = False
            fresh |= deferred
        if n_moved < n:
            keep = (i < n_moved) & (j < n_moved)
            i, j = i[keep], j[keep]
        if len(i) == 0:
            return
        # Closest approach of the two straight motions within the step. (take: a faster gather than a[i].)
        ps = s0.take(i)
        ps -= s0.take(j)
        pt = t0.take(i)
        pt -= t0.take(j)
        qs = ds.take(i)
        qs -= ds.take(j)
        qt = dt_.take(i)
        qt -= dt_.take(j)
        dd = qs * qs
        dd += qt * qt
        np.maximum(dd, 1e-300, out=dd)
        tau = ps * qs
        tau += pt * qt
        np.negative(tau, out=tau)
        tau /= dd
        np.maximum(tau, 0.0, out=tau)
        np.minimum(tau, 1.0, out=tau)
        ps += tau * qs
        pt += tau * qt
        ps *= ps
        pt *= pt
        ps += pt
        rr = a.take(i)
        rr += a.take(j)
        rr *= rr
        touch = (ps <= rr).nonzero()[0]
        if len(touch) == 0:
            return
        i, j = i.take(touch), j.take(touch)
        # Groups among the touching drops only, each labelled by its smallest member (grid.components).
        k = len(i)
        ij = np.concatenate([i, j])
        both = ij.copy()
        both.sort()
        nodes = both[np.concatenate(([True], both[1:] != both[:-1]))]
        ij = nodes.searchsorted(ij)
        slot = small_components(len(nodes), ij[:k], ij[k:])  # the root's place in ``nodes``
        grown = (np.bincount(slot, minlength=len(nodes)) > 1).nonzero()[0]
        if len(grown) == 0:
            return
        # Mass-weighted means over each group in index order, as the reference's bincount adds them (np.add.at
        # adds the rows in the same order, all the columns S … TRAIL at once; M's own column is overwritten).
        rows = d[nodes]
        wm = rows[:, _M]
        g_mass = np.bincount(slot, weights=wm, minlength=len(nodes))[grown]
        sums = np.zeros((len(nodes), _TRAIL + 1))
        np.add.at(sums, slot, rows[:, : _TRAIL + 1] * wm[:, None])
        r = nodes[grown]
        mean = sums[grown]
        mean /= g_mass[:, None]
        mean[:, _M] = g_mass
        d[r, : _TRAIL + 1] = mean
        d[r, _A] = drop_radius(g_mass)
        d[r, _KEY] = _DIRTY  # the position's columns are written before they are read (sim._flush_placed)
        d[r, _RB] = np.inf
        self._dirty = True
        self._fresh_buf[r] = True
        gone = nodes[slot != np.arange(len(nodes))]
        self._merged_away = gone  # removed with the shed drops (sim._shed_outside): one compaction a step
        self.merges += len(gone)
