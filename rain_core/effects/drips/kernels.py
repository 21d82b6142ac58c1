"""Compiled kernels of the drips' per-frame update (rain_core.jit): the roofs' outflow per site and the drops that
land this frame, each one loop instead of a chain of NumPy calls per range of sites.

Their NumPy twins stay the fallback and the oracle: ``DripsEffect.update``'s flux (``RoofReservoirs.outflow_m3_s``
over each roof's sites) for :func:`roof_flux`, and its landings (``flow.landing_counts`` over the visible ranges)
for :func:`landing_impacts`. Divisions, floors and products in the twin's order, no transcendentals: the same
bits (tests/effects/drips/test_kernels.py). Units: m, s, m³, kg·m/s.
"""

from __future__ import annotations

import numpy as np

from rain_core import jit


@jit.kernel
def roof_flux(storage_m3, drain_s, edges, flux, flux32):
    """Each roof's outflow per site (m³/s): storage / drain time / its site count (at least 1), into ``flux``
    (float64) and ``flux32`` (float32, the texture's upload)."""
    for r in range(storage_m3.shape[0]):
        f = storage_m3[r] / drain_s[r] / max(edges[r], 1)
        flux[r] = f
        flux32[r] = f


@jit.kernel
def landing_impacts(ranges, t0_s, t1_s, max_period_s, ground, drop_m3, flux, roof, phase, t_fall_s, x, z, momentum,
                    out):
    """The drops landing in (t0_s, t1_s] on the ground at the sites of ``ranges`` ((k, 3) float64: first site,
    count, world z offset m of the tile), in that order: a row (x, z + offset m, momentum × count kg·m/s) in ``out``
    per site with any; returns how many rows. A site's period is its drop's volume ``drop_m3`` over its roof's
    ``flux`` (at most max_period_s, where none fall); drop j lets go at (j + phase)·period and lands t_fall_s
    later (``flow.landing_counts``). ``out`` must hold the ranges' total count of rows."""
    row = 0
    for k in range(ranges.shape[0]):
        first = int(ranges[k, 0])
        z_base = ranges[k, 2]
        for i in range(first, first + int(ranges[k, 1])):
            if not ground[i]:
                continue
            period = min(drop_m3[i] / max(flux[roof[i]], 1e-300), max_period_s)
            if not period < max_period_s:
                continue
            released0 = np.floor((t0_s - t_fall_s[i]) / period - phase[i])  # floats, as the twin's (no int overflow)
            released1 = np.floor((t1_s - t_fall_s[i]) / period - phase[i])
            n = int(max(released1 - released0, 0.0))
            if n > 0:
                out[row, 0] = x[i]
                out[row, 1] = z[i] + z_base
                out[row, 2] = momentum[i] * n
                row += 1
    return row
