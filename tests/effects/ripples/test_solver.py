"""The wave solvers without OpenGL (issue 5): exactness, energy, damping and the float32 fast path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32

H = 0.05
S = 0.35


# --- exactness and energy (float64 reference) ------------------------------------------------------------------

@pytest.mark.parametrize("dt_factor", [1.0, 0.37])
def test_exact_discrete_mode_float64(waves, dt_factor):
    n, p, q = 48, 3, 2
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    dt = dt_factor * solver.dt_max
    solver.reset(waves.mode(n, H, p, q))
    steps = 400
    for _ in range(steps):
        assert solver.step(dt) == 1
    omega = waves.discrete_omega(n, H, S, dt, p, q)
    exact = waves.mode(n, H, p, q) * math.cos(omega * steps * dt)
    assert np.max(np.abs(solver.height - exact)) < 1e-12


def test_discrete_mode_converges_to_continuous_at_second_order(waves):
    errors = []
    length, t_end, p, q = 1.0, 2.0, 2, 1
    for n in (17, 33, 65):
        h = length / (n - 1)
        solver = WaveSolver(n, h, S, sleep_energy=0.0)
        dt = 0.5 * solver.dt_max
        steps = round(t_end / dt)
        solver.reset(waves.mode(n, h, p, q))
        for _ in range(steps):
            solver.step(dt)
        omega = S * math.pi * math.hypot(p, q) / length
        errors.append(np.max(np.abs(solver.height - waves.mode(n, h, p, q) * math.cos(omega * steps * dt))))
    orders = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(1.8 < o < 2.3 for o in orders), (errors, orders)


def test_energy_is_conserved_without_damping(waves):
    solver = WaveSolver(40, H, S, sleep_energy=0.0)
    solver.reset(waves.smooth_field(40))
    dt = 0.8 * solver.dt_max
    solver.step(dt)
    e0 = solver.energy()
    energies = []
    for _ in range(500):
        solver.step(dt)
        energies.append(solver.energy())
    assert e0 > 0
    assert np.max(np.abs(np.array(energies) / e0 - 1.0)) < 1e-10


def test_energy_matches_staggered_definition(waves):
    """E = h²Σ½((z−z⁻)/Δt)² + ½s²Σ_edges Δz⁻·Δz, computed here from two recorded levels."""
    n = 24
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    solver.reset(waves.smooth_field(n, 3))
    dt = 0.5 * solver.dt_max
    for _ in range(5):
        solver.step(dt)
    prev = solver.height.copy()
    solver.step(dt)
    cur = solver.height
    kinetic = 0.5 * H * H * np.sum(((cur - prev) / dt) ** 2)
    potential = 0.5 * S * S * (np.sum(np.diff(prev, axis=0) * np.diff(cur, axis=0))
                               + np.sum(np.diff(prev, axis=1) * np.diff(cur, axis=1)))
    assert solver.energy() == pytest.approx(kinetic + potential, rel=1e-12)


def test_damping_never_raises_energy_and_does_not_depend_on_dt(waves):
    n = 33
    z0 = waves.mode(n, H, 1, 1)
    results = []
    for dt in (1 / 30, 1 / 240):
        solver = WaveSolver(n, H, S, damping_per_s=0.8, sleep_energy=0.0)
        solver.reset(z0)
        energies = [solver.energy()]
        t_end = 1.0
        for _ in range(round(t_end / dt)):
            solver.step(dt)
            energies.append(solver.energy())
        assert np.all(np.diff(energies) <= 1e-14 * energies[0])
        results.append(solver.energy())
    # Same physical time, different sub-steps: the same energy loss (not twice as much at twice the steps).
    assert results[0] == pytest.approx(results[1], rel=0.02)


def test_slow_mode_amplitude_decays_at_damping_rate(waves):
    n, gamma = 33, 0.05
    solver = WaveSolver(n, H, S, damping_per_s=gamma, sleep_energy=0.0)
    z0 = waves.mode(n, H, 1, 1)
    solver.reset(z0)
    dt = 1 / 60
    # After one period the envelope of a lightly damped mode (γ ≪ ω) is e^(−γt), up to O((γ/ω)²).
    period = 2 * math.pi / waves.discrete_omega(n, H, S, dt, 1, 1)
    steps = round(period / dt)
    for _ in range(steps):
        solver.step(dt)
    ratio = np.max(np.abs(solver.height)) / np.max(np.abs(z0))
    assert ratio == pytest.approx(math.exp(-gamma * steps * dt), rel=0.01)


# --- the float32 fast path -------------------------------------------------------------------------------------

def test_f32_matches_reference(waves):
    n = 64
    ref, fast = WaveSolver(n, H, S, 0.3, sleep_energy=0.0), WaveSolverF32(n, H, S, 0.3, sleep_energy=0.0)
    z0 = waves.mode(n, H, 3, 2)
    for s in (ref, fast):
        s.reset(z0)
    for _ in range(1000):
        ref.step(0.9 * ref.dt_max)
        fast.step(0.9 * ref.dt_max)
    assert fast.height.dtype == np.float32
    assert np.max(np.abs(fast.height - ref.height)) < 2e-5 * np.max(np.abs(z0))
