"""The ripples' compiled kernels (rain_core.effects.ripples.kernels) against their NumPy twins: the float32
stencil and the raindrops exactly (the same float32 / integer operations), the footprints' deposits and whole
field replays to a stated tolerance (libm's cos against NumPy's may differ by an ulp in float64, which float32
rounding almost always absorbs)."""

from __future__ import annotations

import functools
import math
import operator

import numpy as np
import pytest

from rain_core import jit, physics
from rain_core.effects.ripples import field as field_module
from rain_core.effects.ripples import kernels
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.raindrops import raindrops
from rain_core.effects.ripples.solver_f32 import WaveSolverF32

needs_numba = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")

# Kernel-vs-twin tolerance of float32 heights, relative to the largest |height|: a cos an ulp apart (float64)
# moves a deposit by at most an ulp of float32, and the stencil carries it on linearly.
REPLAY_RTOL = 1e-5


@needs_numba
@pytest.mark.parametrize("masked", [False, True])
def test_leapfrog_kernel_gives_the_twins_levels_exactly(masked):
    """Sub-steps fused in one loop: the twin's float32 levels bit for bit, edges 0, through scrolls, mask blocks,
    sources and sub-step changes (odd and even sub-step counts, so both swaps)."""
    n, h = 48, 0.05

    def run():
        solver = WaveSolverF32(n, h, 0.35, 0.3, sleep_energy=0.0)
        rng = np.random.default_rng(2)
        solver.reset(rng.standard_normal((n, n)) * 1e-3)
        if masked:
            mask = np.zeros((n, n), bool)
            mask[:, 8:40] = rng.random((n, 32)) > 0.2
            solver.set_water_mask(mask)
        levels = []
        for frame in range(40):
            if frame % 5 == 3:
                solver.shift(int(rng.integers(-2, 3)), 2)
            if masked:
                solver.set_water_mask_blocks([(n - 3, 12, rng.random((3, 20)) > 0.4)])
            with jit.forced(False):  # the sources by the twin on both sides: this test is the stencil's
                solver.add_impulses(rng.uniform(0.0, 2.3, 4), rng.uniform(0.0, 2.3, 4), 0.08,
                                    rng.uniform(-1e-3, 1e-3, 4))
            solver.step([1 / 30, 1 / 60, 1 / 45, 1 / 200][frame % 4])
            levels.append((solver._z.copy(), solver._zp.copy()))
        return levels

    twin, kernel = jit.twin_and_kernel(run)
    for (z0, p0), (z1, p1) in zip(twin, kernel, strict=True):
        np.testing.assert_array_equal(z1, z0)
        np.testing.assert_array_equal(p1, p0)
        assert not z1[:, [0, -1]].any() and not z1[[0, -1], :].any()
    assert np.abs(twin[-1][0]).max() > 1e-5  # a real test: the water moves


@needs_numba
@pytest.mark.parametrize("masked", [False, True])
def test_deposit_kernel_equals_the_twins_footprints(masked):
    """Raindrops of 1.5 cells, wakes, wide bumps and one wider than a footprint batch (clipped to the grid),
    centres on cell centres, near and beyond the fixed edges, zero peaks: the twin's sums to an ulp, and the
    solver wakes exactly when the twin's footprint is not empty."""
    n, h = 64, 0.05
    rng = np.random.default_rng(9)
    k = 3000
    xs, zs = rng.uniform(-0.2, n * h + 0.1, k), rng.uniform(-0.2, n * h + 0.1, k)
    xs[:200] = np.round(xs[:200] / h) * h
    zs[:200] = np.round(zs[:200] / h) * h
    radii = rng.choice((0.002, 0.02, 0.07, 0.1, 0.15, 0.31), k)
    radii[7] = (n - 1) * h  # a bump as wide as the field
    amounts = rng.uniform(-1e-3, 1e-3, k)
    amounts[::97] = 0.0
    mask = rng.random((n, n)) > 0.3

    def run():
        solver = WaveSolverF32(n, h, 0.35, sleep_energy=0.0)
        if masked:
            solver.set_water_mask(mask)
        solver.add_impulses(xs, zs, radii, amounts)
        return solver._z.copy(), solver._zp.copy(), solver.asleep, solver._sourced

    twin, kernel = jit.twin_and_kernel(run)
    scale = np.abs(twin[0]).max()
    assert scale > 0.0
    np.testing.assert_allclose(kernel[0], twin[0], rtol=0.0, atol=REPLAY_RTOL * scale)
    np.testing.assert_allclose(kernel[1], twin[1], rtol=0.0, atol=REPLAY_RTOL * scale)
    assert kernel[2:] == twin[2:]
    if masked:
        assert not kernel[0][~mask].any()


