"""Measurements shared by the tests and the benchmark: the real drops each drawn instance stands for, and
weighted counts in a test volume (from the float64 twin of the shaders)."""

from __future__ import annotations

import numpy as np

from rain_core.effects.rainfall.boxes import wrap_near
from rain_core.effects.rainfall.sim import RainfallSim


def drop_weights(sim: RainfallSim, index=None, time_s: float | None = None) -> np.ndarray:
    """Real drops each of the instances ``index`` (default all) stands for at time_s: 0 where it is not drawn
    (thinned out, occluded, outside its box). Mirrors the shader."""
    d = sim.drops(index, time_s)
    return np.where(d["visible"], d["weight"], 0.0)


def weighted_count(sim: RainfallSim, time_s: float | None, lo, hi) -> tuple[float, int]:
    """(Σ weights, number of drawn instances) of the drops inside the box [lo, hi] (m, world) at time_s."""
    if sim.last is None or sim.capacity == 0:
        return 0.0, 0
    d = sim.drops(None, time_s)
    p = d["pos"].copy()
    p[:, 2] = wrap_near(p[:, 2], 0.5 * (lo[2] + hi[2]))
    inside = d["visible"] & np.all((p >= lo) & (p <= hi), axis=1)
    return float(d["weight"][inside].sum()), int(inside.sum())
