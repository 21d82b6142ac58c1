"""Fixtures of the windshield tests."""

import numpy as np
import pytest

from rain_core.effects.windshield import WindshieldSim, drop_mass


def _scatter(sim: WindshieldSim, n: int, radius_mm: tuple[float, float], seed: int = 0) -> None:
    """Put n resting drops of contact radius uniform in radius_mm (mm) on the glass, away from its edges."""
    rng = np.random.default_rng(seed)
    g = sim.glass
    uv = rng.uniform(0.1, 0.9, (n, 2))
    a = rng.uniform(*radius_mm, n) * 1e-3
    sim._append(g.from_uv(uv), np.zeros((n, 2)), drop_mass(a))
    sim.arrived += float(drop_mass(a).sum())


@pytest.fixture
def scatter():
    """``scatter(sim, n, radius_mm, seed=0)``: put n resting drops on the glass (counted as arrived)."""
    return _scatter
