"""The wave solvers' time stepping (issue 5): sub-steps, changing dt, bad input, huge impulses, sleep."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.ripples.constants import MAX_COURANT2
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32

H = 0.05
S = 0.35


# --- sub-stepping and changing dt ------------------------------------------------------------------------------

@pytest.mark.parametrize("dt", [1e-5, 1 / 240, 1 / 30, 0.5, 10.0])
def test_substeps_keep_courant_within_bound(waves, dt):
    solver = WaveSolver(32, H, S, damping_per_s=0.3, sleep_energy=0.0)
    k, sub = solver.plan(dt)
    assert solver.courant2(sub) <= MAX_COURANT2
    assert k * sub == pytest.approx(dt, rel=1e-12)
    solver.reset(waves.smooth_field(32))
    e0 = solver.energy()
    for _ in range(3):
        solver.step(dt)
        assert solver.courant2(solver.substep_s) <= MAX_COURANT2
        assert np.all(np.isfinite(solver.height))
    assert solver.energy() <= e0 * (1 + 1e-12)
    assert solver.time_s == pytest.approx(3 * dt, rel=1e-12)


def test_alternating_dt_never_raises_energy_reference(waves):
    solver = WaveSolver(40, H, S, sleep_energy=0.0)
    solver.reset(waves.smooth_field(40, 5))
    energies = [solver.energy()]
    cycle = [1e-5, 1 / 240, 1 / 30, 0.5, 1 / 30, 1 / 240, 1e-3, 1 / 60, 1 / 59]
    for i in range(120):
        solver.step(cycle[i % len(cycle)])
        energies.append(solver.energy())
    energies = np.array(energies)
    assert np.all(np.diff(energies) <= 1e-12 * energies[0])
    assert energies[-1] > 0.3 * energies[0]  # the guard only trims what a shorter step would add


def test_jittery_dt_stays_accurate(waves):
    """A jittering frame time retimes the state every frame; the half-kick transition keeps the scheme
    consistent, and the energy guard (which trims what each shorter step would add) costs little at a
    realistic ±5 % jitter: the error stays within 2× the constant-step error, the energy within 1 %."""
    n, p, q = 33, 1, 2
    h = 0.1
    errors, energies = [], []
    for jitter in (0.0, 0.05):
        solver = WaveSolver(n, h, S, sleep_energy=0.0)
        solver.reset(waves.mode(n, h, p, q))
        rng = np.random.default_rng(2)
        base = 0.4 * solver.dt_max
        t = 0.0
        for _ in range(300):
            dt = base * (1.0 + jitter * rng.uniform(-1, 1))
            solver.step(dt)
            t += dt
        omega = S * math.pi * math.hypot(p, q) / solver.length_m
        errors.append(np.max(np.abs(solver.height - waves.mode(n, h, p, q) * math.cos(omega * t))))
        energies.append(solver.energy())
    assert solver.retimes > 250
    assert errors[1] < 2.0 * errors[0]
    assert energies[1] == pytest.approx(energies[0], rel=0.01)


def test_reuse_tolerance_avoids_retiming_on_jitter(waves):
    solver = WaveSolver(32, H, S, sleep_energy=0.0)
    solver.reset(waves.smooth_field(32))
    rng = np.random.default_rng(0)
    total = 0.0
    for _ in range(600):
        dt = (1 / 60) * (1 + 0.05 * rng.uniform(-1, 1))
        total += dt
        solver.step(dt, reuse_tolerance=0.25)
        # Lag within tol/(1 − tol) of a frame, plus at most that much slipped at each sub-step change.
        assert abs(solver.time_s - total) <= (solver.retimes + 1) * 0.25 / 0.75 * 1.05 / 60
    assert solver.retimes <= 40  # of 600 frames, each of them a retime without the tolerance
    steps = solver.steps
    solver.step(2 / 60, reuse_tolerance=0.25)  # one long frame: two sub-steps, no retime
    assert solver.steps == steps + 2
    assert solver.energy() > 0


# --- stress ----------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf"), -1.0])
def test_bad_dt_rejected(bad):
    solver = WaveSolver(16, H, S)
    with pytest.raises(ValueError, match="dt_s"):
        solver.step(bad)


def test_non_finite_inputs_rejected():
    solver = WaveSolver(16, H, S)
    z = np.zeros((16, 16))
    z[5, 5] = np.nan
    with pytest.raises(ValueError, match="height0"):
        solver.reset(z)
    with pytest.raises(ValueError, match="height0"):
        solver.reset(np.zeros((15, 16)))
    for args in ((np.nan, 0.3, 0.1, 1e-3), (0.3, np.inf, 0.1, 1e-3), (0.3, 0.3, np.nan, 1e-3),
                 (0.3, 0.3, 0.1, np.inf), (0.3, 0.3, 0.1, 1e30), (0.3, 0.3, -0.1, 1e-3)):
        with pytest.raises(ValueError):
            solver.add_impulse(*args)
    with pytest.raises(ValueError):
        solver.set_water_mask(np.full((16, 16), np.nan))
    for bad in (dict(n=2), dict(cell_m=0.0), dict(speed_m_s=np.nan), dict(damping_per_s=-1.0)):
        kwargs = dict(n=16, cell_m=H, speed_m_s=S) | bad
        with pytest.raises(ValueError):
            WaveSolver(**kwargs)
    assert np.all(solver.height == 0.0)


@pytest.mark.parametrize("cls", [WaveSolver, WaveSolverF32])
def test_huge_impulses_stay_finite_and_bounded(cls):
    solver = cls(32, H, S, damping_per_s=0.2, sleep_energy=0.0)
    solver.reset()
    for amount in (1e-3, 1e3, 1e6, -1e6):
        solver.add_impulse(0.8, 0.7, 0.12, amount)
    solver.step(1 / 60)
    e0 = solver.energy()
    for dt in (1e-5, 1 / 240, 1 / 30, 0.5, 10.0):
        solver.step(dt)
        assert np.all(np.isfinite(solver.height))
        assert solver.energy() <= e0 * (1 + 1e-5)
    assert np.isfinite(solver.energy())


@pytest.mark.soak
def test_soak_1e5_steps(waves):
    solver = WaveSolverF32(48, H, S, damping_per_s=0.05, sleep_energy=0.0)
    ref = WaveSolver(48, H, S, damping_per_s=0.05, sleep_energy=0.0)
    rng = np.random.default_rng(7)
    for s in (solver, ref):
        s.reset(waves.smooth_field(48))
    choices = [1e-5, 1 / 240, 1 / 60, 1 / 30, 0.2]
    steps = 0
    e_prev = ref.energy()
    while steps < 100_000:
        if rng.random() < 0.01:
            x, z, amount = rng.uniform(0, 2.3), rng.uniform(0, 2.3), rng.uniform(-1e3, 1e3)
            for s in (solver, ref):
                s.add_impulse(x, z, 0.1, amount)
            e_prev = ref.energy()
        dt = choices[rng.integers(len(choices))]
        solver.step(dt)
        steps += ref.step(dt)
        e = ref.energy()
        assert e <= e_prev * (1 + 1e-11) + 1e-300
        e_prev = e
    assert np.all(np.isfinite(solver.height)) and np.all(np.isfinite(ref.height))


# --- sleep -----------------------------------------------------------------------------------------------------

def test_sleeps_when_settled_and_wakes_on_a_source():
    solver = WaveSolverF32(32, H, S, damping_per_s=3.0, sleep_check_every=4)
    solver.reset()
    solver.add_impulse(0.8, 0.8, 0.15, 1e-3)
    taken = 0
    for _ in range(600):
        taken += solver.step(1 / 60)
        if solver.asleep:
            break
    assert solver.asleep
    assert np.all(solver.height == 0.0)
    assert solver.step(1 / 60) == 0
    solver.add_impulse(0.8, 0.8, 0.15, 1e-3)
    assert not solver.asleep
    assert solver.step(1 / 60) >= 1


def test_never_sleeps_with_zero_threshold_or_while_sourced(waves):
    solver = WaveSolver(24, H, S, damping_per_s=5.0, sleep_energy=0.0, sleep_check_every=1)
    solver.reset(waves.smooth_field(24))
    for _ in range(200):
        solver.step(1 / 30)
    assert not solver.asleep
    solver = WaveSolver(24, H, S, damping_per_s=5.0, sleep_check_every=1)
    solver.reset()
    for _ in range(50):
        solver.add_impulse(0.5, 0.5, 0.1, 1e-12)  # tiny, but a source every frame
        solver.step(1 / 30)
    assert not solver.asleep