@needs_numba
def test_deposit_kernel_clips_a_bump_wider_than_a_batch():
    """A bump whose square window exceeds FOOTPRINT_BATCH_CELLS (the twin's clipped path, a band of rows at a
    time) and bumps entirely off the grid: the twin's levels."""
    n, h = 600, 0.05

    def run():
        solver = WaveSolverF32(n, h, 0.35, sleep_energy=0.0)
        solver.add_impulses([10.0, -40.0, 15.0], [12.0, 5.0, 15.0], [solver.max_radius_m, 1.0, 0.3],
                            [1e-3, 1e-3, -2e-3])
        return solver._z.copy()

    twin, kernel = jit.twin_and_kernel(run)
    assert np.count_nonzero(twin) > 200_000
    np.testing.assert_allclose(kernel, twin, rtol=0.0, atol=REPLAY_RTOL * np.abs(twin).max())


@needs_numba
def test_deposit_kernel_of_bumps_that_miss_the_grid_leaves_the_solver_asleep():
    solver = WaveSolverF32(32, 0.05, 0.35)
    solver._asleep = True
    with jit.forced(True):
        solver.add_impulses([-5.0, 0.5], [0.5, 0.5], 0.1, [1e-3, 0.0])
    assert solver.asleep and not solver.height.any()


@needs_numba
@pytest.mark.parametrize("n", [64, 513])
@pytest.mark.parametrize("rate", [2.0, 40.0])
@pytest.mark.parametrize("masked", [False, True])
def test_raindrop_kernel_gives_the_twins_drops_exactly(n, rate, masked):
    """The drops on water, their centres, crater radii and dents: the twin's, bit for bit (integer hashes, the
    inverse CDF as np.interp computes it, the momentum table)."""
    field = RippleField(n=n, extent_m=0.05 * (n - 1), seed=3, max_drops_per_frame=50_000)
    if masked:
        field.set_water_mask(np.random.default_rng(n).random((n, n)) > 0.6)
    water = field.solver.water_mask
    for _ in range(3):
        batch = field.rain_batch(rate, 1 / 30)
        law = batch.law
        _, *want = raindrops(batch, n, field.cell_m, water)
        out = np.full((4, batch.count + 5), np.nan)
        count = kernels.raindrop_bumps(batch.key, batch.count, n, field.cell_m,
                                       np.ones((1, 1), np.float32) if water is None else water, water is not None,
                                       law.cdf, law.grid, law.p_d, law.dp_d, physics.D_MIN_MM, physics.D_MAX_MM,
                                       batch.crater_m_per_mm, batch.peak_per_momentum, out,
                                       np.empty(batch.count, bool))
        got = out[:, :count]
        assert np.isnan(out[:, count:]).all()
        assert want[0].size > 10
        for g, w in zip(got, want, strict=True):
            np.testing.assert_array_equal(g, w)


