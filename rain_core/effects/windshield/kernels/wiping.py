"""Kernel of a wiper stroke segment: both blades' drops, film, residue and the off-glass bead
(``sweep_blades``). Twin: ``fast_wiping.FastWiping._sweep``. Units: m, rad, kg."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BLADE_HALF_WIDTH_M,
)
from rain_core.effects.windshield.drop_rows import A, M, S, T
from rain_core.effects.windshield.kernels.common import inside


@jit.kernel
def sweep_blades(buf, n, par, gone, beads, flat, areas, order, phi, off, bins, bin_r, per_area, w0, dw, height,
                 offv, offk):
    """``FastWiping._sweep`` for one stroke segment, but the drops' removal and the stroke's end: each blade b
    that moves (``par[b]``, per blade: moving, has a wedge, the wedge's two half-planes (normal s, t and bound),
    lo, hi (rad), up (1 when moving towards +angle), pivot s, t, r_inner, r_outer (m), capacity (kg a bin), cos and
    sin of its angle at the end) gathers the drops among rows [:n] it passes over (marked in ``gone``, bool, the
    first blade first) and the film cells whose centres it passes (``order``/``phi``: the cells within its radii
    sorted by angle, blade b's from ``off[b]`` to ``off[b + 1]``; ``bins`` (blade, cell) its bead bin over each)
    into its bead (``beads``, kg a bin), leaves a residue of ``per_area`` kg/m² paid from the bead and leaks what
    passes the capacity; then every blade's bins off the glass (``bin_r``: bin radii, m) are emptied into ``offv``
    (blade, bin), ``offk`` their count (the caller adds them to ``wiped``). Returns how many drops are gone."""
    nb = par.shape[0]
    n_gone = 0
    for i in range(n):
        gone[i] = False
        s = buf[i, S]
        t = buf[i, T]
        for b in range(nb):
            p = par[b]
            if p[0] == 0.0:
                continue
            if p[1] != 0.0 and not (s * p[2] + t * p[3] >= p[4] and s * p[5] + t * p[6] >= p[7]):
                continue
            rel_s = s - p[11]
            rel_t = t - p[12]
            r = math.hypot(rel_s, rel_t)
            ac = buf[i, A]
            if not (r + ac >= p[13] and r - ac <= p[14]):
                continue
            ang = math.atan2(rel_t, rel_s)
            margin = (ac + BLADE_HALF_WIDTH_M) / max(r, 1e-3)
            if p[10] != 0.0:
                swept = ang >= p[8] and ang <= p[9] + margin
            else:
                swept = ang >= p[8] - margin and ang <= p[9]
            if swept:
                k = min(max(int((r - p[13]) / (p[14] - p[13]) * BEAD_BINS), 0), BEAD_BINS - 1)
                beads[b, k] += buf[i, M]
                gone[i] = True
                n_gone += 1
                break
    for b in range(nb):
        p = par[b]
        bead = beads[b]
        if p[0] != 0.0:
            _sweep_film(flat, areas, bead, order, phi, off[b], off[b + 1], bins[b], p[8], p[9], per_area, p[15])
        offk[b] = 0
        nonzero = False
        for k in range(BEAD_BINS):
            nonzero = nonzero or bead[k] != 0.0
        if not nonzero:
            continue
        for k in range(BEAD_BINS):
            if not inside(p[11] + bin_r[b, k] * p[16], p[12] + bin_r[b, k] * p[17], w0, dw, height):
                offv[b, offk[b]] = bead[k]
                offk[b] += 1
                bead[k] = 0.0
    return n_gone


@jit.kernel
def _sweep_film(flat, areas, bead, order, phi, start, end, bins, lo, hi, per_area, cap):
    """``FastWiping._sweep_film`` of one blade between angles lo and hi (rad): see ``sweep_blades``."""
    cells = np.sort(order[start + np.searchsorted(phi[start:end], lo, "left") :
                          start + np.searchsorted(phi[start:end], hi, "right")])
    if len(cells) == 0:
        return
    for c in cells:
        bead[bins[c]] += flat[c]
        flat[c] = 0.0
    # The rubber leaves a thin residue where it pushed water, paid from the bead.
    need = np.zeros(BEAD_BINS)
    n_cells = np.zeros(BEAD_BINS, np.int64)
    for c in cells:
        need[bins[c]] += per_area * areas[c]
        n_cells[bins[c]] += 1
    scale = np.zeros(BEAD_BINS)
    for k in range(BEAD_BINS):
        has = need[k] > 0.0 if per_area > 0.0 else n_cells[k] > 0
        if has:
            scale[k] = min(1.0, bead[k] / max(need[k], 1e-300))
    paid = np.zeros(BEAD_BINS)
    for c in cells:
        leave = per_area * areas[c] * scale[bins[c]]
        flat[c] += leave
        paid[bins[c]] += leave
    leak = False
    for k in range(BEAD_BINS):
        bead[k] -= paid[k]
        has = need[k] > 0.0 if per_area > 0.0 else n_cells[k] > 0
        # Over capacity the bead leaks past the rubber: spread the excess over the cells just swept.
        scale[k] = max(bead[k] - cap, 0.0) if has else 0.0
        leak = leak or scale[k] != 0.0
    if leak:
        area_bin = np.zeros(BEAD_BINS)
        for c in cells:
            area_bin[bins[c]] += areas[c]
        for c in cells:
            flat[c] += scale[bins[c]] * (areas[c] / area_bin[bins[c]])
        for k in range(BEAD_BINS):
            bead[k] -= scale[k]
    for k in range(BEAD_BINS):
        if bead[k] < 0.0:
            bead[k] = 0.0
