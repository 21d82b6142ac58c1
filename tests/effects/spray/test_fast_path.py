"""The emitter's fast path against its float64 reference (``SprayEmitter(reference=True)``): the water model at all
wheels at once, the launches sorted by bucket, Newton landing times, the body test in the body's frame, and the
ring that receives only the new parcels (rain_core.effects.spray)."""

from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import jit, layout
from rain_core.effects.spray import body, emitter, flight, launch, parcels, spawn, wheels
from rain_core.effects.spray.emitter import SprayEmitter
from rain_core.effects.spray.water import KMH
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, VAN_SPEC, EgoCar, Vehicle
from rain_core.weather import WeatherState, WindState


def _puddle(depth_mm):
    return lambda x, z: np.full(np.broadcast(np.asarray(x), np.asarray(z)).shape, float(depth_mm))


def _fleet(kmh=100.0):
    ego = EgoCar(CAR_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 520.0), 0.05, kmh * KMH)
    ego.yaw_rate_rad_s = 0.08  # turning: outer wheels faster than inner ones
    return [ego,
            Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[1], 0.0, 490.0), 0.0, kmh * KMH),
            Vehicle(VAN_SPEC, (layout.LANE_CENTRES_X[2], 0.0, 560.0), np.pi, 0.8 * kmh * KMH),
            Vehicle(CAR_SPEC, (layout.LANE_CENTRES_X[3], 0.0, 600.0), np.pi, -4.0)]  # reversing


def _frame(t, vehicles, wetness=1.0, wind=(1.5, 0.0, -2.0)):
    weather = WeatherState(rate_mm_h=8.0, wetness=wetness, wind=WindState(velocity_m_s=tuple(wind)))
    return SimpleNamespace(time_s=t, dt_s=1 / 30, vehicles=vehicles, ego=vehicles[0], weather=weather,
                           settings=None, world=None)


def _drive(em, vehicles, frames, dt=1 / 30, t0=0.0, **kw):
    t, out = t0, []
    for _ in range(frames):
        for v in vehicles:
            v.position = v.position + v.forward() * v.speed_m_s * dt
        t += dt
        em.emit(_frame(t, vehicles, **kw))
        out.append(em.landed_impacts())
    return t, out


def test_all_wheels_at_once_equal_the_per_vehicle_water_model(kernel_path):
    fleet = _fleet()
    fn = _puddle(2.5)
    got, geo = wheels.gather_wheels(fleet, fn)
    ref = [wheels.wheel_water(v, fn) for v in fleet]
    ref_geo = wheels.WheelGeometry(ref)
    for a, b in zip(got, ref, strict=True):
        assert a.vehicle is b.vehicle
        for name in ("contacts", "speed_m_s", "width_m", "film_depth_mm", "hydroplaning_risk"):
            assert np.allclose(getattr(a, name), getattr(b, name), rtol=1e-12, atol=1e-12), name
        for name in ("available", "allocated", "thrown", "buckets"):
            assert np.allclose(getattr(a.budget, name), getattr(b.budget, name), rtol=1e-12, atol=1e-15), name
    for name in ("position", "velocity", "forward", "right", "height", "half_length", "contacts", "speed", "travel",
                 "outward", "radius", "width", "wheel_velocity", "box_params"):
        assert np.allclose(getattr(geo, name), getattr(ref_geo, name), rtol=1e-12, atol=1e-12), name
    assert [geo.boxes[i] for i in geo.box_index] == [ref_geo.boxes[i] for i in ref_geo.box_index]
    assert got[3].speed_m_s.max() < 0.0  # the reversing car's wheels keep their sign


def test_launches_sorted_by_bucket_equal_the_reference():
    fleet = _fleet()
    _, geo = wheels.gather_wheels(fleet, _puddle(6.0))
    rng = np.random.default_rng(4)
    n = 3000
    w = rng.integers(0, 4 * len(fleet), n)
    bucket = rng.integers(0, 5, n)
    age = rng.random(n) / 30
    fast = launch.launch_droplets(np.random.default_rng(9), geo, w, bucket, age)
    ref = launch.launch_droplets_reference(np.random.default_rng(9), geo, w, bucket, age)
    for a, b in zip(fast, ref, strict=True):
        assert a.shape == b.shape and np.allclose(a, b, rtol=1e-12, atol=1e-12)