def test_raindrop_kernel_inverse_cdf_at_the_nodes_and_ends():
    """np.interp's inverse CDF in the kernel's own search, on a small table with flat stretches (repeated nodes),
    through the plain-Python function (so it runs where Numba is missing too)."""
    cdf = np.array([0.0, 0.0, 0.25, 0.25, 0.5, 1.0])
    grid = np.array([0.1, 0.2, 0.5, 0.9, 1.5, 6.0])
    p_d = np.linspace(0.0, 1.0, 9)
    dp_d = np.diff(p_d)
    fn = getattr(kernels.raindrop_bumps, "py_func", kernels.raindrop_bumps)
    out = np.empty((4, 40))
    assert fn(7, 40, 8, 0.1, np.ones((1, 1), np.float32), False, cdf, grid, p_d, dp_d, 0.1, 6.0, 1.0, 1.0, out,
              np.empty(40, bool)) == 40
    radii = out[2]
    from rain_core.effects.ripples.raindrops import _unit, pcg

    u = _unit(pcg(np.arange(40, dtype=np.uint32) ^ np.uint32(7)))
    np.testing.assert_array_equal(radii, np.interp(u, cdf, grid))  # crater 1 m per mm: the diameters


def test_quantile_buckets_bracket_the_inverse_cdfs_node():
    """The raindrops' search starts from a bucket of the quantile's top bits: the node np.interp takes (the last
    with cdf ≤ u) lies in the bucket's bracket, for a steep law and for flat stretches; a CDF that decreases
    somewhere gets the whole range (the full search)."""
    fn = getattr(kernels._quantile_buckets, "py_func", kernels._quantile_buckets)
    buckets = 1 << kernels.QUANTILE_BUCKET_BITS
    steep = np.concatenate([[0.0], np.cumsum(np.geomspace(1.0, 1e-6, 512))])
    for cdf in (steep / steep[-1], np.array([0.0, 0.0, 0.25, 0.25, 0.5, 1.0])):
        first = np.empty(buckets + 1, np.int64)
        fn(cdf, first)
        k = np.random.default_rng(5).integers(0, 1 << 24, 20_000)
        u = k / float(1 << 24)
        node = np.searchsorted(cdf, u, side="right") - 1
        j = k >> (24 - kernels.QUANTILE_BUCKET_BITS)
        assert ((first[j] <= node) & (node <= first[j + 1])).all()
    first = np.empty(buckets + 1, np.int64)
    fn(np.array([0.0, 0.5, 0.4, 1.0]), first)
    assert (first[:-1] == 0).all() and first[-1] == 3


def _replay(backend_frames: int, seed: int = 4):
    """A 70-frame drive over a film with puddles: rain (capped drops), two wheels' wakes, spray impacts,
    scrolls in both directions. Returns the heights after each frame and the reports."""
    n, extent = 160, 7.95

    def film(x, z):
        x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
        return np.maximum(0.0, np.sin(1.1 * x) + np.cos(0.8 * z + 0.3 * x) - 0.2)

    field = RippleField(n=n, extent_m=extent, backend="numpy32", seed=seed, max_drops_per_frame=1500)
    field.solver.sleep_energy = 0.0
    heights, reports = [], []
    for frame in range(backend_frames):
        x = 0.05 * frame
        wheels = [((x - 1.0, 0.4 + 0.2 * frame), (x - 0.7, 0.6 + 0.2 * frame), 8.0, None, 0.2),
                  ((x + 1.0, 0.4 + 0.2 * frame), (x + 1.3, 0.6 + 0.2 * frame), 8.0, 2.0, 0.22)]
        impacts = np.array([[x + 0.3, 0.2 * frame + 1.0, 2e-5], [x - 0.5, 0.2 * frame - 2.0, 5e-6]])
        report = field.update([1 / 30, 1 / 33, 1 / 27][frame % 3], center_xz=(x, 0.2 * frame), rate_mm_h=25.0,
                              wheels=wheels, film_depth_fn=film, impacts=impacts)
        heights.append(field.height.copy())
        reports.append(report)
    return heights, reports


@needs_numba
def test_field_replay_kernels_against_the_twin():
    """70 frames of the float32 field with every CPU kernel on against the NumPy twins: the same drops, bumps and
    sub-steps each frame, heights within REPLAY_RTOL of the largest (exactly equal where libm's cos agrees
    with NumPy's, as it does on most machines)."""
    (h0, r0), (h1, r1) = jit.twin_and_kernel(lambda: _replay(70))
    assert r0 == r1
    scale = max(np.abs(h).max() for h in h0)
    assert scale > 0.0 and sum(r["drops"] for r in r0) > 1000
    for a, b in zip(h0, h1, strict=True):
        np.testing.assert_allclose(b, a, rtol=0.0, atol=REPLAY_RTOL * scale)


