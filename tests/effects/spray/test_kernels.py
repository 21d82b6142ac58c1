"""The spray's compiled kernels (rain_core/effects/spray/kernels.py) against their NumPy twins: each kernel on its
own, and the emitter driven through 150 frames of a real scene on both paths.

Tolerances: the kernels do the twins' operations in the same order, so most outputs are equal; what may differ
is libm's exp/expm1/log (float64 and float32) against NumPy's own, by an ulp, and Newton's stopping test (per
parcel instead of over all parcels: a converged landing time moves by ≪ 1e-7 s). A float32 record may then
differ in its last bit (rtol 2e-7), a float64 landing time by 1e-7 s."""

import numpy as np
import pytest

from rain_core import jit, layout, physics
from rain_core.effects.spray import body, flight, kernels, launch, parcels, spawn
from rain_core.effects.spray.emitter import SprayEmitter
from tests.effects.spray.test_fast_path import _body_case, _drive, _fleet, _puddle

pytestmark = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed")


def _flight_case(n=4000, nd=3000, seed=8):
    rng = np.random.default_rng(seed)
    p0 = np.column_stack([rng.uniform(-9.0, 9.0, n), rng.uniform(0.0, 1.5, n), rng.uniform(0.0, 50.0, n)])
    v0 = np.column_stack([rng.uniform(-20.0, 20.0, n), rng.uniform(-10.0, 12.0, n), rng.uniform(-30.0, 30.0, n)])
    d_mm = np.concatenate([rng.uniform(0.1, 5.0, nd), np.full(n - nd, 0.05)])
    air = np.column_stack([rng.uniform(-9.0, 9.0, n), np.zeros(n), rng.uniform(-9.0, 9.0, n)])
    air[nd:] = 0.0
    updraught = np.where(np.arange(n) < nd, rng.uniform(0.0, 0.6, n), 0.0)
    return p0, v0, d_mm, air, updraught, nd, np.array([1.5, 0.2, -2.0])


def test_fly_equals_the_twins_chain():
    """Terminal velocity, carrier air, τ and the landing age of every parcel: the twin's values (u, speed and τ
    to an ulp of log/sqrt, the landing age within 1e-7 s)."""
    p0, v0, d_mm, air, updraught, nd, wind = _flight_case()
    n = len(p0)
    vt = np.empty(n)
    vt[:nd] = spawn._terminal_velocity(d_mm[:nd])
    vt[nd:] = spawn._MIST_VT_M_S
    u_ref, speed_ref, tau_ref = launch.carrier_air_and_tau(wind, air.copy(), updraught, v0, d_mm, vt, nd)
    ground_ref = flight.ground_time(p0, v0, u_ref, tau_ref)
    u, speed, tau, ground = np.empty((n, 3)), np.empty(n), np.empty(n), np.empty(n)
    kernels.fly(p0, v0, d_mm, air, updraught, nd, wind, spawn._MIST_VT_M_S, launch.WAKE_TAU_S, spawn._GK_X,
                spawn._GK_X0, spawn._GK_H, spawn._GK_Y0, spawn._GK_Y1, spawn._GK_D0, spawn._GK_D1, physics.G_M_S2,
                flight.DRAG_TAIL_FIT, layout.KERB_HEIGHT_M, layout.ROAD_HALF_WIDTH_M, 1e-9, 40, u, speed, tau, ground)
    assert np.array_equal(u, u_ref) and np.array_equal(speed, speed_ref)
    assert np.allclose(tau, tau_ref, rtol=1e-15, atol=0.0)
    assert np.abs(ground - ground_ref).max() < 1e-7
    assert (ground > 0).mean() > 0.5 and (np.abs(ground - ground_ref) > 0).mean() < 0.5  # a real test: mostly equal


