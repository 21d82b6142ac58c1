"""The wave solvers' water mask, window scrolling and impulses (issue 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.ripples.solver import WaveSolver

H = 0.05
S = 0.35


def test_dry_cells_held_at_rest(waves):
    n = 32
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    depth = np.zeros((n, n))
    depth[:, : n // 2] = 4.0  # mm of water on the left half only
    solver.set_water_mask(depth)
    solver.reset(waves.smooth_field(n))
    solver.add_impulse(0.5, 0.8, 0.2, 1e-3)
    solver.add_impulse(1.3, 0.8, 0.2, 1e-3)  # on the dry half: nothing
    e0 = solver.energy()
    for _ in range(100):
        solver.step(1 / 60)
    assert np.all(solver.height[:, n // 2:] == 0.0)
    assert np.any(solver.height[:, : n // 2] != 0.0)
    assert solver.energy() <= e0 * (1 + 1e-12)


def test_shift_scrolls_with_zero_fill():
    n = 16
    solver = WaveSolver(n, H, S)
    rng = np.random.default_rng(1)
    z = rng.standard_normal((n, n))
    solver.reset(z)
    z = solver.height.copy()
    solver.shift(3, -2)
    expect = np.zeros_like(z)
    expect[2:, : n - 3] = z[: n - 2, 3:]
    expect[0, :] = expect[-1, :] = expect[:, 0] = expect[:, -1] = 0.0
    np.testing.assert_array_equal(solver.height, expect)


def test_impulse_shape_and_volume():
    n = 64
    solver = WaveSolver(n, H, S)
    solver.reset()
    solver.add_impulse(1.6, 1.5, 0.3, 2e-3)
    z = solver.height
    iz, ix = np.unravel_index(np.argmax(z), z.shape)
    assert (ix * H, iz * H) == pytest.approx((1.6, 1.5), abs=H)
    assert z.max() == pytest.approx(2e-3, rel=0.02)
    volume = z.sum() * H * H
    assert volume == pytest.approx(2e-3 * math.pi * 0.3 ** 2 * (0.5 - 2 / math.pi ** 2), rel=0.02)
    # A sub-cell bump keeps its volume when widened.
    solver.reset()
    solver.add_impulse(1.6, 1.5, 0.01, 2e-3)
    assert solver.height.sum() * H * H == pytest.approx(2e-3 * math.pi * 0.01 ** 2 * (0.5 - 2 / math.pi ** 2),
                                                        rel=0.1)