@needs_numba
def test_bumps_wider_than_the_span_take_the_twin():
    """Radii beyond the field's span are outside ``add_impulses_unchecked``'s contract; the kernel declines them
    (its reach histogram holds n + 3 levels) and the twin lays them, as without the kernels."""
    n, h = 40, 0.05

    def run():
        solver = WaveSolverF32(n, h, 0.35, sleep_energy=0.0)
        solver.add_impulses_unchecked(np.array([1.0, 0.5]), np.array([1.0, 0.7]), np.array([6.0, 0.1]),
                                      np.array([1e-3, -1e-3]))
        return solver._z.copy()

    twin, kernel = jit.twin_and_kernel(run)
    assert twin.any()
    np.testing.assert_array_equal(kernel, twin)


@needs_numba
def test_wake_kernel_gives_the_twins_bumps():
    """Wheels rolling, parked, crossing the window's edges, beyond it, in no water and faster than a cell a
    frame: the twin's bumps (troughs, then each side's crests) and counts, bit for bit (np.hypot and libm's
    hypot agree here; the arithmetic is the twin's)."""
    rng = np.random.default_rng(5)
    w = 60
    p0 = rng.uniform(-1.0, 7.0, (w, 2))  # the window spans about 0.6 … 5.4 m each way
    p1 = p0 + rng.uniform(-1.5, 1.5, (w, 2))
    p1[::7] = p0[::7]  # parked
    speed = rng.uniform(0.0, 30.0, w)
    depth = rng.uniform(0.0, 5.0, w)
    depth[::9] = 0.0  # no water: no trough
    width = rng.uniform(0.12, 0.4, w)
    wheels = np.column_stack([p0, p1, speed, depth, width])

    def run():
        field = RippleField(n=96, extent_m=4.75, seed=1)
        field.recenter(3.0, 2.0)
        field._batch = []
        counts = field._wakes(wheels)
        return counts, [np.concatenate(parts) for parts in zip(*field._batch, strict=True)]

    (c0, b0), (c1, b1) = jit.twin_and_kernel(run)
    np.testing.assert_array_equal(c1, c0)
    assert (c0 == 0).any() and (c0 == 1).any() and ((c0 > 0) & (c0 % 3 == 0)).sum() > 10  # a real test
    for g, want in zip(b1, b0, strict=True):
        np.testing.assert_array_equal(g, want)


class _FloatMaskSolver(WaveSolverF32):
    """The float32 solver with the 0/1 float32 mask it kept before its mask became bytes."""

    mask_dtype = np.float32


def test_the_byte_mask_steps_as_the_float_mask_did(kernel_path, monkeypatch):
    """The float32 solver keeps its water mask as bytes (a quarter of what the stencil, the scroll and the
    raindrops read): the same drops, bumps and levels bit for bit as with a 0/1 float32 mask, through scrolls,
    the mask's strips and bands, rain, wakes and spray."""
    assert WaveSolverF32(8, 0.05, 0.35).mask_dtype is np.bool_
    byte = _replay(40)
    monkeypatch.setitem(field_module.CPU_SOLVERS, "numpy32", _FloatMaskSolver)
    floats = _replay(40)
    assert byte[1] == floats[1] and sum(r["drops"] for r in byte[1]) > 500
    for a, b in zip(byte[0], floats[0], strict=True):
        np.testing.assert_array_equal(a, b)
    assert np.abs(byte[0][-1]).max() > 0.0