def test_newton_landing_times_equal_the_bisection():
    rng = np.random.default_rng(2)
    n = 20_000
    y0, w0 = rng.uniform(0.0, 1.5, n), rng.uniform(-15.0, 15.0, n)
    uy, tau = -rng.uniform(0.1, 9.0, n), rng.uniform(1e-3, 1.0, n)
    for level in (0.0, layout.KERB_HEIGHT_M, 2.0):
        fast = flight.time_to_height_newton(y0, w0, uy, tau, level)
        ref = flight.time_to_height(y0, w0, uy, tau, level)
        assert np.abs(fast - ref).max() < 1e-7
    p0 = np.column_stack([rng.uniform(-8.0, 8.0, n), y0, rng.uniform(0.0, 10.0, n)])
    v0 = np.column_stack([rng.uniform(-20.0, 20.0, n), w0, rng.uniform(-30.0, 30.0, n)])
    u = np.column_stack([rng.uniform(-5.0, 5.0, n), uy, rng.uniform(-5.0, 5.0, n)])
    fast = flight.ground_time(p0, v0, u, tau)
    assert np.abs(fast - flight.ground_time(p0, v0, u, tau, reference=True)).max() < 1e-7
    # Scalars (0-d) and a broadcast level.
    for level in (0.5, np.array([0.0, 0.5])):
        fast = flight.time_to_height_newton(1.0, 2.0, -3.0, 0.1, level)
        assert np.shape(fast) == np.shape(level)
        assert np.abs(fast - flight.time_to_height(1.0, 2.0, -3.0, 0.1, level)).max() < 1e-7


def _body_case(seed=3, n=3000):
    """Parcels thrown back and up from the wheels of a car at 100 km/h (as the spray throws them)."""
    rng = np.random.default_rng(seed)
    car = Vehicle(CAR_SPEC, (1.75, 0.0, 100.0), 0.0, 100 * KMH)
    contacts = car.wheel_contacts()[rng.integers(0, 4, n)]
    vel = car.velocity()
    p0 = contacts + np.column_stack([rng.uniform(-0.3, 0.3, n), rng.uniform(0.05, 0.6, n), rng.uniform(-0.4, 0.4, n)])
    v0 = vel * rng.uniform(0.0, 0.5, (n, 1)) + np.column_stack([rng.normal(0, 3, n), rng.uniform(0, 6, n),
                                                                 rng.normal(0, 3, n)])
    d_mm = rng.uniform(0.1, 3.0, n)
    vt = np.asarray(flight.physics.terminal_velocity(d_mm))
    u = vel * rng.uniform(0.0, 0.35, (n, 1))
    u[:, 1] -= vt
    tau = flight.drag_time_constant(d_mm, np.linalg.norm(v0 - u, axis=1))
    t_max = flight.ground_time(p0, v0, u, tau)
    box = body.BodyBox.of(CAR_SPEC)
    rep = np.ones((n, 1))
    args = (p0, v0, u, tau, t_max, car.position * rep, vel * rep, car.right() * rep, car.forward() * rep)
    return args, box


