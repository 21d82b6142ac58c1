"""rain_core.effects.windshield.merging / grid: merging conserves, fast drops do not tunnel, the hash finds pairs."""

import numpy as np
import pytest

from rain_core.effects.windshield import WindshieldSim, drop_mass
from rain_core.effects.windshield.grid import grid_pairs


def test_merging_conserves_mass_momentum_and_centre_of_mass():
    sim = WindshieldSim(seed=0)
    a = 1.5e-3
    pos = np.array([[0.0, 0.5], [2.5e-3, 0.5], [4.9e-3, 0.5], [0.2, 0.3]])  # a chain of three, one apart
    vel = np.array([[0.0, 0.1], [0.0, 0.0], [0.02, 0.0], [0.0, 0.0]])
    mass = drop_mass(np.array([a, a, 0.8 * a, a]))
    sim._append(pos, vel, mass)
    p0, m0 = (mass[:, None] * vel).sum(axis=0), mass.sum()
    c0 = (mass[:, None] * pos)[:3].sum(axis=0) / mass[:3].sum()
    sim._merge(sim.pos.copy(), np.zeros_like(sim.pos))
    assert sim.count == 2
    assert sim.mass.sum() == pytest.approx(m0, rel=1e-14)
    assert (sim.mass[:, None] * sim.vel).sum(axis=0) == pytest.approx(p0, rel=1e-12)
    big = int(np.argmax(sim.mass))
    assert sim.mass[big] == pytest.approx(mass[:3].sum())
    assert sim.pos[big] == pytest.approx(c0)


def test_fast_drops_do_not_tunnel_through_others():
    sim = WindshieldSim(seed=0)
    sim._append(np.array([[0.0, 0.55], [0.0, 0.5]]), np.zeros((2, 2)), drop_mass(np.array([1e-3, 1e-3])))
    start = np.array([[0.0, 0.45], [0.0, 0.5]])
    disp = np.array([[0.0, 0.1], [0.0, 0.0]])  # the first jumps right over the second within one step
    sim._merge(start, disp)
    assert sim.count == 1


def test_grid_finds_every_touching_pair():
    rng = np.random.default_rng(2)
    for _ in range(10):
        n = int(rng.integers(50, 600))
        p = rng.uniform([-0.7, 0.0], [0.7, 1.1], (n, 2))
        reach = rng.exponential(0.002, n) * rng.choice([1.0, 1.0, 1.0, 12.0], n)
        active = rng.random(n) < 0.3
        i, j = grid_pairs(p, reach, active)
        found = set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))
        d = np.linalg.norm(p[:, None] - p[None], axis=2)
        ii, jj = np.nonzero((d <= reach[:, None] + reach[None]) & np.triu(np.ones((n, n), bool), 1))
        want = {(a, b) for a, b in zip(ii.tolist(), jj.tolist(), strict=True) if active[a] or active[b]}
        assert want <= found
