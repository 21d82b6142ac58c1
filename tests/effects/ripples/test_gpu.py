"""The GPU wave solver against the float64 reference, and the timed backend choice (issue 5)."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.effects.ripples.backend import choose_backend
from rain_core.effects.ripples.solver import WaveSolver

H = 0.05
S = 0.35


def test_gpu_matches_reference_after_1000_steps(waves, gpu_solver_factory):
    n = 64
    ref = WaveSolver(n, H, S, sleep_energy=0.0)
    gpu = gpu_solver_factory(n, H, S, sleep_energy=0.0)
    z0 = waves.mode(n, H, 3, 2) + 0.3 * waves.mode(n, H, 7, 5)
    for s in (ref, gpu):
        s.reset(z0)
    dt = 0.9 * ref.dt_max
    for _ in range(1000):
        ref.step(dt)
    for _ in range(1000):
        gpu.step(dt)
    assert np.max(np.abs(gpu.height - ref.height)) < 2e-5 * np.max(np.abs(z0))
    assert gpu.energy() == pytest.approx(ref.energy(), rel=1e-4)


def test_gpu_matches_reference_with_mask_sources_shift_and_dt_changes(waves, gpu_solver_factory):
    n = 48
    ref = WaveSolver(n, H, S, damping_per_s=0.4, sleep_energy=0.0)
    gpu = gpu_solver_factory(n, H, S, damping_per_s=0.4, sleep_energy=0.0)
    mask = np.ones((n, n), bool)
    mask[30:40, 5:20] = False
    for s in (ref, gpu):
        s.set_water_mask(mask)
        s.reset(waves.smooth_field(n, 9))
    rng = np.random.default_rng(4)
    for frame in range(40):
        xs, zs = rng.uniform(0, 2.3, 5), rng.uniform(0, 2.3, 5)
        amounts = rng.uniform(-1e-3, 1e-3, 5)
        dt = [1 / 60, 1 / 30, 1 / 240, 0.2][frame % 4]
        for s in (ref, gpu):
            s.add_impulses(xs, zs, 0.08, amounts)
            if frame == 20:
                s.shift(2, -3)
            s.step(dt)
    scale = np.max(np.abs(ref.height))
    assert np.max(np.abs(gpu.height - ref.height)) < 1e-4 * scale
    assert gpu.energy() == pytest.approx(ref.energy(), rel=1e-3)
    assert np.all(gpu.height[~np.asarray(ref.water_mask, bool)] == 0.0)


def test_gpu_sleeps_too(gpu_solver_factory):
    gpu = gpu_solver_factory(32, H, S, damping_per_s=4.0, sleep_check_every=2)
    gpu.reset()
    gpu.add_impulse(0.7, 0.7, 0.15, 1e-3)
    for _ in range(600):
        gpu.step(1 / 30)
        if gpu.asleep:
            break
    assert gpu.asleep and gpu.step(1 / 30) == 0


def test_choose_backend_reports_both_paths(gl_ctx):
    choice, timings = choose_backend(gl_ctx, 64, steps=3)
    assert choice in ("numpy32", "gpu")
    assert set(timings) == {"numpy32_ms", "gpu_ms"}
    assert all(v > 0 for v in timings.values())
    assert choose_backend(None, 64, steps=3)[0] == "numpy32"


@pytest.mark.parametrize("order", ["blocks_then_bumps", "bumps_then_blocks", "bumps_only"])
def test_gpu_scroll_drawn_with_the_next_mask_equals_the_reference(waves, gpu_solver_factory, order):
    """A scroll is drawn by the next pass that needs the state, under the mask blocks written after it (one pass
    instead of a scroll and a masking pass): the same water as the reference's scroll-then-mask, whatever
    comes between the scroll and that pass (bumps laid on the scrolled window, new mask blocks, both)."""
    n = 40
    ref = WaveSolver(n, H, S, damping_per_s=0.2, sleep_energy=0.0)
    gpu = gpu_solver_factory(n, H, S, damping_per_s=0.2, sleep_energy=0.0)
    mask = np.ones((n, n), bool)
    mask[5:12, 20:30] = False
    rng = np.random.default_rng(8)
    for s in (ref, gpu):
        s.set_water_mask(mask)
        s.reset(waves.smooth_field(n, 3))
        s.step(1 / 30)
    for frame in range(6):
        dx, dz = [(0, 3), (1, -2), (0, 0), (-4, 0), (0, 5), (2, 2)][frame]
        rows = rng.random((abs(dz) + 2, n)) > 0.3  # the strip that entered and a band, some of it dry
        row0 = n - rows.shape[0] if dz >= 0 else 0
        xs, zs, amounts = rng.uniform(0.2, 1.8, 4), rng.uniform(0.2, 1.8, 4), rng.uniform(-1e-3, 1e-3, 4)
        for s in (ref, gpu):
            s.shift(dx, dz)
            if order == "bumps_then_blocks":
                s.add_impulses(xs, zs, 0.1, amounts)
            if order != "bumps_only":
                s.set_water_mask_blocks([(row0, 0, rows)])
            if order != "bumps_then_blocks":
                s.add_impulses(xs, zs, 0.1, amounts)
            s.step(1 / 30)
        np.testing.assert_array_equal(gpu.water_mask, ref.water_mask)
        scale = np.max(np.abs(ref.height))
        assert np.max(np.abs(gpu.height - ref.height)) < 1e-4 * scale
        assert np.all(gpu.height[ref.water_mask < 0.5] == 0.0)
