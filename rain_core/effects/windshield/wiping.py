"""The blades pushing water (mixed into ``WindshieldSim``).

A blade sweeping over the glass gathers the drops and film it passes over into its bead (kg per radial bin
along the blade), leaves a thin residue paid from the bead, leaks what exceeds its capacity back into the
cells just swept, pushes water past an edge of the glass off it (wiped), and at the end of a stroke leaves
END_LEAVE_FRACTION of the bead as a row of drops and sheds the rest. The blades' geometry and motion:
``wipers``.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BEAD_CAPACITY_KG_M,
    BLADE_HALF_WIDTH_M,
    END_LEAVE_FRACTION,
    M_OBJECT_MIN,
    RESIDUE_M,
)
from rain_core.effects.windshield.wipers import Blade, StrokeSegment
from rain_core.physics import RHO_WATER


class Wiping:
    """The wiper part of ``WindshieldSim`` (its state: ``blades``, ``beads``, ``film``, the drop arrays)."""

    def bead_bin_centres(self, blade: Blade, angle: float, ahead: float = 0.0) -> np.ndarray:
        """(BEAD_BINS, 2) centres (s, t) m of the bead's bins along ``blade`` at ``angle`` (rad), ``ahead`` m in
        front of it (towards +angle)."""
        r = blade.r_inner_m + (np.arange(BEAD_BINS) + 0.5) / BEAD_BINS * (blade.r_outer_m - blade.r_inner_m)
        d = np.array([math.cos(angle), math.sin(angle)])
        nrm = np.array([-d[1], d[0]])
        return np.asarray(blade.pivot) + r[:, None] * d + ahead * nrm

    def _sweep(self, seg: StrokeSegment, wear: float) -> None:
        for b, blade in enumerate(self.blades):
            ta, tb = float(blade.angle(seg.p_start)), float(blade.angle(seg.p_end))
            if ta != tb:
                self._sweep_blade(b, blade, ta, tb, wear)
                self._sweep_ranges[b][0] = min(self._sweep_ranges[b][0], ta, tb)
                self._sweep_ranges[b][1] = max(self._sweep_ranges[b][1], ta, tb)
            self._bead_off_glass(b, blade, tb)
        if seg.event is not None:
            for b, blade in enumerate(self.blades):
                self._end_of_stroke(b, blade, float(blade.angle(seg.p_end)), seg.event)

    def _bin_of(self, blade: Blade, r: np.ndarray) -> np.ndarray:
        x = (r - blade.r_inner_m) / (blade.r_outer_m - blade.r_inner_m)
        return np.minimum(np.maximum((x * BEAD_BINS).astype(np.int64), 0), BEAD_BINS - 1)

    def _sweep_blade(self, b: int, blade: Blade, ta: float, tb: float, wear: float) -> None:
        self._sweep_drops(b, blade, ta, tb)
        self._sweep_film(b, blade, min(ta, tb), max(ta, tb), wear)

    def _sweep_drops(self, b: int, blade: Blade, ta: float, tb: float) -> None:
        """Drops: everything the rubber passed over (its width and the drop's radius as a margin ahead) joins
        the bead."""
        lo, hi = min(ta, tb), max(ta, tb)
        bead = self.beads[b]
        if self.count:
            rel = self.pos - np.asarray(blade.pivot)
            r = np.hypot(rel[:, 0], rel[:, 1])
            phi = np.arctan2(rel[:, 1], rel[:, 0])
            a = self.radius()
            margin = (a + BLADE_HALF_WIDTH_M) / np.maximum(r, 1e-3)
            in_r = (r + a >= blade.r_inner_m) & (r - a <= blade.r_outer_m)
            if tb > ta:
                in_phi = (phi >= lo) & (phi <= hi + margin)
            else:
                in_phi = (phi >= lo - margin) & (phi <= hi)
            swept = in_r & in_phi
            if swept.any():
                np.add.at(bead, self._bin_of(blade, r[swept]), self.mass[swept])
                self._keep(~swept)

    def _swept_cells(self, b: int, blade: Blade, lo: float, hi: float) -> np.ndarray:
        """Film cells (flat indices, ascending) whose centres lie in the blade's sector between lo and hi (rad)."""
        r_c, phi_c = self._cell_polar[b]
        return np.flatnonzero((r_c >= blade.r_inner_m) & (r_c <= blade.r_outer_m) & (phi_c >= lo) & (phi_c <= hi))

    def _cell_bins(self, b: int, blade: Blade, cells: np.ndarray) -> np.ndarray:
        """The bead bin of blade ``b`` over each film cell (flat indices), by the cell centre's radius."""
        return self._bin_of(blade, self._cell_polar[b][0][cells])

    def _sweep_film(self, b: int, blade: Blade, lo: float, hi: float, wear: float) -> None:
        """Film: the cells whose centres the blade passed over go into the bead, which leaves a residue and
        leaks what it cannot hold."""
        cells = self._swept_cells(b, blade, lo, hi)
        if len(cells) == 0:
            return
        bead = self.beads[b]
        flat = self.film.ravel()
        bins = self._cell_bins(b, blade, cells)
        np.add.at(bead, bins, flat[cells])
        flat[cells] = 0.0
        # The rubber leaves a thin residue where it pushed water, paid from the bead.
        want = RHO_WATER * RESIDUE_M * (1.0 + 4.0 * wear) * self._areas_flat[cells]
        need = np.bincount(bins, weights=want, minlength=BEAD_BINS)
        scale = np.where(need > 0, np.minimum(1.0, bead / np.maximum(need, 1e-300)), 0.0)
        leave = want * scale[bins]
        flat[cells] += leave
        bead -= np.bincount(bins, weights=leave, minlength=BEAD_BINS)
        # Over capacity the bead leaks past the rubber: spread the excess over the cells just swept.
        cap = BEAD_CAPACITY_KG_M * (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        has_cells = np.bincount(bins, minlength=BEAD_BINS) > 0
        excess = np.where(has_cells, np.maximum(bead - cap, 0.0), 0.0)
        if excess.any():
            area_bin = np.bincount(bins, weights=self._areas_flat[cells], minlength=BEAD_BINS)
            share = self._areas_flat[cells] / area_bin[bins]
            flat[cells] += excess[bins] * share
            bead -= excess
        np.maximum(bead, 0.0, out=bead)

    def _bead_off_glass(self, b: int, blade: Blade, angle: float) -> None:
        """Water pushed past an edge of the glass (into the cowl, off the side) leaves it: wiped."""
        off = ~self.glass.contains(self.bead_bin_centres(blade, angle))
        if off.any():
            self.wiped += float(self.beads[b][off].sum())
            self.beads[b][off] = 0.0

    def _end_of_stroke(self, b: int, blade: Blade, angle: float, event: str) -> None:
        """At a reversal the bead sheds: END_LEAVE_FRACTION stays as a row of drops just past the blade."""
        bead = self.beads[b]
        if not bead.any():
            return
        sign = 1.0 if event == "top" else -1.0  # the blade was moving towards +angle on the up-stroke
        where = self.bead_bin_centres(blade, angle, ahead=sign * 3.0 * BLADE_HALF_WIDTH_M)
        left = END_LEAVE_FRACTION * bead
        inside = self.glass.contains(where)
        left[~inside] = 0.0
        self.wiped += float((bead - left).sum())
        room = max(self._budget - self.count, 0)
        as_drop = inside & (left >= M_OBJECT_MIN)
        as_drop[np.flatnonzero(as_drop)[room:]] = False
        film_part = inside & ~as_drop & (left > 0)
        np.add.at(self.film.ravel(), self.glass.cell_index(where[film_part]), left[film_part])
        self._append(where[as_drop], np.zeros((int(as_drop.sum()), 2)), left[as_drop])
        bead[:] = 0.0
