"""The ripples under bad and extreme input (issue 18), and the frame's single impulse batch (issue 13).

Each audited case is its own test: sizes that would explode an allocation are refused with a ValueError naming
the field and the range; any finite dt keeps the field finite; strings are not numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.ripples.constants import MAX_CELLS_PER_SIDE
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.wheels import WheelBatch
from rain_core.effects.ripples.window import field_grid

H = 0.05
S = 0.35
SOLVERS = [WaveSolver, WaveSolverF32]


def _moving(cls, n: int = 32, **kwargs):
    """A solver with a ripple in flight, stepped once at a normal frame time."""
    solver = cls(n, H, S, damping_per_s=0.3, sleep_energy=0.0, **kwargs)
    solver.add_impulse(0.8, 0.7, 0.12, 1e-3)
    solver.step(1 / 60)
    return solver


# --- sizes that would exhaust memory ---------------------------------------------------------------------------

@pytest.mark.parametrize("cls", SOLVERS)
def test_solver_grid_of_a_million_cells_per_side_is_refused(cls):
    with pytest.raises(ValueError, match=rf"n must be an int in \[3, {MAX_CELLS_PER_SIDE}\]"):
        cls(10**6, H, S)


def test_field_grid_of_a_million_cells_per_side_is_refused():
    with pytest.raises(ValueError, match="n must be an int in"):
        field_grid(10**6, 25.0)
    with pytest.raises(ValueError, match="n must be an int in"):
        RippleField(n=10**6)


@pytest.mark.parametrize("cls", SOLVERS)
def test_impulse_radius_of_a_million_metres_is_refused(cls):
    solver = cls(32, H, S)
    with pytest.raises(ValueError, match=r"radius_m must be .*\[0, 1\.55\]"):
        solver.add_impulse(0.8, 0.8, 1e6, 1e-3)
    with pytest.raises(ValueError, match=r"radius_m must be in \[0, 1\.55\] m"):
        solver.add_impulses([0.8, 0.4], [0.8, 0.4], [0.1, 1e6], [1e-3, 1e-3])
    assert np.all(solver.height == 0.0)


@pytest.mark.parametrize("cls", SOLVERS)
def test_impulse_as_wide_as_the_field_is_clipped_to_the_grid(cls):
    n = 256
    solver = cls(n, H, S, sleep_energy=0.0)
    solver.add_impulse(solver.length_m / 2, solver.length_m / 2, solver.max_radius_m, 1e-3)
    z = solver.height
    assert np.isfinite(z).all() and z.max() == pytest.approx(1e-3, rel=1e-3)
    assert np.all(z[0] == 0.0) and np.all(z[:, -1] == 0.0)  # the fixed edges stay at rest


def test_mixed_radii_in_one_batch_equal_separate_impulses():
    """One batch mixes raindrop, wake and wide bumps (evaluated in groups of equal reach): the same field as
    adding each bump on its own."""
    rng = np.random.default_rng(3)
    xs, zs = rng.uniform(-0.2, 3.4, 60), rng.uniform(-0.2, 3.4, 60)
    radii = np.concatenate([np.full(40, 0.004), rng.uniform(0.05, 0.3, 15), [1.0, 2.0, 3.1, 0.0, 0.6]])
    amounts = rng.uniform(-1e-3, 1e-3, 60)
    batch, single = WaveSolver(64, H, S), WaveSolver(64, H, S)
    batch.add_impulses(xs, zs, radii, amounts)
    for args in zip(xs, zs, radii, amounts, strict=True):
        single.add_impulse(*args)
    np.testing.assert_allclose(batch.height, single.height, rtol=1e-12, atol=1e-18)


# --- dt: huge, infinite, denormal, tiny, not a number ----------------------------------------------------------

@pytest.mark.parametrize("cls", SOLVERS)
def test_step_of_1e308_seconds_stays_finite(cls):
    solver = _moving(cls, max_substeps=50)
    assert solver.step(1e308) == 50  # shortened to max_substeps·Δt_max, as any long stall
    solver.step(1 / 60)
    assert np.isfinite(solver.height).all() and math.isfinite(solver.energy())


@pytest.mark.parametrize("cls", SOLVERS)
def test_step_of_1e308_with_reuse_tolerance_stays_finite(cls):
    solver = _moving(cls, max_substeps=50)
    solver.step(1e308, reuse_tolerance=0.25)
    for _ in range(5):
        solver.step(1 / 60, reuse_tolerance=0.25)
    assert np.isfinite(solver.height).all() and math.isfinite(solver.energy())


@pytest.mark.parametrize("cls", SOLVERS)
def test_infinite_dt_is_refused_naming_dt(cls):
    solver = _moving(cls)
    with pytest.raises(ValueError, match="dt_s must be finite"):
        solver.step(math.inf)
    assert np.isfinite(solver.height).all()


@pytest.mark.parametrize("cls", SOLVERS)
def test_denormal_dt_between_normal_steps_keeps_the_field_finite(cls):
    solver = _moving(cls)
    e0 = solver.energy()
    assert solver.step(5e-324) == 0  # nothing a float can hold moves in 5e-324 s: carried, not stepped
    for _ in range(3):
        solver.step(1 / 60)
    assert np.isfinite(solver.height).all()
    assert 0.0 < solver.energy() <= e0 * (1 + 1e-5)


@pytest.mark.parametrize("cls", SOLVERS)
def test_repeated_1e_200_dt_neither_raises_nor_spoils_the_field(cls):
    solver = _moving(cls)
    for _ in range(1000):
        assert solver.step(1e-200) == 0
    solver.step(1 / 60)
    assert np.isfinite(solver.height).all() and math.isfinite(solver.energy())


def test_tiny_steps_are_carried_not_lost():
    solver = _moving(WaveSolver)
    t0 = solver.time_s
    tiny = 0.4 * solver.min_step_s
    taken = sum(solver.step(tiny) for _ in range(3))
    assert taken == 1  # the third call brings the carried time past the threshold
    assert solver.time_s - t0 == pytest.approx(3 * tiny, rel=1e-9)


@pytest.mark.parametrize("bad", ["1", b"1", None, [1 / 60], True, {"dt": 1}])
@pytest.mark.parametrize("cls", SOLVERS)
def test_non_numeric_dt_is_refused_naming_dt(cls, bad):
    solver = _moving(cls)
    with pytest.raises(ValueError, match="dt_s"):
        solver.step(bad)


def test_field_update_refuses_a_string_dt():
    field = RippleField(n=16, extent_m=1.5)
    with pytest.raises(ValueError, match="dt_s"):
        field.update("1")


# --- the field's own bounds ------------------------------------------------------------------------------------

def test_max_drops_per_frame_is_bounded():
    with pytest.raises(ValueError, match="max_drops_per_frame"):
        RippleField(n=16, extent_m=1.5, max_drops_per_frame=10**9)


def test_bad_and_huge_droplet_impacts_keep_the_field_finite():
    field = RippleField(n=32, extent_m=3.1, backend="reference")
    field.recenter(0.0, 0.0)
    impacts = np.array([[0.1, 0.2, 1e-4], [np.nan, 0.0, 1.0], [0.3, 0.3, 1e300], [0.0, np.inf, 1.0]])
    assert field.add_droplet_impacts(impacts) == 2
    field.step(1 / 60)
    assert np.isfinite(field.height).all()
    with pytest.raises(ValueError, match="impacts"):
        field.add_droplet_impacts("not impacts")


def test_wheel_batch_names_the_bad_field():
    good = dict(p0_xz=np.zeros((1, 2)), p1_xz=np.ones((1, 2)), speed_m_s=np.ones(1), tire_width_m=np.full(1, 0.2))
    for name, value in (("speed_m_s", np.full(1, np.nan)), ("speed_m_s", np.full(1, -1.0)),
                        ("tire_width_m", np.full(1, 1e6)), ("p0_xz", np.full((1, 2), np.inf))):
        with pytest.raises(ValueError, match=name):
            WheelBatch.of(WheelBatch(**(good | {name: value})))


# --- one batch a frame -----------------------------------------------------------------------------------------

def _frame_sources(field):
    wheels = [((-2.0, 0.2), (2.0, 0.2), 15.0, None, 0.2), ((1.0, -1.0), (1.5, -1.0), 5.0, 3.0, 0.2)]
    impacts = np.array([[0.3, 0.1, 2e-4], [-0.4, 0.5, 1e-4]])
    return field.update(1 / 30, center_xz=(0.0, 0.0), rate_mm_h=8.0, wheels=wheels, impacts=impacts,
                        film_depth_fn=lambda x, z: np.full(np.shape(x), 4.0))


def test_a_frames_sources_reach_the_solver_as_one_batch():
    field = RippleField(n=64, extent_m=6.3, backend="numpy32", seed=5)
    calls = []
    original = field.solver.add_impulses_unchecked
    field.solver.add_impulses_unchecked = lambda *a: (calls.append(len(a[0])), original(*a))
    report = _frame_sources(field)
    assert report["drops"] > 0 and report["wake_bumps"] > 0
    assert len(calls) == 1 and calls[0] >= report["drops"] + report["wake_bumps"] + 2


def test_gpu_field_draws_the_frames_bumps_with_one_write_and_one_draw(gl_ctx, shaders):
    from rain_core.effects.ripples.backend import make_field

    field = make_field(gl_ctx, n=64, extent_m=6.3, backend="gpu", seed=5, shaders=shaders)
    ref = RippleField(n=64, extent_m=6.3, backend="reference", seed=5)
    solver = field.solver
    counts = {"write": 0, "render": 0}

    class Spy:
        def __init__(self, target, method):
            self.target, self.method = target, method

        def __getattr__(self, name):
            attr = getattr(self.target, name)
            if name == self.method:
                def counted(*args, **kwargs):
                    counts[name] += 1
                    return attr(*args, **kwargs)
                return counted
            return attr

    solver._grow_bumps(1 << 16)  # room for the whole frame: the spies stay in place
    try:
        solver._bump_buffer = Spy(solver._bump_buffer, "write")
        solver._bump_vao = Spy(solver._bump_vao, "render")
        report = _frame_sources(field)
        assert counts == {"write": 1, "render": 1}
        _frame_sources(ref)  # the same seed: the same drops, wakes and droplets on the float64 reference
        scale = np.abs(ref.height).max()
        assert scale > 0 and report["drops"] > 0
        assert np.abs(field.height - ref.height).max() < 1e-4 * scale
    finally:
        for name in ("_bump_buffer", "_bump_vao"):
            if isinstance(getattr(solver, name), Spy):
                setattr(solver, name, getattr(solver, name).target)
        field.release()


@pytest.mark.parametrize("dt", [5e-324, 1e308])
def test_gpu_solver_extreme_dt_stays_finite(gpu_solver_factory, dt):
    solver = gpu_solver_factory(32, H, S, damping_per_s=0.3, sleep_energy=0.0, max_substeps=20)
    solver.add_impulse(0.8, 0.7, 0.12, 1e-3)
    solver.step(1 / 60)
    solver.step(dt)
    solver.step(1 / 60)
    assert np.isfinite(solver.height).all() and math.isfinite(solver.energy())
