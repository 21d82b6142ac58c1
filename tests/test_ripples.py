"""Ripple solver and field (issue 5): exactness, energy, sub-stepping, stress, backends, sources, textures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.ripples import (
    MAX_COURANT2,
    RainRippleTexture,
    RippleField,
    WaveSolver,
    WaveSolverF32,
    WaveSolverGPU,
    WheelSweep,
    choose_backend,
)

H = 0.05
S = 0.35


def mode(n: int, h: float, p: int, q: int) -> np.ndarray:
    """sin(pπx/L)·sin(qπz/L) on the grid, indexed [iz, ix]."""
    length = (n - 1) * h
    x = np.arange(n) * h
    return np.outer(np.sin(q * np.pi * x / length), np.sin(p * np.pi * x / length))


def discrete_omega(n: int, h: float, speed: float, dt: float, p: int, q: int) -> float:
    """ω_d of mode (p, q): cos(ω_d Δt) = 1 − 2C²[sin²(pπh/2L) + sin²(qπh/2L)]."""
    length = (n - 1) * h
    c2 = (speed * dt / h) ** 2
    cos_w = 1.0 - 2.0 * c2 * (math.sin(p * math.pi * h / (2 * length)) ** 2
                              + math.sin(q * math.pi * h / (2 * length)) ** 2)
    return math.acos(cos_w) / dt


def smooth_field(n: int, seed: int = 0) -> np.ndarray:
    """A few Gaussian bumps, zero at the edges (mm scale)."""
    rng = np.random.default_rng(seed)
    x = np.arange(n) * H
    xx, zz = np.meshgrid(x, x)
    length = (n - 1) * H
    out = np.zeros((n, n))
    for _ in range(4):
        cx, cz = rng.uniform(0.3, 0.7, 2) * length
        out += rng.uniform(-1e-3, 1e-3) * np.exp(-((xx - cx) ** 2 + (zz - cz) ** 2) / (0.1 * length) ** 2)
    out[0, :] = out[-1, :] = out[:, 0] = out[:, -1] = 0.0
    return out


@pytest.fixture(scope="module")
def gpu_solver_factory(gl_ctx, shaders):
    made = []

    def make(*args, **kwargs):
        solver = WaveSolverGPU(gl_ctx, *args, shaders=shaders, **kwargs)
        made.append(solver)
        return solver

    yield make
    for solver in made:
        solver.release()


# --- exactness and energy (float64 reference) --------------------------------------------------------------

@pytest.mark.parametrize("dt_factor", [1.0, 0.37])
def test_exact_discrete_mode_float64(dt_factor):
    n, p, q = 48, 3, 2
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    dt = dt_factor * solver.dt_max
    solver.reset(mode(n, H, p, q))
    steps = 400
    for _ in range(steps):
        assert solver.step(dt) == 1
    omega = discrete_omega(n, H, S, dt, p, q)
    exact = mode(n, H, p, q) * math.cos(omega * steps * dt)
    assert np.max(np.abs(solver.height - exact)) < 1e-12


def test_discrete_mode_converges_to_continuous_at_second_order():
    errors = []
    length, t_end, p, q = 1.0, 2.0, 2, 1
    for n in (17, 33, 65):
        h = length / (n - 1)
        solver = WaveSolver(n, h, S, sleep_energy=0.0)
        dt = 0.5 * solver.dt_max
        steps = round(t_end / dt)
        solver.reset(mode(n, h, p, q))
        for _ in range(steps):
            solver.step(dt)
        omega = S * math.pi * math.hypot(p, q) / length
        errors.append(np.max(np.abs(solver.height - mode(n, h, p, q) * math.cos(omega * steps * dt))))
    orders = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(1.8 < o < 2.3 for o in orders), (errors, orders)


def test_energy_is_conserved_without_damping():
    solver = WaveSolver(40, H, S, sleep_energy=0.0)
    solver.reset(smooth_field(40))
    dt = 0.8 * solver.dt_max
    solver.step(dt)
    e0 = solver.energy()
    energies = []
    for _ in range(500):
        solver.step(dt)
        energies.append(solver.energy())
    assert e0 > 0
    assert np.max(np.abs(np.array(energies) / e0 - 1.0)) < 1e-10


def test_energy_matches_staggered_definition():
    """E = h²Σ½((z−z⁻)/Δt)² + ½s²Σ_edges Δz⁻·Δz, computed here from two recorded levels."""
    n = 24
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    solver.reset(smooth_field(n, 3))
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


def test_damping_never_raises_energy_and_does_not_depend_on_dt():
    n = 33
    z0 = mode(n, H, 1, 1)
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


def test_slow_mode_amplitude_decays_at_damping_rate():
    n, gamma = 33, 0.05
    solver = WaveSolver(n, H, S, damping_per_s=gamma, sleep_energy=0.0)
    z0 = mode(n, H, 1, 1)
    solver.reset(z0)
    dt = 1 / 60
    # After one period the envelope of a lightly damped mode (γ ≪ ω) is e^(−γt), up to O((γ/ω)²).
    period = 2 * math.pi / discrete_omega(n, H, S, dt, 1, 1)
    steps = round(period / dt)
    for _ in range(steps):
        solver.step(dt)
    ratio = np.max(np.abs(solver.height)) / np.max(np.abs(z0))
    assert ratio == pytest.approx(math.exp(-gamma * steps * dt), rel=0.01)


# --- sub-stepping and changing dt ------------------------------------------------------------------------

@pytest.mark.parametrize("dt", [1e-5, 1 / 240, 1 / 30, 0.5, 10.0])
def test_substeps_keep_courant_within_bound(dt):
    solver = WaveSolver(32, H, S, damping_per_s=0.3, sleep_energy=0.0)
    k, sub = solver.plan(dt)
    assert solver.courant2(sub) <= MAX_COURANT2
    assert k * sub == pytest.approx(dt, rel=1e-12)
    solver.reset(smooth_field(32))
    e0 = solver.energy()
    for _ in range(3):
        solver.step(dt)
        assert solver.courant2(solver.substep_s) <= MAX_COURANT2
        assert np.all(np.isfinite(solver.height))
    assert solver.energy() <= e0 * (1 + 1e-12)
    assert solver.time_s == pytest.approx(3 * dt, rel=1e-12)


def test_alternating_dt_never_raises_energy_reference():
    solver = WaveSolver(40, H, S, sleep_energy=0.0)
    solver.reset(smooth_field(40, 5))
    energies = [solver.energy()]
    cycle = [1e-5, 1 / 240, 1 / 30, 0.5, 1 / 30, 1 / 240, 1e-3, 1 / 60, 1 / 59]
    for i in range(120):
        solver.step(cycle[i % len(cycle)])
        energies.append(solver.energy())
    energies = np.array(energies)
    assert np.all(np.diff(energies) <= 1e-12 * energies[0])
    assert energies[-1] > 0.3 * energies[0]  # the guard only trims what a shorter step would add


def test_jittery_dt_stays_accurate():
    """A jittering frame time retimes the state every frame; the half-kick transition keeps the scheme
    consistent, and the energy guard (which trims what each shorter step would add) costs little at a
    realistic ±5 % jitter: the error stays within 2× the constant-step error, the energy within 1 %."""
    n, p, q = 33, 1, 2
    h = 0.1
    errors, energies = [], []
    for jitter in (0.0, 0.05):
        solver = WaveSolver(n, h, S, sleep_energy=0.0)
        solver.reset(mode(n, h, p, q))
        rng = np.random.default_rng(2)
        base = 0.4 * solver.dt_max
        t = 0.0
        for _ in range(300):
            dt = base * (1.0 + jitter * rng.uniform(-1, 1))
            solver.step(dt)
            t += dt
        omega = S * math.pi * math.hypot(p, q) / solver.length_m
        errors.append(np.max(np.abs(solver.height - mode(n, h, p, q) * math.cos(omega * t))))
        energies.append(solver.energy())
    assert solver.retimes > 250
    assert errors[1] < 2.0 * errors[0]
    assert energies[1] == pytest.approx(energies[0], rel=0.01)


def test_reuse_tolerance_avoids_retiming_on_jitter():
    solver = WaveSolver(32, H, S, sleep_energy=0.0)
    solver.reset(smooth_field(32))
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


# --- stress --------------------------------------------------------------------------------------------------

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
def test_soak_1e5_steps():
    solver = WaveSolverF32(48, H, S, damping_per_s=0.05, sleep_energy=0.0)
    ref = WaveSolver(48, H, S, damping_per_s=0.05, sleep_energy=0.0)
    rng = np.random.default_rng(7)
    for s in (solver, ref):
        s.reset(smooth_field(48))
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


# --- sleep ----------------------------------------------------------------------------------------------

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


def test_never_sleeps_with_zero_threshold_or_while_sourced():
    solver = WaveSolver(24, H, S, damping_per_s=5.0, sleep_energy=0.0, sleep_check_every=1)
    solver.reset(smooth_field(24))
    for _ in range(200):
        solver.step(1 / 30)
    assert not solver.asleep
    solver = WaveSolver(24, H, S, damping_per_s=5.0, sleep_check_every=1)
    solver.reset()
    for _ in range(50):
        solver.add_impulse(0.5, 0.5, 0.1, 1e-12)  # tiny, but a source every frame
        solver.step(1 / 30)
    assert not solver.asleep


# --- mask, shift, impulses ------------------------------------------------------------------------------

def test_dry_cells_held_at_rest():
    n = 32
    solver = WaveSolver(n, H, S, sleep_energy=0.0)
    depth = np.zeros((n, n))
    depth[:, : n // 2] = 4.0  # mm of water on the left half only
    solver.set_water_mask(depth)
    solver.reset(smooth_field(n))
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


# --- backends agree --------------------------------------------------------------------------------------

def test_f32_matches_reference():
    n = 64
    ref, fast = WaveSolver(n, H, S, 0.3, sleep_energy=0.0), WaveSolverF32(n, H, S, 0.3, sleep_energy=0.0)
    z0 = mode(n, H, 3, 2)
    for s in (ref, fast):
        s.reset(z0)
    for _ in range(1000):
        ref.step(0.9 * ref.dt_max)
        fast.step(0.9 * ref.dt_max)
    assert fast.height.dtype == np.float32
    assert np.max(np.abs(fast.height - ref.height)) < 2e-5 * np.max(np.abs(z0))


def test_gpu_matches_reference_after_1000_steps(gpu_solver_factory):
    n = 64
    ref = WaveSolver(n, H, S, sleep_energy=0.0)
    gpu = gpu_solver_factory(n, H, S, sleep_energy=0.0)
    z0 = mode(n, H, 3, 2) + 0.3 * mode(n, H, 7, 5)
    for s in (ref, gpu):
        s.reset(z0)
    dt = 0.9 * ref.dt_max
    for _ in range(1000):
        ref.step(dt)
    for _ in range(1000):
        gpu.step(dt)
    assert np.max(np.abs(gpu.height - ref.height)) < 2e-5 * np.max(np.abs(z0))
    assert gpu.energy() == pytest.approx(ref.energy(), rel=1e-4)


def test_gpu_matches_reference_with_mask_sources_shift_and_dt_changes(gpu_solver_factory):
    n = 48
    ref = WaveSolver(n, H, S, damping_per_s=0.4, sleep_energy=0.0)
    gpu = gpu_solver_factory(n, H, S, damping_per_s=0.4, sleep_energy=0.0)
    mask = np.ones((n, n), bool)
    mask[30:40, 5:20] = False
    for s in (ref, gpu):
        s.set_water_mask(mask)
        s.reset(smooth_field(n, 9))
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


# --- the field around the car ----------------------------------------------------------------------------

def test_field_is_world_anchored():
    field = RippleField(None, n=64, extent_m=6.3, backend="reference", recenter_margin_cells=1)
    field.recenter(0.0, 0.0)
    field.solver.add_impulse(*(np.array([1.0, 2.0]) - field.origin_xz), 0.2, 1e-3)  # world (1, 2)
    field.solver.sleep_energy = 0.0

    def peak_world():
        z = field.height
        iz, ix = np.unravel_index(np.argmax(z), z.shape)
        return field.origin_xz[0] + ix * field.cell_m, field.origin_xz[1] + iz * field.cell_m

    assert peak_world() == pytest.approx((1.0, 2.0), abs=field.cell_m)
    shift = field.recenter(0.77, -0.52)
    assert shift != (0, 0)
    assert peak_world() == pytest.approx((1.0, 2.0), abs=field.cell_m)
    fx, fz = field.world_to_cell(1.0, 2.0)
    assert field.height[round(float(fz)), round(float(fx))] == pytest.approx(field.height.max())
    field.recenter(100.0, 0.0)  # far away: everything left the window, at rest
    assert np.all(field.height == 0.0)


def test_wheel_sweep_leaves_a_continuous_wake():
    field = RippleField(None, n=128, extent_m=12.7, backend="reference")
    field.recenter(0.0, 0.0)
    laid = field.add_wheel_sweep((-3.0, 0.5), (3.0, 0.5), speed_m_s=20.0, film_depth_mm=5.0, tire_width_m=0.2)
    assert laid >= math.floor(6.0 / field.cell_m + 1e-9)
    z = field.height
    fx0, fz = field.world_to_cell(-2.5, 0.5)
    fx1, _ = field.world_to_cell(2.5, 0.5)
    row = z[round(float(fz)), round(float(fx0)):round(float(fx1))]
    expected = 5e-3 * 20.0 / 10.0  # film depth × speed / 10 m/s
    assert np.all(row < -0.5 * expected)
    assert row.min() > -1.5 * expected
    assert field.add_wheel_sweep((-3.0, 0.5), (3.0, 0.5), 0.0, 5.0, 0.2) == 0  # standing still
    assert field.add_wheel_sweep((50.0, 50.0), (60.0, 50.0), 20.0, 5.0, 0.2) == 0  # outside the window


def test_raindrops_poisson_seeded_and_only_on_water():
    from rain_core import physics

    def run(seed):
        field = RippleField(None, n=64, extent_m=6.3, backend="numpy32", seed=seed)
        field.recenter(0.0, 0.0)
        depth = np.zeros((64, 64))
        depth[:, :32] = 3.0
        field.set_water_mask(depth)
        counts = [field.add_raindrops(5.0, 1 / 60) for _ in range(30)]
        return field, counts

    a, counts = run(3)
    b, _ = run(3)
    np.testing.assert_array_equal(a.height, b.height)
    assert np.all(a.height[:, 32:] == 0.0)
    assert np.any(a.height[:, :32] < 0.0)
    water_area = 62 * 31 * a.cell_m ** 2
    expected = physics.flux_horizontal_per_m2_s(5.0) * water_area / 60
    assert np.mean(counts) == pytest.approx(expected, rel=5 * math.sqrt(expected * 30) / (expected * 30) + 0.01)
    assert a.add_raindrops(0.0, 1 / 60) == 0


def test_raindrop_budget_keeps_momentum_flux():
    def total_dent(budget):
        field = RippleField(None, n=64, extent_m=6.3, backend="reference", seed=11,
                            max_drops_per_frame=budget)
        field.recenter(0.0, 0.0)
        for _ in range(20):
            field.add_raindrops(20.0, 1 / 30)
        return field.height.sum()

    full, capped = total_dent(10**6), total_dent(64)
    assert capped == pytest.approx(full, rel=0.25)


def test_field_update_with_film_depth_fn():
    field = RippleField(None, n=64, extent_m=6.3, backend="numpy32", seed=2)

    def film(x, z):
        return np.where(x > 0.5, 4.0, 0.0)  # mm: water east of x = 0.5 m

    wheels = [WheelSweep((-2.0, 0.0), (2.0, 0.0), 15.0, 0.2, None), ((1.0, -1.0), (1.5, -1.0), 5.0, 3.0, 0.2)]
    stats = field.update(1 / 60, center_xz=(0.0, 0.0), rate_mm_h=2.0, wheels=wheels, film_depth_fn=film)
    assert stats["substeps"] >= 1 and stats["wake_bumps"] > 0
    xs, _ = field.cell_centres_xz()
    assert np.all(field.height[xs <= 0.5] == 0.0)
    assert np.any(field.height[xs > 0.5] != 0.0)
    with pytest.raises(ValueError):
        field.update(1 / 60, wheels=[WheelSweep((0, 0), (1, 0), 5.0, 0.2, None)])


@pytest.mark.parametrize("backend", ["numpy32", "gpu"])
def test_normal_texture_is_central_difference(gl_ctx, shaders, backend):
    field = RippleField(gl_ctx, n=64, extent_m=6.3, backend=backend, shaders=shaders)
    try:
        field.recenter(0.0, 0.0)
        field.solver.add_impulse(3.0, 3.1, 0.5, 2e-2)
        field.step(1 / 30)
        z = field.height.astype(np.float64)
        slopes = np.frombuffer(field.normal_texture.read(), np.float16).reshape(64, 64, 2).astype(np.float64)
        dx = (z[1:-1, 2:] - z[1:-1, :-2]) / (2 * field.cell_m)
        dz = (z[2:, 1:-1] - z[:-2, 1:-1]) / (2 * field.cell_m)
        scale = max(np.abs(dx).max(), np.abs(dz).max())
        assert scale > 0
        assert np.max(np.abs(slopes[1:-1, 1:-1, 0] - dx)) < 2e-3 * scale
        assert np.max(np.abs(slopes[1:-1, 1:-1, 1] - dz)) < 2e-3 * scale
        resource = field.water_normals_resource()
        assert resource["texture"] is field.normal_texture
        assert resource["origin_xz_m"] == field.origin_xz and resource["extent_m"] == pytest.approx(6.3)
        h = np.frombuffer(field.height_texture.read(), np.float32)
        h = h.reshape(64, 64, -1)[..., 0]
        np.testing.assert_allclose(h, z, atol=1e-7)
    finally:
        field.release()


# --- far puddles -----------------------------------------------------------------------------------------

def test_rain_ripple_texture(gl_ctx, shaders):
    tile = RainRippleTexture(gl_ctx, size=64, shaders=shaders, seed=5)
    try:
        def slopes(t, rate):
            tile.render(t, rate)
            return np.frombuffer(tile.texture.read(), np.float16).reshape(64, 64, 2).astype(np.float64)

        assert np.all(slopes(1.0, 0.0) == 0.0)
        light, heavy = slopes(1.0, 1.0), slopes(1.0, 30.0)
        assert 0 < np.sqrt(np.mean(light ** 2)) < np.sqrt(np.mean(heavy ** 2))
        np.testing.assert_array_equal(slopes(1.0, 30.0), heavy)  # deterministic for a seed and time
        assert np.any(slopes(1.2, 30.0) != heavy)  # animated
        # Seamless: the step across the wrap is no larger than steps inside the tile.
        inside = np.max(np.abs(np.diff(heavy, axis=1)))
        assert np.max(np.abs(heavy[:, 0] - heavy[:, -1])) <= inside
        assert np.max(np.abs(heavy[0, :] - heavy[-1, :])) <= np.max(np.abs(np.diff(heavy, axis=0)))
        d_light, s_light = tile.parameters(1.0)
        d_heavy, s_heavy = tile.parameters(30.0)
        assert np.all(d_heavy > d_light) and s_heavy > s_light > 0
    finally:
        tile.release()


def test_benchmark_quick_writes_table_and_plot(tmp_path, capsys):
    from rain_core.bench import ripples as bench

    assert bench.main(["--quick", "--out", str(tmp_path)]) == 0
    text = (tmp_path / "ripples.md").read_text()
    assert "order vs continuous" in text and "chosen" in text and "asleep" in text
    assert (tmp_path / "ripples.png").stat().st_size > 1000
    orders = [float(line.split("|")[-2]) for line in text.splitlines()
              if line.startswith("| 256 |") and "NumPy float64" in line]
    assert orders and abs(orders[0] - 2.0) < 0.1


def test_film_depth_followed_with_strips_and_bands():
    """After a scroll only the entering cells are asked; each frame re-asks a band of rows; the mask always
    equals the function's verdict on the current window."""
    asked = []
    puddle_x = [0.5]

    def film(x, z):
        asked.append(np.size(x))
        return np.where(np.asarray(x) > puddle_x[0], 4.0, 0.0)

    n = 64
    field = RippleField(None, n=n, extent_m=6.3, backend="numpy32", recenter_margin_cells=1, mask_refresh_s=0.5)
    field.update(1 / 60, center_xz=(0.0, 0.0), film_depth_fn=film)
    assert asked == [n * n]
    asked.clear()
    field.update(1 / 60, center_xz=(0.31, 0.0), film_depth_fn=film)  # 3 cells east
    assert sum(asked) < 8 * n  # the 3 new columns and a band of rows, not the window
    xs, _ = field.cell_centres_xz()
    np.testing.assert_array_equal(field.solver.water_mask > 0.5, xs > 0.5)
    puddle_x[0] = 1.0  # the puddle shrinks: within mask_refresh_s every row has been re-asked
    for _ in range(31):
        field.update(1 / 60, film_depth_fn=lambda x, z: film(x, z))  # a new function object every frame
    assert max(asked[-31:]) < n * n
    np.testing.assert_array_equal(field.solver.water_mask > 0.5, xs > 1.0)
    with pytest.raises(ValueError):
        field.refresh_water_mask(lambda x, z: np.full(np.shape(x), np.nan))


