"""The blades on the fast path (mixed into ``sim.WindshieldSim`` ahead of the reference's ``wiping.Wiping``):
a sweep first keeps the drops inside the blade's wedge (two half-planes through the pivot), then tests those
exactly as the reference does; film cells come from a per-blade table sorted by angle."""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import BLADE_HALF_WIDTH_M
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.wipers import Blade


class FastWiping:
    """The reference's drop sweep and bead bookkeeping on the drop array (its state: ``_buf``, ``_n``,
    ``beads``, ``blades``, the per-blade tables)."""

    def _sweep_drops(self, b: int, blade: Blade, ta: float, tb: float) -> None:
        """The reference's drop sweep, on the drops inside the blade's wedge only."""
        gone = self._swept_drops(b, blade, ta, tb, None)
        if gone is not None:
            self._keep(~gone)

    def _swept_drops(self, b: int, blade: Blade, ta: float, tb: float, gone: np.ndarray | None,
                     a_max: float | None = None):
        """Move the drops blade ``b`` sweeps between angles ta and tb (rad) into its bead, leaving out those
        already ``gone`` (bool over the drops, or None), and mark them gone; returns the mask (None: none gone).
        The caller removes the gone drops (one compaction for both blades: a drop the first swept is not there
        for the second, as in the reference, which removes them in between). ``a_max``: the largest drop
        radius (m), if the caller has it."""
        n = self._n
        if n == 0:
            return gone
        lo, hi = min(ta, tb), max(ta, tb)
        d = self._buf[:n]
        px, py = blade.pivot
        px, py = float(px), float(py)
        # The widest angular margin any drop in the blade's reach can have, and the wedge it widens.
        if a_max is None:
            a_max = float(d[:, _A].max())
        margin = (a_max + BLADE_HALF_WIDTH_M) / max(blade.r_inner_m - a_max, 1e-3) + 1e-6
        w_lo, w_hi = (lo - 1e-6, hi + margin) if tb > ta else (lo - margin, hi + 1e-6)
        if w_hi - w_lo < 0.9 * math.pi:
            # Two half-planes through the pivot bound the wedge (it is narrower than π). (Rounding moves the planes
            # by ~1e-15 m; the wedge is widened by ≥ 1e-6 rad, ≥ 1e-7 m where a drop can be swept.)
            c_lo, s_lo, c_hi, s_hi = math.cos(w_lo), math.sin(w_lo), math.cos(w_hi), math.sin(w_hi)
            s, t = d[:, _S], d[:, _T]
            in_wedge = t * c_lo - s * s_lo >= py * c_lo - px * s_lo
            in_wedge &= s * s_hi - t * c_hi >= px * s_hi - py * c_hi
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
        if swept.any():
            idx = cand[swept]
            np.add.at(self.beads[b], self._bin_of(blade, r[swept]), rows[swept, _M])
            if gone is None:
                gone = np.zeros(n, bool)
            gone[idx] = True
        return gone

    def _sweep(self, seg, wear: float) -> None:
        """wiping.Wiping._sweep, with the blade angles in scalar math (Blade.angle, without NumPy)."""
        c0 = 1.0 - math.cos(math.pi * min(max(seg.p_start, 0.0), 1.0))
        c1 = 1.0 - math.cos(math.pi * min(max(seg.p_end, 0.0), 1.0))
        gone = None
        a_max = float(self._buf[: self._n, _A].max()) if self._n else 0.0
        for b, blade in enumerate(self.blades):
            span = blade.top_rad - blade.park_rad
            ta, tb = blade.park_rad + span * 0.5 * c0, blade.park_rad + span * 0.5 * c1
            if ta != tb:
                # Wiping._sweep_blade, the swept drops removed once for both blades (below).
                gone = self._swept_drops(b, blade, ta, tb, gone, a_max)
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

    def _swept_cells(self, b: int, blade: Blade, lo: float, hi: float) -> np.ndarray:
        order, phi_sorted = self._cells_by_angle[b]  # the cells within the blade's radii, by angle
        return np.sort(order[phi_sorted.searchsorted(lo, "left") : phi_sorted.searchsorted(hi, "right")])

    def _cell_bins(self, b: int, blade: Blade, cells: np.ndarray) -> np.ndarray:
        return self._bins_of_cells[b][cells]

    def _bead_off_glass(self, b: int, blade: Blade, angle: float) -> None:
        """Water pushed past an edge of the glass leaves it: wiped (the reference's, on cached bin radii)."""
        bead = self.beads[b]
        if not bead.any():
            return
        r = self._bin_r[b]
        s = blade.pivot[0] + r * math.cos(angle)
        t = blade.pivot[1] + r * math.sin(angle)
        off = ~self._inside(s, t)
        if off.any():
            self.wiped += float(bead[off].sum())
            bead[off] = 0.0