@needs_numba
def test_deposit_kernel_with_its_cache_hints_equals_its_plain_python_self():
    """The deposit fetches the cells of bumps ahead (cache_hints.prefetch, a no-op in Python): the compiled
    kernel adds the same float32 values bit for bit as its own Python function, with the mask and without, bumps
    near the edges and of several reaches included."""
    from rain_core.effects.ripples.cache_hints import prefetch
    from rain_core.effects.ripples.constants import FOOTPRINT_BATCH_CELLS, MIN_FOOTPRINT_CELLS

    assert prefetch(np.zeros(3), 1) is None
    n, h = 40, 0.05
    rng = np.random.default_rng(11)
    k = 300
    xs, zs = rng.uniform(-0.1, n * h, k), rng.uniform(-0.1, n * h, k)
    radii = rng.choice((0.01, 0.07, 0.12, 0.3), k)
    amounts = rng.uniform(-1e-3, 1e-3, k)
    start = rng.standard_normal((2, n, n)).astype(np.float32) * np.float32(1e-3)
    for mask, use_mask in ((np.ones((1, 1), bool), False), (rng.random((n, n)) > 0.3, True)):
        levels = []
        for fn in (kernels.deposit_bumps, kernels.deposit_bumps.py_func):
            z, zp = start[0].copy(), start[1].copy()
            cells = fn(z, zp, mask, use_mask, xs, zs, radii, amounts, h, MIN_FOOTPRINT_CELLS * h, (n - 1) * h,
                       FOOTPRINT_BATCH_CELLS, np.empty((2, k)), np.empty((2, k), np.int64),
                       np.empty(n + 3, np.int64))
            levels.append((cells, z, zp))
        (c0, z0, p0), (c1, z1, p1) = levels
        assert c0 == c1 > 1000
        np.testing.assert_array_equal(z0, z1)
        np.testing.assert_array_equal(p0, p1)


def _libm_deposit(z, zp, mask, use_mask, xs, zs, radii, amounts, h, min_radius_m, length_m) -> int:
    """The deposit cell by cell with libm's cos for every value (the kernel before its estimates): bumps by
    reach, stably; each bump's cells row by row; the same pre-test, rim test, float64 values and float32 adds."""
    r_eff = np.maximum(radii, min_radius_m)
    peaks = amounts * (radii / r_eff) ** 2
    keep = (xs > -r_eff) & (xs < length_m + r_eff) & (zs > -r_eff) & (zs < length_m + r_eff) & (peaks != 0.0)
    reach = np.where(keep, np.ceil(r_eff / h), -1).astype(np.int64)
    n, count = z.shape[0], 0
    for b in np.argsort(reach, kind="stable")[np.count_nonzero(~keep):]:
        x, y, r, a, w = float(xs[b]), float(zs[b]), float(r_eff[b]), float(peaks[b]), int(reach[b])
        c0, r0 = math.floor(x / h), math.floor(y / h)
        near = r * r * (1.0 + 1e-9)
        for row in range(max(1, r0 - w), min(n - 2, r0 + w) + 1):
            dz = row * h - y
            for col in range(max(1, c0 - w), min(n - 2, c0 + w) + 1):
                dx = col * h - x
                d2 = dx * dx + dz * dz
                if d2 > near or not math.sqrt(d2) / r < 1.0:
                    continue
                v = 0.5 * (1.0 + math.cos(math.pi * (math.sqrt(d2) / r))) * a
                if v != 0.0:
                    count += 1
                    f = np.float32(v * float(mask[row, col]) if use_mask else v)
                    z[row, col] += f
                    zp[row, col] += f
    return count


