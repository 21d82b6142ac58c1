"""The blades on the fast path (mixed into ``sim.WindshieldSim`` ahead of the reference's ``wiping.Wiping``):
a sweep first keeps the drops inside the blade's wedge (two half-planes through the pivot), then tests those
exactly as the reference does; film cells come from a per-blade table sorted by angle."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.constants import BEAD_BINS, BEAD_CAPACITY_KG_M, BLADE_HALF_WIDTH_M, RESIDUE_M
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.wipers import Blade
from rain_core.physics import RHO_WATER


class FastWiping:
    """The reference's drop sweep and bead bookkeeping on the drop array (its state: ``_buf``, ``_n``,
    ``beads``, ``blades``, the per-blade tables)."""

    def _sweep_drops(self, b: int, blade: Blade, ta: float, tb: float) -> None:
        """The reference's drop sweep, on the drops inside the blade's wedge only."""
        gone = self._swept_drops(b, blade, ta, tb, None)
        if gone is not None:
            self._keep(~gone)

    @staticmethod
    def _wedge_planes(blade: Blade, ta: float, tb: float, a_max: float):
        """The two half-planes through the pivot that bound what the blade sweeps between angles ta and tb (rad),
        its wedge widened by the widest angular margin a drop of radius ≤ ``a_max`` (m) can have in the blade's
        reach: ((normal, threshold), (normal, threshold)), a drop at p = (s, t) being a candidate only if
        p·normal ≥ threshold for both; None when that wedge is nearly π wide or wider (no such bound)."""
        lo, hi = min(ta, tb), max(ta, tb)
        margin = (a_max + BLADE_HALF_WIDTH_M) / max(blade.r_inner_m - a_max, 1e-3) + 1e-6
        w_lo, w_hi = (lo - 1e-6, hi + margin) if tb > ta else (lo - margin, hi + 1e-6)
        if w_hi - w_lo >= 0.9 * math.pi:
            return None
        # t·cos(w_lo) − s·sin(w_lo) ≥ that of the pivot, and s·sin(w_hi) − t·cos(w_hi) ≥ that of the pivot.
        # (Rounding moves the planes by ~1e-15 m; the wedge is widened by ≥ 1e-6 rad, ≥ 1e-7 m where a drop can be
        # swept, so any evaluation of p·normal keeps every drop the exact test can sweep.)
        px, py = float(blade.pivot[0]), float(blade.pivot[1])
        c_lo, s_lo, c_hi, s_hi = math.cos(w_lo), math.sin(w_lo), math.cos(w_hi), math.sin(w_hi)
        return ((-s_lo, c_lo), py * c_lo - px * s_lo), ((s_hi, -c_hi), px * s_hi - py * c_hi)

    def _swept_drops(self, b: int, blade: Blade, ta: float, tb: float, gone: np.ndarray | None,
                     a_max: float | None = None, in_wedge: np.ndarray | None = None):
        """Move the drops blade ``b`` sweeps between angles ta and tb (rad) into its bead, leaving out those
        already ``gone`` (bool over the drops, or None), and mark them gone; returns the mask (None: none gone).
        The caller removes the gone drops (one compaction for both blades: a drop the first swept is not there
        for the second, as in the reference, which removes them in between). ``a_max``: the largest drop
        radius (m), and ``in_wedge``: the drops inside the blade's widened wedge (bool; ``_wedge_planes``), if
        the caller has them."""
        n = self._n
        if n == 0:
            return gone
        lo, hi = min(ta, tb), max(ta, tb)
        d = self._buf[:n]
        px, py = blade.pivot
        px, py = float(px), float(py)
        if in_wedge is None:
            if a_max is None:
                a_max = float(d[:, _A].max())
            planes = self._wedge_planes(blade, ta, tb, a_max)
            if planes is not None:
                (n_lo, k_lo), (n_hi, k_hi) = planes
                s, t = d[:, _S], d[:, _T]
                in_wedge = s * n_lo[0] + t * n_lo[1] >= k_lo
                in_wedge &= s * n_hi[0] + t * n_hi[1] >= k_hi
        if in_wedge is not None:
            if gone is not None:
                in_wedge &= ~gone
            cand = in_wedge.nonzero()[0]
            if len(cand) == 0:
                return gone
        else:
            cand = np.arange(n) if gone is None else (~gone).nonzero()[0]
        rows = d.take(cand, axis=0)
        rel_s, rel_t = rows[:, _S] - px, rows[:, _T] - py
        r = np.hypot(rel_s, rel_t)
        phi = np.arctan2(rel_t, rel_s)
        ac = rows[:, _A]
        margin_c = (ac + BLADE_HALF_WIDTH_M) / np.maximum(r, 1e-3)
        in_r = (r + ac >= blade.r_inner_m) & (r - ac <= blade.r_outer_m)
        if tb > ta:
            in_phi = (phi >= lo) & (phi <= hi + margin_c)
        else:
            in_phi = (phi >= lo - margin_c) & (phi <= hi)
        swept = in_r & in_phi
        if np.count_nonzero(swept):
            idx = cand[swept]
            np.add.at(self.beads[b], self._bin_of(blade, r[swept]), rows[swept, _M])
            if gone is None:
                gone = np.zeros(n, bool)
            gone[idx] = True
        return gone

    def _sweep(self, seg, wear: float) -> None:
        """wiping.Wiping._sweep, with the blade angles in scalar math (Blade.angle, without NumPy) and the drops in
        the wedges of both blades found in one product."""
        c0 = 1.0 - math.cos(math.pi * min(max(seg.p_start, 0.0), 1.0))
        c1 = 1.0 - math.cos(math.pi * min(max(seg.p_end, 0.0), 1.0))
        moves = []
        for blade in self.blades:
            span = blade.top_rad - blade.park_rad
            moves.append((blade.park_rad + span * 0.5 * c0, blade.park_rad + span * 0.5 * c1))
        if jit.active():
            self._sweep_compiled(seg, wear, moves)
            return
        gone = None
        n = self._n
        a_max = float(self._buf[:n, _A].max()) if n else 0.0
        wedges = [None] * len(moves)
        planes = [(b, self._wedge_planes(blade, ta, tb, a_max))
                  for b, (blade, (ta, tb)) in enumerate(zip(self.blades, moves, strict=True)) if n and ta != tb]
        planes = [(b, p) for b, p in planes if p is not None]
        if planes:
            # Every half-plane at once: p·normal for each drop and plane (columns), against the thresholds.
            normals = np.array([[nrm for nrm, _ in p] for _, p in planes]).reshape(-1, 2).T
            bounds = np.array([[k for _, k in p] for _, p in planes]).ravel()
            above = self._buf[:n, _S : _T + 1] @ normals >= bounds
            for q, (b, _) in enumerate(planes):
                wedges[b] = above[:, 2 * q] & above[:, 2 * q + 1]
        for b, (blade, (ta, tb)) in enumerate(zip(self.blades, moves, strict=True)):
            if ta != tb:
                # Wiping._sweep_blade, the swept drops removed once for both blades (below).
                gone = self._swept_drops(b, blade, ta, tb, gone, a_max, wedges[b])
                self._sweep_film(b, blade, min(ta, tb), max(ta, tb), wear)
                rng = self._sweep_ranges[b]
                rng[0] = min(rng[0], ta, tb)
                rng[1] = max(rng[1], ta, tb)
            self._bead_off_glass(b, blade, tb)
        if gone is not None:
            self._keep(~gone)
        if seg.event is not None:
            for b, blade in enumerate(self.blades):
                self._end_of_stroke(b, blade, float(blade.angle(seg.p_end)), seg.event)

    def _sweep_tables(self) -> tuple:
        """What ``kernels.sweep_blades`` reads of the blades that never changes: the cells within each blade's
        radii by angle (concatenated, with offsets), the bead bin over each cell, the bins' radii."""
        if self._kw_tables is None:
            orders = [order for order, _ in self._cells_by_angle]
            off = np.zeros(len(orders) + 1, np.int64)
            off[1:] = np.cumsum([len(o) for o in orders])
            self._kw_tables = (
                np.concatenate(orders).astype(np.int64),
                np.concatenate([phi for _, phi in self._cells_by_angle]),
                off,
                np.stack(self._bins_of_cells).astype(np.int64),
                np.stack(self._bin_r),
                np.zeros((len(self.blades), BEAD_BINS)),
                np.zeros(len(self.blades), np.int64),
            )
        return self._kw_tables

    def _sweep_compiled(self, seg, wear: float, moves: list) -> None:
        """``_sweep`` from the blades' angles on, by ``kernels.sweep_blades`` (the drops, film and off-glass bead
        of both blades), the drops it gathered removed once and the stroke's end as the twin does them."""
        n = self._n
        a_max = self._a_bound  # (the shed's, right before the sweeps: the pass over the radii is spared)
        if a_max is None:
            a_max = float(self._buf[:n, _A].max()) if n else 0.0
        par = []
        for blade, (ta, tb) in zip(self.blades, moves, strict=True):
            planes = self._wedge_planes(blade, ta, tb, a_max) if n and ta != tb else None
            (n_lo, k_lo), (n_hi, k_hi) = planes if planes is not None else (((0.0, 0.0), 0.0), ((0.0, 0.0), 0.0))
            par.append((float(ta != tb), float(planes is not None), n_lo[0], n_lo[1], k_lo, n_hi[0], n_hi[1], k_hi,
                        min(ta, tb), max(ta, tb), float(tb > ta), float(blade.pivot[0]), float(blade.pivot[1]),
                        blade.r_inner_m, blade.r_outer_m,
                        BEAD_CAPACITY_KG_M * (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS,
                        math.cos(tb), math.sin(tb)))
        order, phi, off, bins, bin_r, offv, offk = self._sweep_tables()
        gone = self._scratch().gone
        n_gone = kernels.sweep_blades(self._buf, n, np.array(par), gone, self.beads, self.film.ravel(),
                                      self._areas_flat, order, phi, off, bins, bin_r,
                                      RHO_WATER * RESIDUE_M * (1.0 + 4.0 * wear), self._w0, self._dw, self._height,
                                      offv, offk)
        for b, (ta, tb) in enumerate(moves):
            if ta != tb:
                rng = self._sweep_ranges[b]
                rng[0] = min(rng[0], ta, tb)
                rng[1] = max(rng[1], ta, tb)
            if offk[b]:
                self.wiped += float(np.add.reduce(offv[b, : offk[b]]))
        if n_gone:
            self._n = kernels.compact_rows(self._buf, self._fresh_buf, n, gone)
        if seg.event is not None:
            for b, blade in enumerate(self.blades):
                self._end_of_stroke(b, blade, float(blade.angle(seg.p_end)), seg.event)

    def _sweep_film(self, b: int, blade: Blade, lo: float, hi: float, wear: float) -> None:
        """wiping.Wiping._sweep_film with fewer NumPy calls (the same operations on the same values): the cells'
        bins and areas gathered once, and a bead bin has swept cells exactly where its residue need is > 0
        (every cell wants a positive residue)."""
        cells = self._swept_cells(b, blade, lo, hi)
        if len(cells) == 0:
            return
        bead = self.beads[b]
        flat = self.film.ravel()
        bins = self._bins_of_cells[b].take(cells)
        np.add.at(bead, bins, flat.take(cells))
        flat[cells] = 0.0
        # The rubber leaves a thin residue where it pushed water, paid from the bead.
        areas = self._areas_flat.take(cells)
        per_area = RHO_WATER * RESIDUE_M * (1.0 + 4.0 * wear)
        want = per_area * areas
        need = np.bincount(bins, weights=want, minlength=BEAD_BINS)
        has_cells = need > 0 if per_area > 0.0 else np.bincount(bins, minlength=BEAD_BINS) > 0
        scale = np.where(has_cells, np.minimum(1.0, bead / np.maximum(need, 1e-300)), 0.0)
        leave = want * scale.take(bins)
        flat[cells] += leave
        bead -= np.bincount(bins, weights=leave, minlength=BEAD_BINS)
        # Over capacity the bead leaks past the rubber: spread the excess over the cells just swept.
        cap = BEAD_CAPACITY_KG_M * (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        excess = np.where(has_cells, np.maximum(bead - cap, 0.0), 0.0)
        if np.count_nonzero(excess):
            area_bin = np.bincount(bins, weights=areas, minlength=BEAD_BINS)
            share = areas / area_bin.take(bins)
            flat[cells] += excess.take(bins) * share
            bead -= excess
        np.maximum(bead, 0.0, out=bead)

    def _swept_cells(self, b: int, blade: Blade, lo: float, hi: float) -> np.ndarray:
        order, phi_sorted = self._cells_by_angle[b]  # the cells within the blade's radii, by angle
        return np.sort(order[phi_sorted.searchsorted(lo, "left") : phi_sorted.searchsorted(hi, "right")])

    def _cell_bins(self, b: int, blade: Blade, cells: np.ndarray) -> np.ndarray:
        return self._bins_of_cells[b][cells]

    def _bead_off_glass(self, b: int, blade: Blade, angle: float) -> None:
        """Water pushed past an edge of the glass leaves it: wiped (the reference's, on cached bin radii; the
        few bins in Python floats, the same operations as ``_inside``)."""
        bead = self.beads[b]
        if not any(bead.tolist()):
            return
        px, py = float(blade.pivot[0]), float(blade.pivot[1])
        ca, sa = math.cos(angle), math.sin(angle)
        height, w0, dw = self._height, self._w0, self._dw
        off = []
        for k, r in enumerate(self._bin_r_list[b]):  # every bin: the sum below adds the same elements
            s = px + r * ca
            t = py + r * sa
            if not (0.0 <= t <= height and abs(s) <= 0.5 * (w0 + dw * t)):
                off.append(k)
        if off:
            self.wiped += float(np.add.reduce(bead[off]))
            bead[off] = 0.0
