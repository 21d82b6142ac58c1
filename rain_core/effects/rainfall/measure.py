"""Measurements shared by the tests and the benchmark: the real drops each drawn drop stands for, and weighted
counts in a test volume."""

from __future__ import annotations

import numpy as np

from rain_core.effects.rainfall.boxes import Boxes, drawn_density_factor, membership, wrap_near
from rain_core.effects.rainfall.sim import RainfallSim


def drop_weights(sim: RainfallSim, slots, p: np.ndarray, boxes: Boxes) -> np.ndarray:
    """Real drops each of ``slots`` (at positions p, m) stands for: a·m_own/max(Σν·m, ν_outer). Mirrors the
    shader; 0 outside its box."""
    slots = np.asarray(slots)
    return sim.weight[slots] * membership(p, boxes, sim.layer[slots]) / drawn_density_factor(p, boxes)


def weighted_count(sim: RainfallSim, time_s: float, lo, hi) -> tuple[float, int]:
    """(Σ weights, number of drawn drops) of the live drops inside the box [lo, hi] (m, world) at time_s."""
    slots = np.flatnonzero(sim.pool.alive)
    if slots.size == 0 or sim.boxes is None:
        return 0.0, 0
    p = sim.positions(slots, time_s)
    centre_z = 0.5 * (lo[2] + hi[2])
    p[:, 2] = wrap_near(p[:, 2], centre_z)
    live = time_s < sim.t_hit[slots]
    inside = live & np.all((p >= lo) & (p <= hi), axis=1)
    w = drop_weights(sim, slots[inside], p[inside], sim.boxes)
    return float(w.sum()), int(inside.sum())

