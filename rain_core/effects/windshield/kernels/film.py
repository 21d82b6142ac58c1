"""Kernels of the film: evaporation, where beads form, the drying rate per cell and the rain sensor's masses
(``sim``'s twins). Units: m, s, kg."""

from __future__ import annotations

import math

from rain_core import jit
from rain_core.effects.windshield.constants import (
    CROSSWIND_GAIN,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    FLOW_AT_BOTTOM,
    FLOW_SPREAD,
)
from rain_core.effects.windshield.drop_rows import M, S, T


@jit.kernel
def bead_points(cells, r, w0, dw, height, st):
    """``WindshieldSim._film_step``'s beads placed: for the film ``cells`` (flat indices) and the uniform numbers
    ``r`` (2k: across, then up the cell), the points (s, t) m on the glass into ``st`` (2, k) (the cell's UV
    plus the draw, then ``DropArray._bead_drops``' GlassGeometry.from_uv; the same operations)."""
    k = cells.shape[0]
    for j in range(k):
        iv = cells[j] // FILM_CELLS
        iu = cells[j] - iv * FILM_CELLS
        u = (iu + r[j]) / FILM_CELLS
        v = (iv + r[k + j]) / FILM_CELLS
        t = v * height
        st[0, j] = (u - 0.5) * (w0 + dw * t)
        st[1, j] = t


@jit.kernel
def evaporate_film(flat, evap, loss, bead_mass, thick):
    """``WindshieldSim._film_step``'s drying: each cell of ``flat`` (kg) loses its ``evap`` (kg this sub-step),
    at most what it has (into ``loss``); the cells then above ``bead_mass`` (kg) go to ``thick`` in order.
    Returns how many."""
    k = 0
    for c in range(flat.shape[0]):
        lo = min(flat[c], evap[c])
        loss[c] = lo
        flat[c] -= lo
        if flat[c] > bead_mass[c]:
            thick[k] = c
            k += 1
    return k


@jit.kernel
def film_drying(head, cross, cell_up, cell_q, areas, evap):
    """``WindshieldSim._prepare``'s drying of the film: per cell (factors ``cell_up``, ``cell_q`` of its centre,
    area ``areas`` m²) the air over it for ``head`` along and ``cross`` across the glass (m/s; airflow's formula)
    and the film's evaporation in it, kg/s for a wet cell, into ``evap``."""
    for c in range(evap.shape[0]):
        up = head * cell_up[c] if head >= 0.0 else head * FLOW_AT_BOTTOM
        side = abs(up) * FLOW_SPREAD * cell_q[c] + CROSSWIND_GAIN * cross
        air = math.sqrt(side * side + up * up)
        evap[c] = FILM_EVAP_KG_M2_S * (1.0 + air / EVAP_AIR_M_S) * areas[c]


@jit.kernel
def sensor_masses(buf, n, s_lo, s_hi, t_lo, t_hi, out):
    """The masses (kg) of the drops among rows [:n] inside the rain sensor's box (s, t within the bounds, m), in
    row order into ``out``; returns how many (the caller sums them as the twin does)."""
    k = 0
    for i in range(n):
        s = buf[i, S]
        t = buf[i, T]
        if s >= s_lo and s <= s_hi and t >= t_lo and t <= t_hi:
            out[k] = buf[i, M]
            k += 1
    return k
