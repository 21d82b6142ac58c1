"""The ripples' per-frame shortcuts (issue 13) against the plain computations they replace."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.effects.ripples.scroll import RowWindow, shift_in_place, shift_line, shifted


@pytest.mark.parametrize("dtype", [np.float64, np.float32, bool])
def test_shift_in_place_equals_shifted(dtype, kernel_path):
    rng = np.random.default_rng(2)
    for dx, dz in [(0, 19), (0, -19), (3, 0), (-2, 5), (7, -11), (0, 0), (0, 40), (-40, 1), (1, 40)]:
        a = (rng.random((40, 33)) > 0.5).astype(dtype) if dtype is bool else rng.random((40, 33)).astype(dtype)
        fill = True if dtype is bool else np.nan
        want = shifted(a, dx, dz, fill)
        got = shift_in_place(a, dx, dz, fill)
        assert got is a
        np.testing.assert_array_equal(got, want)
    # A column or row view (the field's unknown-row and -column flags) shifts through to its base.
    flags = np.zeros(12, bool)
    flags[3] = True
    shift_in_place(flags[:, None], 0, 2, True)
    np.testing.assert_array_equal(flags, shifted(np.eye(1, 12, 3, dtype=bool).T, 0, 2, True)[:, 0])



@pytest.mark.parametrize("dtype", [np.int64, bool])
def test_shift_line_equals_shifted(dtype):
    """``shift_line`` (the field's flags of unknown rows and columns, its rows' water counts) is ``shifted`` of the
    line as a column, in place, for scrolls either way, none, and past its end."""
    rng = np.random.default_rng(3)
    for d in (19, -19, 1, -1, 0, 39, -39, 40, -41):
        a = rng.integers(0, 2 if dtype is bool else 100, 40).astype(dtype)
        fill = True if dtype is bool else 31
        want = shifted(a[:, None], 0, d, fill)[:, 0]
        assert shift_line(a, d, fill) is a
        np.testing.assert_array_equal(a, want)

@pytest.mark.parametrize("dtype", [np.float32, bool])
def test_row_window_scrolls_equal_shifted(dtype, kernel_path):
    """Scrolls that run out of spare rows both ways (the rows go back to the middle), jumps past the window and
    adopting a new array: always ``shifted`` of the previous values, and the rows outside never leak in."""
    rng = np.random.default_rng(5)
    a = (rng.random((40, 33)) > 0.5).astype(dtype) if dtype is bool else rng.random((40, 33)).astype(dtype)
    fill = True if dtype is bool else np.nan
    window = RowWindow(a, 7)
    want = a.copy()
    for dz in [3, 3, 3, 3, 5, -2, -9, -9, -9, 1, 39, 40, -41, 6, 6, 6, -13, 0]:
        want = shifted(want, 0, dz, fill)
        got = window.shift(dz, fill)
        assert got is window.view and got.flags.c_contiguous
        np.testing.assert_array_equal(got, want)
        if dz == -13:  # a new array adopted: scrolled from its values on
            want = (rng.random((40, 33)) > 0.5).astype(dtype) if dtype is bool else rng.random((40, 33)).astype(dtype)
            window.adopt(want)
            want = want.copy()


@pytest.mark.parametrize("rate", [0.5, 8.0, 60.0])
def test_drop_table_matches_the_exact_law(rate):
    """The momentum table (an index and a gather per drop) against the fall-speed law on the same quantiles:
    diameters exactly the inverse CDF's, momenta within 1e-3 each, the momentum flux within 1e-4."""
    import math

    from rain_core import physics
    from rain_core.effects.ripples.field import RippleField

    field = RippleField(n=16, extent_m=1.0, backend="numpy32", seed=0)
    u = (np.arange(1 << 18) + 0.5) / (1 << 18)  # stratified: a deterministic mean over the law
    d, p = field._flux_weighted_drops(rate, u.copy())
    _, grid, cdf, _ = field._drop_table(rate)[:4]
    d_exact = np.interp(u, cdf, grid)
    p_exact = physics.RHO_WATER * math.pi / 6.0 * (d_exact * 1e-3) ** 3 * np.asarray(physics.terminal_velocity(d_exact))
    np.testing.assert_array_equal(d, d_exact)
    np.testing.assert_allclose(p, p_exact, rtol=1e-3)
    assert p.mean() == pytest.approx(p_exact.mean(), rel=1e-4)
    assert np.all(p > 0.0) and np.all(np.diff(d) >= 0.0)