def test_body_test_in_the_bodys_frame_agrees_with_a_dense_reference():
    args, box = _body_case()
    n = len(args[3])
    t_max = args[4]
    idx = np.zeros(n, dtype=np.int64)
    dense = body.body_hit_time(*args, [box], idx, samples=400, refine=16)
    ref = body.body_hit_time(*args, [box], idx)
    fast = body.body_hit_time_fast(*args, np.tile(np.array(list(vars(box).values())), (n, 1)))
    hit_d, hit_f, hit_r = dense < t_max, fast < t_max, ref < t_max
    assert 0.1 < hit_d.mean() < 0.9  # a real test: many drops meet the body, many do not
    # The fast test decides the fate as well as the default reference does (both against 400 samples).
    assert (hit_f != hit_d).mean() <= max((hit_r != hit_d).mean(), 0.005) + 0.005
    both = hit_f & hit_d
    assert np.mean(np.abs(fast - dense)[both] < 2e-3) > 0.97
    # The age returned is outside the body: the drop is drawn only up to its surface (some of these random
    # drops start inside it, which the spray's launches never do: left out).
    def inside_at(t):
        pos = flight.flight_position(args[0], args[1], args[2], args[3], t)
        rel = pos - (args[5] + args[6] * t[:, None])
        return box.contains(np.stack([np.einsum("nc,nc->n", rel, args[7]), rel[:, 1],
                                      -np.einsum("nc,nc->n", rel, args[8])], -1))

    starts_inside = inside_at(np.zeros(n))
    assert not inside_at(fast)[hit_f & ~starts_inside].any()


def _same_body_test(monkeypatch):
    """Make the fast emitter use the reference body test, so everything else can be compared exactly."""
    def reference_body(p0, v0, u, tau, t_max, origin, vel, right, forward, box_params):
        rows, index = np.unique(box_params, axis=0, return_inverse=True)
        boxes = [body.BodyBox(*row) for row in rows]
        return body.body_hit_time(p0, v0, u, tau, t_max, origin, vel, right, forward, boxes, index)

    monkeypatch.setattr(emitter, "body_hit_time_fast", reference_body)


def test_fast_emitter_writes_the_references_parcels(monkeypatch):
    """Same seed, same frames → the same parcels (float32 records equal) and the same landings, once the body
    test (the one approximation that differs: see the next test) is the same. The NumPy twin: its landings match
    to the last bits kept here, which the compiled kernels' Newton stops do not promise (test_kernels.py compares
    them with the twin)."""
    _same_body_test(monkeypatch)
    runs = []
    for reference in (False, True):
        em = SprayEmitter(seed=7, budget=3000, film_depth_fn=_puddle(4.0), reference=reference)
        with jit.forced(False):
            _, landed = _drive(em, _fleet(), 45)
        runs.append((em, np.concatenate(landed)))
    (fast, fast_landed), (ref, ref_landed) = runs
    assert fast.stats.parcels == ref.stats.parcels > 5000 and fast.stats.mist_puffs == ref.stats.mist_puffs > 0
    for rf, rr in zip(fast.rings, ref.rings, strict=True):
        for name in parcels.PARTICLE_DTYPE.names:
            assert np.allclose(rf.data[name], rr.data[name], rtol=2e-7, atol=1e-6), name
        assert rf.head == rr.head
    assert fast.stats.thrown_kg == pytest.approx(ref.stats.thrown_kg, rel=1e-12)
    assert np.allclose(fast.stats.fates, ref.stats.fates, rtol=1e-9)
    # Landings in standing water: the same ones; the fast path looks up the water under a landing with the
    # next frame's wheels, so one that lands within its own frame reaches the ripples a frame later.
    assert len(ref_landed) > 100
    late = len(ref_landed) - len(fast_landed)
    assert 0 <= late <= len(fast._candidates) + len(fast._pending) - len(ref._pending)
    as_set = {tuple(row) for row in np.round(ref_landed, 6)}  # equal up to the launches' last bits
    assert all(tuple(row) in as_set for row in np.round(fast_landed, 6))


def test_fast_emitter_matches_the_reference_statistics(kernel_path):
    """With its own body test (denser in the window where a drop can meet the body) the fast path throws the
    same water into the same fates within a few per cent."""
    out = []
    for reference in (False, True):
        em = SprayEmitter(seed=11, budget=4000, film_depth_fn=_puddle(3.0), reference=reference)
        t, landed = _drive(em, _fleet(), 60)
        out.append((em, sum(len(x) for x in landed), sum(float(x[:, 2].sum()) for x in landed)))
    (fast, fast_n, fast_p), (ref, ref_n, ref_p) = out
    assert fast.stats.thrown_kg == pytest.approx(ref.stats.thrown_kg, rel=1e-12)
    assert fast.stats.emitted_kg == pytest.approx(ref.stats.emitted_kg, rel=0.02)
    assert fast.stats.parcels == pytest.approx(ref.stats.parcels, rel=0.05)
    share_f = fast.stats.fates / fast.stats.fates.sum()
    share_r = ref.stats.fates / ref.stats.fates.sum()
    assert np.abs(share_f - share_r).max() < 0.04
    assert fast_n == pytest.approx(ref_n, rel=0.1) and fast_p == pytest.approx(ref_p, rel=0.1)