def test_body_hit_equals_the_twin():
    """The kernel finds the twin's age (the same float32 search; an ulp of float32 exp may move a coarse or zoomed
    sample across the body's face, so a few ages differ, by at most one zoom step)."""
    args, box = _body_case(n=3000)
    p0, v0, u, tau, t_max, origin, vel, right, forward = args
    n = len(tau)
    box_params = np.tile(np.array(list(vars(box).values())), (n, 1))
    ref = body.body_hit_time_fast(*args, box_params)
    age = np.random.default_rng(1).random(n) / 30.0
    # The kernel reads the vehicle's table and moves its origin back by each drop's age: give it origins that
    # come back to ``origin``.
    table = np.column_stack([origin[:1] + vel[:1] * 0.0, vel[:1], right[:1], forward[:1], box_params[:1]])
    table = np.ascontiguousarray(np.repeat(table, n, axis=0))
    table[:, 0:3] = origin + vel * age[:, None]
    out = np.full(n, -1.0)
    kernels.body_hit(p0, v0, u, tau, t_max, table, np.arange(n, dtype=np.int64), age, n, body.SAMPLES, body.ZOOM,
                     body.ROUNDS, out)
    ref2 = body.body_hit_time_fast(p0, v0, u, tau, t_max, table[:, 0:3] - vel * age[:, None], vel, right, forward,
                                   box_params)
    hit = ref2 < t_max
    assert 0.1 < hit.mean() < 0.9
    assert np.mean(out == ref2) > 0.995
    assert np.array_equal(out < t_max, hit) or np.mean((out < t_max) != hit) < 0.002
    assert np.abs(out - ref2).max() <= np.max(t_max) / body.SAMPLES / body.ZOOM + 1e-6
    assert np.abs(ref2 - ref).max() < 1e-6  # the moved origin is the same origin (to rounding)


def test_kernel_emitter_writes_the_twins_parcels():
    """150 frames of four vehicles (turning, reversing, a lorry) in wind on a 4 mm puddle, twice: the compiled path
    writes the twin's parcels (float32 records to an ulp), spawns the same counts, books the same fates and lands
    the same drops in the water."""
    runs = []
    for compiled in (False, True):
        with jit.forced(compiled):
            em = SprayEmitter(seed=7, budget=3000, film_depth_fn=_puddle(4.0))
            _, landed = _drive(em, _fleet(), 150)
            runs.append((em, np.concatenate(landed)))
    (twin, twin_landed), (comp, comp_landed) = runs
    assert comp.stats.parcels == twin.stats.parcels > 10_000 and comp.stats.mist_puffs == twin.stats.mist_puffs > 0
    assert np.allclose(comp.stats.fates, twin.stats.fates, rtol=1e-12)
    for name in ("emitted_kg", "thrown_kg", "available_kg", "parcels", "mist_puffs"):
        assert getattr(comp.stats, name) == getattr(twin.stats, name), name
    for comp_book, twin_book in ((comp._acc, twin._acc), (comp.stats.wheel_thrown_kg, twin.stats.wheel_thrown_kg),
                                 (comp.stats.wheel_emitted_kg, twin.stats.wheel_emitted_kg)):
        assert len(comp_book) == len(twin_book) == 4
        for a, b in zip(comp_book.values(), twin_book.values(), strict=True):
            assert np.array_equal(a, b)
    for rc, rt in zip(comp.rings, twin.rings, strict=True):
        assert rc.head == rt.head
        assert np.array_equal(rc.birth, rt.birth)
        for name in parcels.PARTICLE_DTYPE.names:
            assert np.allclose(rc.data[name], rt.data[name], rtol=2e-7, atol=0.0), name
        assert np.allclose(rc.death, rt.death, rtol=0.0, atol=1e-6)
    assert len(comp_landed) == len(twin_landed) > 1000
    assert np.allclose(comp_landed, twin_landed, rtol=1e-9, atol=1e-7)
    for name in ("_candidates", "_pending"):  # the landings still in flight, and still to be looked up
        a, b = getattr(comp, name), getattr(twin, name)
        assert a.shape == b.shape and np.allclose(a, b, rtol=1e-9, atol=1e-7), name
    assert np.allclose(comp._life_q90, twin._life_q90, rtol=1e-9, atol=0.0)
    assert comp.rng.random() == twin.rng.random()  # the same draws, in the same order