@needs_numba
@pytest.mark.parametrize("mask_kind", ["none", "bool", "fractions"])
def test_deposit_kernels_estimates_add_libms_values_exactly(mask_kind):
    """The deposit estimates its values with a polynomial cosine and takes libm's cos only where the float32
    could differ: the same bits (signed zeros included) and the same count as libm's cos everywhere, for peaks
    from 1e-30 to 100 m of both signs, cells on the rim (d / r within 1e-13 of 1, where libm decides) and a
    mask of bytes or of float32 fractions."""
    from rain_core.effects.ripples.constants import FOOTPRINT_BATCH_CELLS, MIN_FOOTPRINT_CELLS

    n, h = 48, 0.05
    rng = np.random.default_rng(13)
    k = 600
    xs, zs = rng.uniform(-0.1, n * h, k), rng.uniform(-0.1, n * h, k)
    radii = rng.choice((0.001, 0.07, 0.09, 0.12, 0.2), k)
    amounts = rng.choice((-1.0, 1.0), k) * 10.0 ** rng.uniform(-30.0, 2.0, k)
    # Rims through a cell's centre: cell (12, 20) at d / r = 1 − 1e-13, 1 − 1e-9, 1 and 1 + 1e-13.
    x0, z0 = 10.3 * h, 20 * h
    dx = 12 * h - x0
    rim = dx / np.array([1.0 - 1e-13, 1.0 - 1e-9, 1.0, 1.0 + 1e-13])
    xs, zs = np.concatenate([xs, np.full(4, x0)]), np.concatenate([zs, np.full(4, z0)])
    radii, amounts = np.concatenate([radii, rim]), np.concatenate([amounts, [1e-3, -1e-3, 1e-3, 1e-3]])
    estimate = 0.5 * (1.0 + kernels._cos_pi(dx / rim[0])) * 1e-3
    assert abs(estimate) <= 1e-3 * kernels.PROFILE_ERROR  # the first rim bump's cell is libm's to decide
    mask = {"none": np.ones((1, 1), bool), "bool": rng.random((n, n)) > 0.3,
            "fractions": rng.choice((0.0, 1.0, 0.3, 0.77), (n, n)).astype(np.float32)}[mask_kind]
    use_mask = mask_kind != "none"
    start = rng.standard_normal((2, n, n)).astype(np.float32) * np.float32(1e-3)
    start[:, rng.random((n, n)) > 0.5] = np.float32(-0.0)
    args = (xs, zs, radii, amounts, h, MIN_FOOTPRINT_CELLS * h, (n - 1) * h)
    z, zp = start[0].copy(), start[1].copy()
    cells = kernels.deposit_bumps(z, zp, mask, use_mask, *args, FOOTPRINT_BATCH_CELLS, np.empty((2, k + 4)),
                                  np.empty((2, k + 4), np.int64), np.empty(n + 3, np.int64))
    want_z, want_zp = start[0].copy(), start[1].copy()
    assert cells == _libm_deposit(want_z, want_zp, mask, use_mask, *args) > 5000
    np.testing.assert_array_equal(z.view(np.uint32), want_z.view(np.uint32))
    np.testing.assert_array_equal(zp.view(np.uint32), want_zp.view(np.uint32))


def test_polynomial_cosine_stays_within_its_bound_of_libms():
    """PROFILE_ERROR rests on _cos_pi lying within 4e-16 of libm's cos over [0, 1] (a 30-fold margin)."""
    fn = getattr(kernels._cos_pi, "py_func", kernels._cos_pi)
    rel = np.concatenate([np.linspace(0.0, 1.0, 20_001), 0.5 + np.linspace(-1e-6, 1e-6, 101),
                          1.0 - np.geomspace(1e-16, 1e-3, 200)])
    worst = max(abs(fn(float(u)) - math.cos(math.pi * float(u))) for u in rel)
    assert worst < 4e-16
    assert worst * 30 < kernels.PROFILE_ERROR


def test_prefetch_changes_no_value(kernel_path):
    """A compiled loop with the hint on every element sums what the plain loop sums (and the hint is a no-op in
    Python)."""
    from rain_core.effects.ripples.cache_hints import prefetch

    def total(a):
        s = 0.0
        for i in range(a.size):
            prefetch(a, min(i + 8, a.size - 1))
            s += a[i]
        return s

    if jit.active():
        import numba

        run = numba.njit(total)
    else:
        run = total
    a = np.random.default_rng(1).random(1000)
    # Left to right, as the loops add: Python 3.12's sum() of floats compensates its rounding (Neumaier).
    assert run(a) == total(a) == functools.reduce(operator.add, a.tolist(), 0.0)