def test_arriving_drops_are_flux_weighted():
    """Drops reaching the water follow N(D)·v(D) (the fast, large drops arrive more often than their share
    of the air), not the airborne N(D)."""
    from rain_core import physics

    field = RippleField(None, n=16, extent_m=1.0, backend="numpy32", seed=0)
    rate = 10.0
    d = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 20001)
    density = np.gradient(np.asarray(physics.drop_diameter_cdf(d, rate)), d)
    flux = density * np.asarray(physics.terminal_velocity(d))
    expected = np.trapezoid(d * flux, d) / np.trapezoid(flux, d)
    airborne = np.trapezoid(d * density, d) / np.trapezoid(density, d)
    samples = field._flux_weighted_diameters(physics, rate, 200_000)
    assert samples.mean() == pytest.approx(expected, rel=0.005)
    assert expected > 1.1 * airborne


from rain_core.renderer import Effect  # noqa: E402

# --- the effect in the scene ---------------------------------------------------------------------------------

class _Puddle(Effect):
    """Stands in for the road effect: publishes a film depth of 5 mm everywhere on the road."""

    name = "puddle"

    def active(self, frame):
        return True

    def update(self, frame, rc):
        rc.resources["film_depth_fn"] = lambda x, z: np.where(np.abs(np.asarray(x)) < 7.0, 5.0, 0.0)