def test_launches_equal_the_twins_and_draw_the_same_numbers():
    """Droplets of every bucket and mist puffs from four vehicles' wheels: the compiled launches give the twins'
    values (to an ulp of exp, sin, cos and pow: rtol 1e-13) and leave the generator where the twins leave it."""
    from rain_core.effects.spray import wheels

    fleet = _fleet()
    _, geo = wheels.gather_wheels(fleet, _puddle(6.0), build_wheels=False)
    rng = np.random.default_rng(4)
    counts = np.array([700, 500, 300, 200, 150])
    nd, nm = int(counts.sum()), 120
    n = nd + nm
    bounds = np.zeros(7, dtype=np.int64)
    np.cumsum(np.append(counts, nm), out=bounds[1:])
    w = np.concatenate([rng.integers(0, 4 * len(fleet), nd), rng.integers(0, 4 * len(fleet), nm)])
    age = rng.random(n) / 30

    def buffers():
        return (np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full(n, np.nan), np.full(n, np.nan),
                np.full(n, np.nan), np.full((n, 3), np.nan), np.full(n, np.nan))

    twin, comp = buffers(), buffers()
    rng_twin, rng_comp = np.random.default_rng(9), np.random.default_rng(9)
    launch.launch_droplets_sorted(rng_twin, geo, w[:nd], bounds, age[:nd], twin)
    launch.launch_mist(rng_twin, geo, w[nd:], None, age[nd:], out=tuple(a[nd:] for a in twin))
    buf = spawn.SpawnBuffers().ensure(n)
    launch.launch_parcels_compiled(rng_comp, geo, w, bounds, nd, age, comp, spawn._vehicle_table(geo),
                                   spawn._vehicle_consts(geo), buf.draws, buf.offs)
    for name, a, b in zip(("p0", "v0", "d_mm", "sigma0", "growth", "air", "updraught"), comp, twin, strict=True):
        assert np.isfinite(a).all(), name
        assert np.allclose(a, b, rtol=1e-13, atol=1e-15), name
    # Mostly the same bits: p0, v0 ~99.9 % (the tread's sin, cos and pow), d_mm ~97 % (exp), the rest all.
    assert np.mean(comp[0] == twin[0]) > 0.99 and np.mean(comp[2] == twin[2]) > 0.9
    assert all(np.array_equal(a, b) for a, b in zip(comp[3:], twin[3:], strict=True))
    assert rng_comp.random() == rng_twin.random()