def _clip_loop(length, ax, az, bx, bz, pad):
    """The Liang–Barsky clip edge by edge (the form the field used before it took the four edges at once)."""
    lo, hi = -pad, length + pad
    t0, t1 = np.zeros_like(ax), np.ones_like(ax)
    inside = np.ones(ax.shape, bool)
    for p, q in ((-(bx - ax), ax - lo), (bx - ax, hi - ax), (-(bz - az), az - lo), (bz - az, hi - az)):
        flat = p == 0.0
        inside &= ~(flat & (q < 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(flat, 0.0, q / np.where(flat, 1.0, p))
        t0 = np.where(~flat & (p < 0.0), np.maximum(t0, r), t0)
        t1 = np.where(~flat & (p > 0.0), np.minimum(t1, r), t1)
    inside &= t0 <= t1
    dx, dz = bx - ax, bz - az
    return ax + t0 * dx, az + t0 * dz, ax + t1 * dx, az + t1 * dz, inside


def test_segment_clip_equals_the_edge_by_edge_clip():
    from rain_core.effects.ripples.field import RippleField
    from rain_core.effects.ripples.wakes import clip_segments

    field = RippleField(n=64, extent_m=6.3, backend="numpy32")
    rng = np.random.default_rng(5)
    ax, az, bx, bz = rng.uniform(-4.0, 10.0, (4, 500))
    bx[:60] = ax[:60]  # vertical, horizontal and degenerate segments, inside and outside
    bz[40:100] = az[40:100]
    pad = rng.uniform(0.0, 0.5, 500)
    got = clip_segments(ax, az, bx, bz, pad, field.solver.length_m)
    want = _clip_loop(field.solver.length_m, ax, az, bx, bz, pad)
    assert 50 < want[4].sum() < 450
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g[want[4]], w[want[4]])
    np.testing.assert_array_equal(got[4], want[4])


@pytest.mark.parametrize("masked", [False, True])
@pytest.mark.parametrize("choices", [(0.002, 0.02, 0.07, 0.12, 0.31), (0.002, 0.1, 0.15, 0.31)])
def test_float32_footprint_equals_the_reference(masked, choices):
    """The fast path's footprint (a 2·reach window, one flatnonzero) gives the reference's cells and values in
    the reference's order, so the float32 sums are the same: raindrops of 1.5 cells, wakes and wide bumps,
    centres on cell corners, near and beyond the fixed edges, and rims of a whole number of cells."""
    from rain_core.effects.ripples.solver import WaveSolver
    from rain_core.effects.ripples.solver_f32 import WaveSolverF32

    n, h = 64, 0.05
    ref, fast = WaveSolver(n, h, 0.35), WaveSolverF32(n, h, 0.35)
    if masked:
        mask = np.random.default_rng(3).random((n, n)) > 0.3
        ref.set_water_mask(mask)
        fast.set_water_mask(mask)
    rng = np.random.default_rng(9)
    k = 3000
    xs, zs = rng.uniform(-0.2, n * h + 0.1, k), rng.uniform(-0.2, n * h + 0.1, k)
    xs[:200] = np.round(xs[:200] / h) * h  # centres on cell centres: distances of whole cells
    zs[:200] = np.round(zs[:200] / h) * h
    radii = rng.choice(choices, k)  # the second set has rims of exactly 2 and 3 cells
    amounts = rng.uniform(-1e-3, 1e-3, k)
    flat_r, vals_r = ref._footprint(xs, zs, radii, amounts)
    flat_f, vals_f = fast._footprint(xs, zs, radii, amounts)
    np.testing.assert_array_equal(flat_f, flat_r)
    np.testing.assert_array_equal(vals_f, vals_r)


def _advance_2d(solver, k: int, alpha: float, kc2: float):
    """The float32 step on the 2-D interior views (the form the fast path had before it went flat)."""
    z, zp = solver._z, solver._zp
    a, kk = np.float32(alpha), np.float32(kc2)
    mask = None if solver._mask is None else solver._mask[1:-1, 1:-1]
    for _ in range(k):
        zi, pi = z[1:-1, 1:-1], zp[1:-1, 1:-1]
        np.subtract(zi, pi, out=pi)
        pi *= a
        pi += zi
        s = z[:-2, 1:-1] + z[2:, 1:-1]
        s += z[1:-1, :-2]
        s += z[1:-1, 2:]
        s -= zi * np.float32(4.0)
        s *= kk
        pi += s
        if mask is not None:
            pi *= mask
        z, zp = zp, z
    solver._z, solver._zp = z, zp


@pytest.mark.parametrize("masked", [False, True])
def test_float32_flat_stencil_equals_the_2d_one(masked):
    """The stencil over whole rows as one flat range gives the levels the 2-D interior form gives, edges 0,
    through scrolls, mask blocks, sources and sub-step changes."""
    from rain_core.effects.ripples.solver_f32 import WaveSolverF32

    n, h = 40, 0.05
    flat, plain = (WaveSolverF32(n, h, 0.35, 0.3, sleep_energy=0.0) for _ in range(2))
    plain._advance = lambda k, alpha, kc2: _advance_2d(plain, k, alpha, kc2)
    rng = np.random.default_rng(2)
    if masked:
        mask = np.zeros((n, n), bool)
        mask[:, 10:30] = rng.random((n, 20)) > 0.2
        for s in (flat, plain):
            s.set_water_mask(mask)
    for frame in range(30):
        xs, zs, amounts = rng.uniform(-0.1, 2.0, 6), rng.uniform(-0.1, 2.0, 6), rng.uniform(-1e-3, 1e-3, 6)
        block, dx = rng.random((3, 20)) > 0.4, int(rng.integers(-2, 3))
        for s in (flat, plain):
            if frame % 5 == 3:
                s.shift(dx, 2)
            if masked:
                s.set_water_mask_blocks([(n - 3, 12, block)])
            s.add_impulses(xs, zs, 0.08, amounts)
            s.step([1 / 30, 1 / 60, 1 / 45][frame % 3])
        np.testing.assert_array_equal(flat._z, plain._z)
        np.testing.assert_array_equal(flat._zp, plain._zp)
        assert not flat._z[:, [0, -1]].any() and not flat._z[[0, -1], :].any()


def test_wheel_batch_of_a_valid_batch_is_that_batch_and_bad_ones_still_name_the_field():
    """``WheelBatch.of`` hands a valid batch (the effect's, every frame) back as it is, after a few reductions;
    a bad one goes the long way and names what is wrong."""
    from rain_core.effects.ripples.wheels import WheelBatch

    p0 = np.zeros((4, 2))
    good = WheelBatch(p0, p0 + 0.5, np.full(4, 9.0), np.full(4, 0.2), np.array([np.nan, 1.0, 0.0, np.nan]))
    assert WheelBatch.of(good) is good
    assert WheelBatch.of(WheelBatch(p0, p0, np.full(4, 9.0), np.full(4, 0.2))).film_depth_mm is None
    nan_p0 = p0.copy()
    nan_p0[2, 1] = np.nan
    bad = {"p0_xz": dict(p0_xz=nan_p0), "speed_m_s": dict(speed_m_s=np.array([9.0, -1.0, 9.0, 9.0])),
           "tire_width_m": dict(tire_width_m=np.array([0.2, 0.2, 0.0, 0.2])),
           "film_depth_mm": dict(film_depth_mm=np.array([1.0, -2.0, 0.0, 1.0])),
           "one entry per wheel": dict(speed_m_s=np.full(3, 9.0))}
    fields = dict(p0_xz=p0, p1_xz=p0 + 0.5, speed_m_s=np.full(4, 9.0), tire_width_m=np.full(4, 0.2))
    for name, change in bad.items():
        with pytest.raises(ValueError, match=name):
            WheelBatch.of(WheelBatch(**{**fields, **change}))
    as_lists = WheelBatch.of(WheelBatch([[0, 0]], [[1, 1]], [9], [0.2]))  # not arrays: converted, checked
    assert as_lists.speed_m_s.dtype == np.float64 and as_lists.p0_xz.shape == (1, 2)



def test_wheel_batch_from_rows_is_checked_once_and_names_a_bad_field():
    """``WheelBatch.from_rows`` (the effect's batch every frame) checks its rows once: ``of`` then returns it as it
    is, with the same arrays as the batch built column by column; a bad row names its field, as ``of`` does."""
    from rain_core.effects.ripples.wheels import WheelBatch

    rows = [(0.0, 1.0, 0.5, 1.5, 9.0, 0.2), (-3.0, 2.0, -3.0, 2.5, 0.0, 0.3)]
    batch = WheelBatch.from_rows(rows)
    assert batch._checked and WheelBatch.of(batch) is batch and batch.film_depth_mm is None
    a = np.array(rows)
    plain = WheelBatch.of(WheelBatch(a[:, 0:2].copy(), a[:, 2:4].copy(), a[:, 4].copy(), a[:, 5].copy()))
    assert not plain._checked
    for name in ("p0_xz", "p1_xz", "speed_m_s", "tire_width_m"):
        assert getattr(batch, name).tobytes() == getattr(plain, name).tobytes()
    assert len(WheelBatch.from_rows([])) == 0
    bad = {"p0_xz": (0, np.nan), "p1_xz": (3, np.inf), "speed_m_s": (4, -1.0), "tire_width_m": (5, 0.0)}
    for name, (column, value) in bad.items():
        wrong = [list(r) for r in rows]
        wrong[1][column] = value
        with pytest.raises(ValueError, match=name):
            WheelBatch.from_rows(wrong)
    with pytest.raises(ValueError, match="W, 6"):
        WheelBatch.from_rows([(0.0, 1.0, 0.5)])

def test_wheel_rows_give_the_vehicles_own_bits():
    """``wheel_rows`` (Python floats) gives ``wheel_contacts``, ``previous_wheel_contacts``, |``wheel_speeds``| and
    ``wheel_widths`` bit for bit, turning, reversing and at rest, with and without previous contacts; the effect's
    batch of a frame is those rows for the vehicles near the window."""
    from types import SimpleNamespace

    from rain_core.effects.ripples import RipplesEffect
    from rain_core.effects.ripples.wheels import wheel_rows
    from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, Vehicle

    rng = np.random.default_rng(4)
    vehicles = []
    for i in range(60):
        v = Vehicle(TRUCK_SPEC if i % 3 == 0 else CAR_SPEC, position=np.array([rng.uniform(-8, 8), 0.0,
                    rng.uniform(-3e3, 3e3)]), yaw=rng.uniform(-7.0, 7.0), speed_m_s=rng.uniform(-9.0, 40.0))
        v.yaw_rate_rad_s = float(rng.uniform(-2.0, 2.0)) if i % 4 else 0.0
        if i % 5 == 0:
            v.speed_m_s = 0.0
        if i % 2:
            v.previous_wheel_contacts = v.wheel_contacts() + rng.uniform(-1.0, 1.0, (4, 3))
        else:
            v.previous_wheel_contacts = None
        vehicles.append(v)
    for v in vehicles:
        before = v.wheel_contacts() if v.previous_wheel_contacts is None else v.previous_wheel_contacts
        want = np.concatenate([before[:, (0, 2)], v.wheel_contacts()[:, (0, 2)], np.abs(v.wheel_speeds())[:, None],
                               v.wheel_widths()[:, None]], axis=1)
        assert np.array(wheel_rows(v)).tobytes() == want.tobytes()
    field = SimpleNamespace(origin_xz=(-4.0, -100.0), extent_m=200.0)
    batch = RipplesEffect(None).wheel_batch(SimpleNamespace(vehicles=vehicles), field)
    near = [v for v in vehicles if -24.0 < v.position[0] < 216.0 and -120.0 < v.position[2] < 120.0]
    rows = np.concatenate([batch.p0_xz, batch.p1_xz, batch.speed_m_s[:, None], batch.tire_width_m[:, None]], axis=1)
    assert 0 < len(near) < len(vehicles) and rows.tobytes() == np.array(sum(map(wheel_rows, near), [])).tobytes()
    assert batch.film_depth_mm is None
    assert len(RipplesEffect(None).wheel_batch(SimpleNamespace(vehicles=[]), field)) == 0


def _wakes_before(field, wheels):
    """The field's wakes as they were laid before the per-wheel values were gathered in one go (each array
    gathered alone, crests picked by a mask even when every wheel rolled): the bumps it would emit."""
    from rain_core.effects.ripples.constants import MIN_FOOTPRINT_CELLS, WAKE_REF_SPEED_M_S
    from rain_core.effects.ripples.wakes import clip_segments

    x0, z0, x1, z1, speed, depth_mm, width = wheels.T
    radius = np.minimum(0.5 * width, field.solver.max_radius_m)
    trough = field.wake_gain * depth_mm * 1e-3 * speed / WAKE_REF_SPEED_M_S
    ox, oz = field.origin_xz
    ax, az, bx, bz, inside = clip_segments(x0 - ox, z0 - oz, x1 - ox, z1 - oz, radius + 2.0 * field.cell_m,
                                           field.solver.length_m)
    live = inside & (trough != 0.0)
    ax, az, bx, bz, radius, trough = (v[live] for v in (ax, az, bx, bz, radius, trough))
    length = np.hypot(bx - ax, bz - az)
    count = np.maximum(1, np.ceil(length / field.cell_m)).astype(np.int64)
    spacing = np.where(length > 0.0, length / count, radius)
    peak = -trough * np.minimum(spacing / radius, 1.0)
    wheel = np.repeat(np.arange(count.size), count)
    t = (np.arange(wheel.size) - np.repeat(np.cumsum(count) - count, count) + 0.5) / count[wheel]
    xs, zs = ax[wheel] + t * (bx - ax)[wheel], az[wheel] + t * (bz - az)[wheel]
    reach = np.maximum(radius, MIN_FOOTPRINT_CELLS * field.cell_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        nx = np.where(length > 0.0, -(bz - az) / length, 0.0) * 2.0 * reach
        nz = np.where(length > 0.0, (bx - ax) / length, 0.0) * 2.0 * reach
    side = (length > 0.0)[wheel]
    sx, sz = nx[wheel][side], nz[wheel][side]
    crest = -0.5 * peak[wheel][side]
    r = radius[wheel]
    return (np.concatenate([xs, xs[side] + sx, xs[side] - sx]), np.concatenate([zs, zs[side] + sz, zs[side] - sz]),
            np.concatenate([r, r[side], r[side]]), np.concatenate([peak[wheel], crest, crest]))


@pytest.mark.parametrize("parked", [0, 3])
def test_wakes_gathered_at_once_equal_the_wheel_by_wheel_gathers(parked):
    """The wake bumps with the per-wheel values gathered in one go equal the old array-by-array form exactly,
    with every wheel rolling, with some parked (no crests), and with wheels outside the window or dry."""
    from rain_core.effects.ripples.field import RippleField

    field = RippleField(n=64, extent_m=6.3, backend="numpy32")
    rng = np.random.default_rng(4)
    w = 12
    p0 = rng.uniform(-3.6, 3.6, (w, 2))  # the window spans ±3.1 m: most inside, some beyond
    p1 = p0 + rng.uniform(-0.6, 0.6, (w, 2))
    p1[:parked] = p0[:parked]
    depth = rng.uniform(0.0, 3.0, w)
    depth[5] = 0.0  # a dry wheel lays nothing
    wheels = np.column_stack([p0, p1, rng.uniform(1.0, 30.0, w), depth, rng.uniform(0.15, 0.3, w)])
    emitted = []
    field._emit = lambda *bumps: emitted.append(bumps)
    counts = field._wakes(wheels)
    want = _wakes_before(field, wheels)
    assert len(emitted) == 1 and counts.sum() == len(want[0]) > 0 and (counts == 0).sum() >= 1
    for got, expected in zip(emitted[0], want, strict=True):
        np.testing.assert_array_equal(got, expected)


def test_gpu_solver_mask_row_window_equals_shifted(gl_ctx, shaders):
    """The GPU solver's CPU copy of the mask scrolls along z in a row window: through recentring both ways and a
    lateral scroll, it stays ``shifted`` of the mask (entering cells water) and equals the mask texture."""
    from rain_core.effects.ripples.gpu import WaveSolverGPU

    n = 40
    solver = WaveSolverGPU(gl_ctx, n, 0.05, 0.3, shaders=shaders)
    try:
        want = np.random.default_rng(6).random((n, n)) > 0.4
        solver.set_water_mask(want)
        first_window = None
        for dx, dz in [(0, 9), (0, 9), (0, 9), (0, 9), (3, 2), (0, -25), (0, -25), (0, 7), (0, 45), (0, 6)]:
            solver.shift(dx, dz)
            first_window = first_window or solver._mask_window
            want = shifted(want, dx, dz, True)
            np.testing.assert_array_equal(solver.water_mask, want)
            texels = np.frombuffer(solver.mask_texture.read(), np.uint8).reshape(n, n)
            np.testing.assert_array_equal(texels > 127, want)
        # One window all along (the lateral scroll moved its rows in place), and the mask is its view.
        assert solver._mask_window is first_window and solver._mask is first_window.view
    finally:
        solver.release()


@pytest.mark.parametrize("masked", [False, True])
def test_float32_solver_row_windows_equal_the_in_place_scroll(masked, kernel_path):
    """The float32 solver scrolls its mask and levels along z in row windows: through recentring both ways, the
    steps' swaps of the levels, lateral scrolls, a reset, a new mask and sleep, it keeps the values the in-place
    scroll (``WaveSolver.shift``) gives, bit for bit."""
    from rain_core.effects.ripples.solver import WaveSolver
    from rain_core.effects.ripples.solver_f32 import WaveSolverF32

    n = 48
    rng = np.random.default_rng(12)
    solvers = [WaveSolverF32(n, 0.05, 0.3, 0.5) for _ in range(2)]
    mask = rng.random((n, n)) > 0.3
    for s in solvers:
        if masked:
            s.set_water_mask(mask)
    moves = [(0, 9), (0, 11), (0, 13), (0, 9), (2, 3), (0, -25), (0, -20), (0, 7), (0, 60), (0, 6), (0, -4)] * 3
    for i, (dx, dz) in enumerate(moves):
        xs, zs = rng.uniform(0.2, 2.2, (2, 30))
        for s in solvers:
            s.add_impulses(xs, zs, 0.12, np.full(30, 1e-3))
            s.step(1 / 30)
        solvers[0].shift(dx, dz)
        WaveSolver.shift(solvers[1], dx, dz)  # the plain in-place scroll
        if i == 10:
            for s in solvers:
                s.reset()
        if i == 20 and masked:
            for s in solvers:
                s.set_water_mask(np.roll(mask, 5, axis=0))
        a, b = solvers
        assert a.height.tobytes() == b.height.tobytes() and a._zp.tobytes() == b._zp.tobytes()
        assert (a.water_mask is None) == (b.water_mask is None)
        if a.water_mask is not None:
            assert a.water_mask.tobytes() == b.water_mask.tobytes()
    windows = solvers[0]._row_windows
    assert windows[1] is not None and {id(solvers[0]._z), id(solvers[0]._zp)} == {id(windows[1].view),
                                                                                 id(windows[2].view)}
    # Asleep: the mask scrolls, the levels stay as they are (as the in-place scroll leaves them).
    for s in solvers:
        s._asleep = True
    solvers[0].shift(0, 5)
    WaveSolver.shift(solvers[1], 0, 5)
    assert solvers[0].height.tobytes() == solvers[1].height.tobytes()


def test_wheel_batch_rows_equal_the_columns_side_by_side():
    """``WheelBatch.rows`` (one array written column by column) is the batch's columns side by side, with the
    unknown depths asked (or given), NaN → 0 and clamped to [0, 1e3] mm, the known ones kept."""
    from rain_core.effects.ripples.wheels import WheelBatch

    rng = np.random.default_rng(9)
    p0, p1 = rng.uniform(-5, 5, (2, 6, 2))
    speed, width = rng.uniform(0, 30, 6), rng.uniform(0.1, 0.4, 6)
    asked_all = np.array([1.0, np.nan, -2.0, 2e3, 0.5, 3.0])
    film = lambda x, z: asked_all[:len(x)]  # noqa: E731
    for depth in (None, np.array([np.nan, 1.0, np.nan, 2.0, np.nan, np.nan]), np.array([1.0, 2, 3, 4, 5, 6])):
        batch = WheelBatch(p0, p1, speed, width, depth)
        want_depth = np.full(6, np.nan) if depth is None else depth.copy()
        unknown = np.isnan(want_depth)
        want_depth[unknown] = np.clip(np.nan_to_num(asked_all[:unknown.sum()], nan=0.0), 0.0, 1e3)
        want = np.concatenate([p0, p1, speed[:, None], want_depth[:, None], width[:, None]], axis=1)
        assert batch.rows(film).tobytes() == want.tobytes()
        assert batch.rows(None, asked_all[:unknown.sum()]).tobytes() == want.tobytes()


def test_window_centre_uses_the_cameras_own_forward_axis():
    """The effect's window centre takes the camera's normalised forward alone: the same centre as with
    ``basis()[2]``, for unnormalised, tilted, backward and degenerate forward vectors."""
    from types import SimpleNamespace

    from rain_core.camera import Camera
    from rain_core.effects.ripples import RipplesEffect, window_centre_xz
    from rain_core.vehicles import Vehicle

    rng = np.random.default_rng(3)
    field = SimpleNamespace(extent_m=25.0, recenter_margin_cells=4, cell_m=25.0 / 511)
    for i in range(200):
        ego = Vehicle(position=np.array([rng.uniform(-5, 5), 0.0, rng.uniform(-1e3, 1e3)]), yaw=rng.uniform(-4, 4))
        forward = rng.normal(size=3) * rng.uniform(0.1, 30.0) if i % 7 else np.zeros(3)
        camera = Camera(position=ego.position + rng.normal(size=3) * 5.0, forward=forward, up=rng.normal(size=3))
        heading = ego.forward()
        want = window_centre_xz((ego.position[0], ego.position[2]), (heading[0], heading[2]), field.extent_m,
                                camera.position, camera.basis()[2], car_half_length_m=0.5 * float(ego.spec.length_m),
                                margin_m=field.recenter_margin_cells * field.cell_m)
        assert RipplesEffect.window_centre(SimpleNamespace(ego=ego, camera=camera), field) == want