def _ripple_scene(gl_ctx, puddles, rate=0.0):
    from rain_core.ripples import RipplesEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in (("rain.rate_mm_h", rate), ("rain.puddles", puddles), ("rain.cracks", puddles),
                        ("quality.ripple_grid", 128), ("camera.mode", "chase")):
        set_value(settings, path, value)
    effect = RipplesEffect(gl_ctx, settings, seed=1, backend="numpy32")
    return Scene(gl_ctx, (64, 36), settings=settings, seed=1, effects=[_Puddle(), effect]), effect


def test_effect_skips_without_standing_water(gl_ctx):
    scene, effect = _ripple_scene(gl_ctx, puddles=0.0, rate=0.0)
    scene.step(1 / 30)
    scene.render()
    table = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
    assert table["ripples"] is False and effect.field is None
    scene.release()


def test_driving_through_water_leaves_a_wake_behind_the_wheels(gl_ctx):
    scene, effect = _ripple_scene(gl_ctx, puddles=1.0, rate=0.0)
    for _ in range(20):
        scene.step(1 / 30)
        scene.render()
    field = effect.field
    assert field.solver.energy() > 0 and np.isfinite(field.height).all()
    ego = scene.ego
    # The wake lies along the wheels' tracks behind the car, not beside the lane.
    track_x = ego.wheel_contacts()[0, 0]
    behind = [ego.position[2] + d for d in (3.0, 5.0, 7.0)]

    def disturbance(x, z):  # largest |height| within 2 cells of (x, z)
        ix, iz = (int(round(float(v))) for v in field.world_to_cell(x, z))
        return np.abs(field.height[iz - 2: iz + 3, ix - 2: ix + 3]).max()

    on_track = np.mean([disturbance(track_x, z) for z in behind])
    off_track = np.mean([disturbance(track_x - 6.0, z) for z in behind])
    assert on_track > 5 * off_track
    names = [row[0] for row in scene.renderer.pass_table()]
    assert "ripples.update" in names
    note = dict((row[0], row[4]) for row in scene.renderer.pass_table())["ripples.update"]
    assert "numpy32" in note
    scene.release()