@pytest.mark.parametrize("depth_mm", [0.0, 0.15, 1.2, 2.5, 6.0, float("nan"), -3.0, 1e30])
def test_wheels_equal_the_twins(depth_mm):
    """The wheels' kinematics and water model (turning, reversing, a lorry and a van; dry to beyond the cap, NaN
    and negative depths from an override): every table column, depth, budget array and risk is the twin's, bit
    for bit (the yaw's cosine and sine stay NumPy's; the rest is the twin's arithmetic in its order)."""
    from rain_core.effects.spray import wheels

    fleet = _fleet()
    fleet[1].speed_m_s = -0.0
    fleet[2].yaw_rate_rad_s = -0.3
    fn = _puddle(depth_mm)
    extra = np.array([[1.0, 500.0], [-3.0, 700.0]])
    out = []
    for compiled in (False, True):
        with jit.forced(compiled):
            out.append(wheels.gather_wheels(fleet, fn, extra_xz=extra))
    (twin_list, twin), (comp_list, comp) = out
    for name in ("_vehicle_table", "_wheel_table", "buckets", "available", "extra_depth_mm"):
        assert np.array_equal(getattr(comp, name), getattr(twin, name), equal_nan=True), name
    assert comp.throwing == twin.throwing
    for a, b in zip(comp_list, twin_list, strict=True):
        for name in ("contacts", "speed_m_s", "width_m", "film_depth_mm", "hydroplaning_risk"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        for name in ("available", "allocated", "thrown", "buckets"):
            assert np.array_equal(getattr(a.budget, name), getattr(b.budget, name)), name
    assert twin.throwing == (depth_mm > 0.0)  # a real test: water is thrown where there is some


def test_landing_bookkeeping_equals_the_twins():
    """Wet candidates join the landings in flight, due ones leave them: the twins' boolean masks, row for row
    (dry, NaN and exactly-standing depths; due times on both sides of now, one exactly at it)."""
    rng = np.random.default_rng(5)
    pending, cand = rng.random((50, 4)), rng.random((40, 4))
    depth = rng.uniform(0.0, 4.0, 40)
    depth[:3] = (np.nan, 2.0, np.nextafter(2.0, 0.0))
    got = kernels.add_wet_landings(pending, cand, depth, 2.0)
    assert np.array_equal(got, np.concatenate([pending, cand[depth >= 2.0]]))
    assert 0 < (depth >= 2.0).sum() < 40
    now = float(pending[7, 0])
    landed, rest = kernels.due_landings(pending, now)
    done = pending[:, 0] <= now
    assert np.array_equal(landed, pending[done, 1:]) and np.array_equal(rest, pending[~done])
    assert 0 < done.sum() < 50


def test_quantile_equals_the_twins():
    """The horizons' 90th percentile: the same order statistics, so the same value (ties and one or two
    elements included)."""
    rng = np.random.default_rng(6)
    for n in (1, 2, 3, 10, 11, 400, 1001):
        x = rng.random(n)
        if n > 3:
            x[: n // 3] = x[0]  # ties
        assert kernels.quantile_90(x) == spawn.quantile_90(x) == pytest.approx(np.quantile(x, 0.9), rel=1e-15)


@pytest.mark.parametrize("nd, nm", [(300, 40), (300, 0), (0, 25), (1, 1)])
def test_settle_and_horizons_in_one_call_equal_the_three_calls(nd, nm):
    """kernels.settle_horizons: kernels.settle, then spawn._horizons by kernels.quantile_90 (the path it replaces),
    bit for bit — fates, lives, spread rates, the running percentiles and the horizons (a ring without parcels
    keeps its percentile and gets 0)."""
    from rain_core.effects.spray import parcels

    rng = np.random.default_rng(9)
    n = nd + nm
    t_body, t_ground = rng.uniform(0.0, 2.0, nd), rng.uniform(0.0, 1.5, n)
    cap, speed, growth = rng.uniform(0.5, 3.0, nm), rng.uniform(1.0, 30.0, n), rng.random(n)
    fates = (parcels.FATE_ROAD, parcels.FATE_BODY, parcels.FATE_AIR)
    out = []
    for merged in (False, True):
        life, fate, g = np.empty(n), np.empty(n, np.int64), growth.copy()
        q90 = [0.7, 2.5]
        if merged:
            q = np.array(q90)
            horizons = kernels.settle_horizons(t_body, t_ground, cap, speed, nd, life, fate, g, *fates, q)
            q90 = q.tolist()
        else:
            kernels.settle(t_body, t_ground, cap, speed, nd, life, fate, g, *fates)
            horizons = [0.0, 0.0]
            for ring, sl in ((0, slice(0, nd)), (1, slice(nd, n))):
                if sl.stop > sl.start:
                    q90[ring] = 0.9 * q90[ring] + 0.1 * max(kernels.quantile_90(life[sl]), 0.05)
                    horizons[ring] = max(q90[ring], 0.05)
        out.append((life, fate, g, q90, tuple(horizons)))
    for a, b in zip(*out, strict=True):
        assert np.array_equal(a, b)
    assert (out[1][4][0] > 0.0) == (nd > 0) and (out[1][4][1] > 0.0) == (nm > 0)


def test_ring_push_by_the_kernel_equals_the_twins():
    """ParcelRing.push with the kernels (kernels.push_rows) and without: the same slots, times, head, slot ranges
    and last death, through pushes that fit, wrap, fill the ring exactly and overflow it."""
    rng = np.random.default_rng(11)
    rings = []
    for compiled in (False, True):
        with jit.forced(compiled):
            ring, log = parcels.ParcelRing(50), []
            for n in (20, 25, 30, 50, 7, 80, 1):
                rec = np.zeros(n, parcels.PARTICLE_DTYPE)
                parcels.as_floats(rec)[:] = rng.random((n, parcels.PARTICLE_FLOATS))
                birth, death = rng.random(n), rng.uniform(1.0, 9.0, n)
                log.append((ring.push(rec, birth, death), ring.head, ring.last_death()))
            rings.append((ring, log))
        rng = np.random.default_rng(11)
    (twin, twin_log), (comp, comp_log) = rings
    assert comp_log == twin_log and any(len(r) == 2 for r, _, _ in twin_log)
    assert np.array_equal(comp.data, twin.data) and np.array_equal(comp.birth, twin.birth)
    assert np.array_equal(comp.death, twin.death)


def _five_kernel_calls(em, frame, geo, buf, nd, n, w, bounds, mass, birth, age_now, now, wind):
    """spawn._launch_to_records as it was before kernels.launch_to_records: the five kernels called one by one,
    the mist caps drawn between the body test and the settle."""
    rng = em.rng
    out = tuple(a[:n] for a in buf.launch)
    launch.launch_parcels_compiled(rng, geo, w, bounds, nd, age_now, out, spawn._vehicle_table(geo),
                                   spawn._vehicle_consts(geo), buf.draws, buf.offs)
    p0, v0, d_mm, sigma0, growth, air, updraught = out
    u, speed, tau, t_ground, t_body = (a[:n] for a in buf.flight)
    kernels.fly(p0, v0, d_mm, air, updraught, nd, np.ascontiguousarray(wind, dtype=np.float64), spawn._MIST_VT_M_S,
                launch.WAKE_TAU_S, spawn._GK_X, spawn._GK_X0, spawn._GK_H, spawn._GK_Y0, spawn._GK_Y1, spawn._GK_D0,
                spawn._GK_D1, physics.G_M_S2, flight.DRAG_TAIL_FIT, layout.KERB_HEIGHT_M, layout.ROAD_HALF_WIDTH_M,
                1e-9, 40, u, speed, tau, t_ground)
    vi = w // 4
    life, fate = np.empty(n), np.empty(n, dtype=np.int64)
    if nd:
        kernels.body_hit(p0, v0, u, tau, t_ground, spawn._vehicle_table(geo), vi, age_now, nd, body.SAMPLES,
                         body.ZOOM, body.ROUNDS, t_body)
    cap = rng.uniform(*launch.MIST_LIFE_S, n - nd) if n > nd else np.zeros(0)
    q90 = buf.q90
    q90[0], q90[1] = em._life_q90
    horizons = kernels.settle_horizons(t_body[:nd], t_ground, cap, speed, nd, life, fate, growth, parcels.FATE_ROAD,
                                       parcels.FATE_BODY, parcels.FATE_AIR, q90)
    em._life_q90[0], em._life_q90[1] = q90.tolist()
    spawn._file_compiled(em, frame, geo, buf, nd, now, horizons, fate, life, mass, p0, v0, u, tau, birth, sigma0,
                         growth, d_mm, vi)


def test_launch_to_records_equals_the_five_kernel_calls(monkeypatch):
    """kernels.launch_to_records (launch, fly, body test, settle and filing in one call, the caps drawn before
    it) against the five kernels called one by one: over 150 frames the same rings, times, landings, stats,
    percentiles and generator state, bit for bit."""
    runs = []
    for one_call in (True, False):
        with monkeypatch.context() as m:
            if not one_call:
                m.setattr(spawn, "_launch_to_records", _five_kernel_calls)
            with jit.forced(True):
                em = SprayEmitter(seed=7, budget=3000, film_depth_fn=_puddle(4.0))
                _, landed = _drive(em, _fleet(), 150)
        runs.append((em, np.concatenate(landed)))
    (one, one_landed), (five, five_landed) = runs
    assert one.stats.parcels == five.stats.parcels > 10_000 and one.stats.mist_puffs == five.stats.mist_puffs > 0
    assert np.array_equal(one.stats.fates, five.stats.fates) and np.array_equal(one_landed, five_landed)
    for a, b in zip(one.rings, five.rings, strict=True):
        assert a.head == b.head and a.last_death() == b.last_death()
        assert np.array_equal(a.data, b.data) and np.array_equal(a.birth, b.birth)
        assert np.array_equal(a.death, b.death)
    assert np.array_equal(one._candidates, five._candidates) and np.array_equal(one._pending, five._pending)
    assert one._life_q90 == five._life_q90
    assert one.rng.bit_generator.state == five.rng.bit_generator.state