@pytest.mark.parametrize("reference", [False, True])
def test_water_thrown_per_second_is_the_water_models_flux(reference, kernel_path):
    """Per wheel: the parcels' mass per second equals the water model's thrown flux (the remainder waiting for
    the next parcel is all that is missing), and the flux is M_w = v·b·WFD·ρ_w above 64 km/h."""
    fleet = _fleet(100.0)[:2]
    fleet[0].yaw_rate_rad_s = 0.0
    em = SprayEmitter(seed=5, budget=6000, film_depth_fn=_puddle(3.0), reference=reference)
    em.emit(_frame(0.0, fleet))
    t, _ = _drive(em, fleet, 30)
    for v in fleet:
        key = id(v)
        model = em.wheels[fleet.index(v)].budget
        thrown, emitted = em.stats.wheel_thrown_kg[key], em.stats.wheel_emitted_kg[key]
        assert np.allclose(thrown / t, model.thrown.sum(axis=-1), rtol=1e-9)  # steady: rate × time
        assert np.allclose(model.thrown.sum(axis=-1), model.available, rtol=1e-12)  # all of M_w at 100 km/h
        assert np.allclose(emitted + em._acc[key].sum(axis=-1), thrown, rtol=1e-12)
        assert np.all(np.abs(emitted / thrown - 1.0) < 0.03)


def test_only_new_parcels_are_written_and_uploaded(kernel_path):
    em = SprayEmitter(seed=1, budget=2000, film_depth_fn=_puddle(3.0))
    fleet = _fleet()
    t, _ = _drive(em, fleet, 3)
    em.take_dirty()  # the first upload (whole rings) is done
    for ring in em.rings:
        ring.data["rand"][:] = -7.0  # a marker: any slot written again loses it
    _drive(em, fleet, 1, t0=t)
    dirty = em.take_dirty()
    for ring, ranges in zip(em.rings, dirty, strict=True):
        written = np.zeros(ring.capacity, bool)
        for start, count in ranges:
            written[start:start + count] = True
        assert len(ranges) <= 2 and written.sum() < ring.capacity  # one range, or two where it wraps
        assert np.all(ring.data["rand"][~written] == -7.0) and np.all(ring.data["rand"][written] >= 0.0)
        # What was written is this frame's parcels still alive at its end (those that died within it are not).
        now = em.clock(t + 1 / 30)
        assert np.all(ring.birth[written] > now - 1 / 30 - 1e-9) and np.all(ring.death[written] > now)
        older = ring.birth[~written]
        assert np.all((older <= now - 1 / 30 + 1e-9) | np.isinf(older))  # earlier frames' (or empty) slots
    count = sum(c for r in dirty for _, c in r)
    assert 0 < count <= em.stats.last_parcels + em.stats.last_mist


def test_fast_terminal_velocity_is_the_models_bit_for_bit():
    """The spawn path's terminal velocity (per-interval tables, no branches) over every size a launch can give
    (0.1–5 mm, the table's knots among them) is physics.terminal_velocity's, bit for bit."""
    knots = flight.physics.GUNN_KINZER_D_MM
    d = np.concatenate([np.random.default_rng(3).uniform(0.1, 5.0, 20000), [0.1, 5.0],
                        knots[(knots >= 0.1) & (knots <= 5.0)]])
    assert np.array_equal(spawn._terminal_velocity(d), flight.physics.terminal_velocity(d))
    sizes = launch._SIZES  # every bucket's clip stays inside the table, where no branch is needed
    assert sizes[:, 2].min() > knots[0] and sizes[:, 3].max() < knots[-1]
