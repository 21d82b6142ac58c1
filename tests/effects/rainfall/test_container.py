"""rainfall: the physics of the spawned drops, the container's drawn density, the container's placement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.rainfall import RainfallSim, drawn_share, full_region, layer_boxes, weighted_count

# --- physics of the spawned drops ----------------------------------------------------------------------------


def test_spawned_diameters_and_speeds_follow_the_physics(rain):
    rate = 8.0
    sim = RainfallSim(40000, seed=2)
    sim.advance(rain.input(0.0, rate=rate))
    slots = np.flatnonzero(sim.pool.alive)
    d = sim.diameter[slots]
    n = d.size
    assert n > 20000
    # The first fill is the air's population: N(D) (one KS test at the 0.1 % level, seeded).
    assert physics.ks_distance(d, rate) < 1.95 / math.sqrt(n)
    # Fall speeds are the measured terminal velocities of those diameters (no wind: purely vertical).
    v = -sim.vel[slots, 1]
    np.testing.assert_allclose(v, physics.terminal_velocity(d), rtol=1e-12)
    assert np.all(sim.vel[slots][:, [0, 2]] == 0.0)
    # The speed distribution, tested on its own: F_v(v) = F_D(v⁻¹(v)) (v is monotone in D).
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 4001)
    v_sorted = np.sort(v)
    f_v = np.interp(v_sorted, physics.terminal_velocity(grid), physics.drop_diameter_cdf(grid, rate))
    i = np.arange(1, n + 1)
    ks_v = max((i / n - f_v).max(), (f_v - (i - 1) / n).max())
    assert ks_v < 1.95 / math.sqrt(n)
    # With the camera still, every later spawn falls in through a top face: in proportion to N(D)·v(D).
    t = 0.0
    new = []
    for _ in range(20):
        t += 0.5
        upd = sim.advance(rain.input(t, rate=rate))
        new.append(sim.diameter[upd.spawn_slots])
    df = np.sort(np.concatenate(new))
    weights = physics.marshall_palmer(grid, rate) * physics.terminal_velocity(grid)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (weights[1:] + weights[:-1]) * np.diff(grid))])
    f = np.interp(df, grid, cdf / cdf[-1])
    m = df.size
    j = np.arange(1, m + 1)
    assert m > 2000
    assert max((j / m - f).max(), (f - (j - 1) / m).max()) < 1.95 / math.sqrt(m)
    # …while diameters drawn from N(D) alone would fail the same test.
    f_n = physics.drop_diameter_cdf(df, rate)
    assert max((j / m - f_n).max(), (f_n - (j - 1) / m).max()) > 3.0 / math.sqrt(m)


@pytest.mark.parametrize("speed, wind", [(0.0, (0.0, 0.0, 0.0)), (27.8, (3.0, 0.0, 2.0))])
def test_expected_count_in_a_test_volume_within_5_percent(speed, wind, rain):
    """Weighted drops per m³ in a test box of each layer's full region equal the physical density."""
    rate = 8.0
    sims = [RainfallSim(30000, seed=s) for s in range(2)]
    ratios = []
    for sim in sims:
        t = rain.drive(sim, 4.0, speed=speed, rate=rate, wind=wind)
        for _ in range(3):  # a few frames a second apart, averaged
            t = rain.drive(sim, 1.0, speed=speed, rate=rate, wind=wind, t0=t + 1.0 / 30.0)
            for k in range(3):
                lo, hi = full_region(sim.boxes, k)
                w, _ = weighted_count(sim, t, lo, hi)
                ratios.append((k, w / (physics.number_density_per_m3(rate) * np.prod(hi - lo))))
    for k in range(3):
        mean = np.mean([r for kk, r in ratios if kk == k])
        assert abs(mean - 1.0) < 0.05, (k, mean)
    # The drawn count follows the physical density until the budget is full (heavy rain).
    light = RainfallSim(8000, seed=1)
    light.advance(rain.input(0.0, rate=0.5))
    heavy = RainfallSim(8000, seed=1)
    heavy.advance(rain.input(0.0, rate=28.0))
    assert light.live == pytest.approx(drawn_share(0.5) * heavy.live, rel=0.1)
    assert drawn_share(0.5) < 0.5 and drawn_share(28.0) == 1.0



def test_container_follows_the_camera_and_looks_ahead():
    boxes = layer_boxes([0.0, 1.2, 100.0], [0.0, 0.0, -1.0], 40.0)
    lo, hi = boxes.lo, boxes.hi
    assert np.all(lo[:, 2] < 100.0) and np.all(hi[:, 2] > 100.0)  # the camera is inside every box
    assert np.all(100.0 - lo[:, 2] > 3.0 * (hi[:, 2] - 100.0))  # most of each box is in front
    assert np.all(np.diff(hi[:, 0] - lo[:, 0]) > 0)  # nested, growing
    down = layer_boxes([0.0, 5.0, 100.0], [0.0, -1.0, 0.0], 40.0)
    np.testing.assert_allclose(0.5 * (down.lo[:, 2] + down.hi[:, 2]), 100.0)  # looking down: centred
