"""rain_core.spray: the Flintsch/Weir water model, the flight model and its GLSL twin, the emitter, the effect."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import layout, physics, spray
from rain_core.spray import (
    BUCKETS,
    KMH,
    MECHANISMS,
    BodyBox,
    SprayEmitter,
    allocate_water,
    body_hit_time,
    drag_time_constant,
    flight_position,
    flight_velocity,
    ground_time,
    hydroplaning_risk,
    phase_function,
)
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, Vehicle
from rain_core.weather import WeatherState, WindState

RNG = np.random.default_rng(7)


# --- the water model ----------------------------------------------------------------------------------------

def test_allocation_sums_to_what_was_available_and_never_exceeds_it():
    v = np.concatenate([[0.0, 1.0, 60.0], RNG.uniform(0.0, 60.0, 2000)])
    b = np.concatenate([[0.2, 0.0, 0.3], RNG.uniform(0.1, 0.4, 2000)])
    h = np.concatenate([[0.005, 0.005, 0.0], RNG.uniform(0.0, 0.012, 2000)])
    h[RNG.random(len(h)) < 0.1] = 0.0
    w = allocate_water(v, b, h)
    assert np.allclose(w.available, physics.splash_water_flux(v, b, h), rtol=1e-12, atol=0)
    assert np.all(w.allocated >= 0.0)
    assert np.allclose(w.allocated.sum(axis=-1), w.available, rtol=1e-12, atol=1e-15)
    assert np.all(w.allocated.sum(axis=-1) <= w.available * (1 + 1e-12) + 1e-15)
    assert np.all(w.thrown >= 0.0) and np.all(w.thrown <= w.allocated * (1 + 1e-12) + 1e-15)
    assert np.allclose(w.buckets.sum(axis=-1), w.thrown.sum(axis=-1), rtol=1e-12, atol=1e-15)
    assert np.all(w.buckets >= 0.0) and np.all(w.retained >= -1e-12)
    assert w.buckets.shape[-1] == len(BUCKETS) and w.allocated.shape[-1] == len(MECHANISMS)


def test_water_is_spent_in_order_capillary_tread_side_bow():
    v, b = 30.0, 0.2
    per_mm = v * b * 1.0  # kg/s per mm of film
    thin, grooves, side, deep = (allocate_water(v, b, h * 1e-3).allocated for h in (0.05, 1.0, 3.0, 8.0))
    assert np.allclose(thin, [0.05 * per_mm, 0, 0, 0])
    assert np.allclose(grooves, [0.1 * per_mm, 0.9 * per_mm, 0, 0])
    assert np.allclose(side, [0.1 * per_mm, 1.5 * per_mm, 1.4 * per_mm, 0])
    assert np.allclose(deep, [0.1 * per_mm, 1.5 * per_mm, 3.0 * per_mm, 3.4 * per_mm])


def test_nothing_below_the_speed_and_depth_thresholds():
    h = np.linspace(0.0, 0.01, 41)
    slow = allocate_water(47.9 * KMH, 0.22, h)
    assert np.all(slow.spray == 0.0) and np.all(slow.mist == 0.0)  # no spray below 48 km/h
    assert np.all(slow.thrown[..., 0] == 0.0)
    walk = allocate_water(14.9 * KMH, 0.22, h)
    assert np.all(walk.thrown[..., 1] == 0.0)  # grooves keep their water below 15 km/h
    creep = allocate_water(4.9 * KMH, 0.22, h)
    assert np.all(creep.thrown == 0.0) and np.all(creep.retained == creep.available)
    dry = allocate_water(np.linspace(0, 60, 13), 0.22, 0.0)
    assert np.all(dry.available == 0.0) and np.all(dry.thrown == 0.0)
    shallow = allocate_water(30.0, 0.22, 1.59e-3)
    assert shallow.allocated[2] == 0.0 and shallow.allocated[3] == 0.0  # no side waves until grooves are full
    mid = allocate_water(30.0, 0.22, 4.59e-3)
    assert mid.allocated[2] > 0.0 and mid.allocated[3] == 0.0  # no bow wave below 4.6 mm
    fast = allocate_water(64.0 * KMH, 0.22, 0.2e-3)
    assert fast.spray > 0.0 and fast.mist > 0.0  # measurable spray by 64 km/h


def test_emission_is_linear_in_speed_and_film_depth_where_the_model_says_so():
    b = 0.225
    h = np.array([0.05, 0.2, 1.0, 3.0, 6.0]) * 1e-3
    v = np.array([70.0, 90.0]) * KMH  # past every ramp: everything thrown
    one = allocate_water(v[:, None], b, h[None, :]).thrown.sum(axis=-1)
    two_v = allocate_water(2 * v[:, None], b, h[None, :]).thrown.sum(axis=-1)
    two_h = allocate_water(v[:, None], b, 2 * h[None, :]).thrown.sum(axis=-1)
    assert np.allclose(two_v, 2 * one, rtol=1e-12) and np.allclose(two_h, 2 * one, rtol=1e-12)
    assert np.allclose(one, physics.splash_water_flux(v[:, None], b, h[None, :]), rtol=1e-12)
    # Inside one band a mechanism's share is linear in the depth too (capillary below 0.1 mm).
    cap = allocate_water(25.0, b, np.array([0.02, 0.04, 0.08]) * 1e-3).allocated[..., 0]
    assert np.allclose(cap / cap[0], [1, 2, 4], rtol=1e-12)
    # Below the ramps the throw is not linear: half the speed inside the capillary ramp throws less than half.
    a, c = (allocate_water(s * KMH, b, 0.1e-3).thrown[0] for s in (56.0, 112.0))
    assert a < 0.5 * c


def test_hydroplaning_risk():
    car = spray.TYRE_PRESSURE_KPA["car"]
    assert spray.hydroplaning_speed_m_s(car) / KMH == pytest.approx(6.36 * math.sqrt(car))
    v = np.linspace(0.0, 50.0, 101)
    thin = hydroplaning_risk(v, 0.2e-3, car)
    assert np.all(thin == 0.0)  # a film the tread drains never lifts the tyre
    deep = hydroplaning_risk(v, 8e-3, car)
    assert np.all(np.diff(deep) >= 0.0) and deep[0] == 0.0 and deep[-1] == 1.0
    assert hydroplaning_risk(60 * KMH, 8e-3, car) == 0.0  # below half the load on the water wedge
    depths = np.linspace(0.0, 10e-3, 51)
    assert np.all(np.diff(hydroplaning_risk(90 * KMH, depths, car)) >= 0.0)
    assert hydroplaning_risk(95 * KMH, 8e-3, spray.TYRE_PRESSURE_KPA["truck"]) == 0.0  # lorry tyres: 700 kPa
    assert hydroplaning_risk(95 * KMH, 8e-3, car) > 0.8


# --- flight -------------------------------------------------------------------------------------------------

def test_closed_form_solves_linear_drag():
    p0, v0, u, tau = np.array([0.5, 0.3, 2.0]), np.array([3.0, 8.0, -20.0]), np.array([1.0, -2.0, 0.0]), 0.3
    x, v, dt = p0.copy(), v0.copy(), 1e-4
    for _ in range(10000):  # RK4 of dv/dt = (u − v)/τ to t = 1 s
        def f(state):
            return np.concatenate([state[3:], (u - state[3:]) / tau])
        s = np.concatenate([x, v])
        k1 = f(s)
        k2 = f(s + 0.5 * dt * k1)
        k3 = f(s + 0.5 * dt * k2)
        k4 = f(s + dt * k3)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x, v = s[:3], s[3:]
    assert np.allclose(flight_position(p0, v0, u, tau, 1.0), x, atol=1e-9)
    assert np.allclose(flight_velocity(v0, u, tau, 1.0), v, atol=1e-9)
    assert np.allclose(flight_position(p0, v0, u, tau, 0.0), p0)


def test_drag_time_constant_matches_quadratic_drag():
    d = np.array([0.1, 0.3, 1.0, 3.0])
    vt = np.asarray(physics.terminal_velocity(d))
    assert np.allclose(drag_time_constant(d, vt), vt / spray.G)  # at terminal speed: plain v_t/g
    assert np.allclose(drag_time_constant(d, vt * (1 + 1e-9)), vt / spray.G, rtol=1e-6)  # continuous there
    # The distance to slow from s0 to v_t is quadratic drag's (v_t²/g)·ln(s0/v_t) (1-D, no gravity), stretched
    # by at most DRAG_TAIL_FIT for quadratic drag's long tail.
    s0 = 25.0
    tau = drag_time_constant(d, s0)
    linear = tau * (s0 - vt)
    quadratic = vt**2 / spray.G * np.log(s0 / vt)
    assert np.all(linear >= quadratic) and np.all(linear <= spray.DRAG_TAIL_FIT * quadratic)
    # Where a drop lands: within 25 % of an RK4 quadratic-drag flight (the bench tabulates this).
    for d_mm, launch in ((2.0, (0.0, 3.0, -6.0)), (0.3, (0.0, 4.0, -12.0)), (3.0, (2.0, 2.0, 8.0))):
        ref, t_ref = spray.quadratic_drag_reference((0, 0.3, 0), launch, d_mm)
        vt1 = physics.terminal_velocity(d_mm)
        u = np.array([0.0, -vt1, 0.0])
        tau1 = drag_time_constant(d_mm, np.linalg.norm(np.asarray(launch) - u))
        t = ground_time(np.array([[0, 0.3, 0]]), np.array([launch]), u[None], np.array([tau1]))[0]
        land = flight_position(np.array([0, 0.3, 0]), np.array(launch), u, tau1, t)
        reach = np.hypot(ref[0], ref[2])
        assert abs(np.hypot(land[0], land[2]) - reach) < 0.25 * reach + 0.02


def test_ground_time_lands_on_the_road_and_on_the_kerb_top():
    p0 = np.array([[1.0, 0.4, 0.0], [6.5, 0.4, 0.0]])
    v0 = np.array([[0.0, 3.0, 0.0], [6.0, 3.0, 0.0]])
    u = np.array([[0.0, -6.5, 0.0], [0.0, -6.5, 0.0]])
    tau = np.array([0.5, 0.5])
    t = ground_time(p0, v0, u, tau)
    y = flight_position(p0, v0, u, tau, t)[:, 1]
    assert y[0] == pytest.approx(0.0, abs=1e-9)
    assert y[1] == pytest.approx(layout.KERB_HEIGHT_M, abs=1e-9)  # flew over the kerb onto the sidewalk


def test_body_hit_stops_drops_at_the_body_and_lets_the_rest_pass():
    car = Vehicle(CAR_SPEC, (0.0, 0.0, 0.0), 0.0, 20.0)
    box = BodyBox.of(CAR_SPEC)
    fl = car.wheel_contacts()[0]
    # Thrown straight up from the front-left tyre's inner half: meets the wheel arch above the well.
    p0 = np.array([fl + [0.05, 0.3, 0.0], fl + [0.0, 0.05, 0.0]])
    v0 = np.array([[0.0, 15.0, -20.0], [-12.0, 0.5, -20.0]])  # second: sideways out of the well, low
    u = np.array([[0.0, -1.0, 0.0], [0.0, -1.0, 0.0]])
    tau = np.array([0.05, 0.05])
    t_ground = ground_time(p0, v0, u, tau)
    t = body_hit_time(p0, v0, u, tau, t_ground, np.zeros((2, 3)), np.tile(car.velocity(), (2, 1)),
                      np.tile(car.right(), (2, 1)), np.tile(car.forward(), (2, 1)), [box], np.zeros(2, int))
    assert t[0] < 0.5 * t_ground[0]
    top = flight_position(p0[0], v0[0], u[0], tau[0], t[0])
    assert box.well_top - 0.05 < top[1] < box.well_top + 0.2  # stopped at the arch
    assert t[1] == t_ground[1]


# --- the GLSL twin ------------------------------------------------------------------------------------------

def _probe(gl_ctx, shaders, p0, v0, tau, u, age, mu):
    return spray.glsl_probe(gl_ctx, shaders, p0, v0, tau, u, age, mu)


def test_glsl_flight_and_phase_agree_with_numpy(gl_ctx, shaders):
    n = 512
    p0 = RNG.uniform(-5, 5, (n, 3))
    v0 = RNG.uniform(-30, 30, (n, 3))
    u = RNG.uniform(-3, 3, (n, 3))
    u[:, 1] = -RNG.uniform(0.2, 9.0, n)
    tau = RNG.uniform(0.005, 1.0, n)
    age = RNG.uniform(0.0, 3.0, n)
    age[:16] = RNG.uniform(0, 1e-5, 16)  # the series branch near t = 0
    mu = np.cos(RNG.uniform(0, np.pi, n))
    pos, vel, ph = _probe(gl_ctx, shaders, p0, v0, tau, u, age, mu)
    assert np.allclose(pos, flight_position(p0, v0, u, tau, age), atol=2e-4, rtol=1e-5)
    assert np.allclose(vel, flight_velocity(v0, u, tau, age), atol=1e-4, rtol=1e-5)
    assert np.allclose(ph, phase_function(mu), rtol=2e-4, atol=1e-6)


def test_phase_function_is_normalised():
    mu = 1.0 - np.geomspace(1e-9, 2.0, 400001)[::-1]  # dense near the forward peak
    mu = np.concatenate([[-1.0], mu[mu > -1.0], [1.0]])
    p = phase_function(mu)
    total = 2 * np.pi * np.sum((p[1:] + p[:-1]) / 2 * np.diff(mu))
    assert total == pytest.approx(1.0, abs=2e-3)
    assert 0.05 < spray.REFLECTION_SHARE < 0.08  # water's mean external reflectance (~6.6 %)


# --- the emitter --------------------------------------------------------------------------------------------

def _frame(t, vehicles, wetness=0.0, wind=(0.0, 0.0, 0.0)):
    weather = WeatherState(rate_mm_h=4.0, wetness=wetness, wind=WindState(velocity_m_s=tuple(wind)))
    return SimpleNamespace(time_s=t, dt_s=0.0, vehicles=vehicles, ego=vehicles[0] if vehicles else None,
                           weather=weather, settings=None, world=None)


def _drive(emitter, vehicles, seconds, dt=1 / 30, wetness=0.0, t0=0.0, wind=(0.0, 0.0, 0.0)):
    t = t0
    emitter.emit(_frame(t, vehicles, wetness, wind))
    for _ in range(int(round(seconds / dt))):
        for v in vehicles:
            v.previous_wheel_contacts = v.wheel_contacts()
            v.position = v.position + v.forward() * v.speed_m_s * dt
        t += dt
        emitter.emit(_frame(t, vehicles, wetness, wind))
    return t


def _puddle(depth_mm):
    return lambda x, z: np.full(np.broadcast(np.asarray(x), np.asarray(z)).shape, float(depth_mm))


def _cars(kmh=100.0):
    return [Vehicle(CAR_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 500.0), 0.0, kmh * KMH),
            Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[1], 0.0, 480.0), 0.0, kmh * KMH)]


def _all_records(emitter):
    return [r.data[r.death > -np.inf] for r in emitter.rings]


def test_droplets_never_pass_below_the_road(gl_ctx, shaders):
    em = SprayEmitter(seed=3, budget=4000, film_depth_fn=_puddle(8.0))
    t = _drive(em, _cars(80.0), 1.0, wind=(3.0, 0.0, -2.0))
    recs = np.concatenate(_all_records(em))
    assert len(recs) > 1000
    frac = np.linspace(0.0, 1.0, 101)
    ages = recs["life"][:, None].astype(np.float64) * frac[None, :]
    pos = flight_position(recs["p0"][:, None, :], recs["v0"][:, None, :], recs["u"][:, None, :],
                          recs["tau"][:, None], ages)
    assert pos[..., 1].min() >= 0.0
    # The shader evaluates the same float32 numbers: at the end of every life it is still above the road.
    pos_gl, _, _ = _probe(gl_ctx, shaders, recs["p0"], recs["v0"], recs["tau"], recs["u"], recs["life"],
                          np.zeros(len(recs)))
    assert pos_gl[:, 1].min() >= 0.0
    assert t > 0.9


def test_emitted_parcels_carry_the_thrown_mass():
    em = SprayEmitter(seed=5, budget=3000, film_depth_fn=_puddle(3.0))
    _drive(em, _cars(70.0), 0.5, wetness=1.0)
    pending = sum(float(a.sum()) for a in em._acc.values())
    st = em.stats
    assert st.thrown_kg > 0 and st.emitted_kg > 0.95 * st.thrown_kg
    assert st.emitted_kg + pending == pytest.approx(st.thrown_kg, rel=1e-12)
    assert st.thrown_kg <= st.available_kg * (1 + 1e-12)
    assert st.fates.sum() == pytest.approx(st.emitted_kg, rel=1e-12)


def test_determinism():
    runs = []
    for seed in (11, 11, 12):
        em = SprayEmitter(seed=seed, budget=2000, film_depth_fn=_puddle(5.0))
        _drive(em, _cars(90.0), 0.3)
        runs.append(np.concatenate(_all_records(em)).tobytes())
    assert runs[0] == runs[1] and runs[0] != runs[2]


def test_wet_road_makes_mist_at_speed_and_a_dry_road_none():
    wet = SprayEmitter(seed=1, budget=2000, film_depth_fn=_puddle(0.0))
    _drive(wet, _cars(100.0), 0.5, wetness=1.0)
    assert wet.stats.mist_puffs > 0 and wet.stats.parcels > 0
    b = wet.wheels[0].budget
    assert np.all(b.spray > 0) and np.all(b.splash < b.spray)  # a film makes spray, hardly any splash
    dry = SprayEmitter(seed=1, budget=2000, film_depth_fn=_puddle(0.0))
    _drive(dry, _cars(100.0), 0.5, wetness=0.0)
    assert dry.stats.parcels == 0 and dry.stats.mist_puffs == 0 and not dry.throwing()
    slow = SprayEmitter(seed=1, budget=2000, film_depth_fn=_puddle(0.0))
    _drive(slow, _cars(40.0), 0.5, wetness=1.0)
    assert slow.stats.mist_puffs == 0  # no spray below 48 km/h


def test_budget_bounds_the_parcels_alive():
    em = SprayEmitter(seed=2, budget=500, film_depth_fn=_puddle(6.0))
    t = _drive(em, _cars(100.0), 1.0, wetness=1.0)
    drops, mist = em.alive_counts(t)
    assert 0 < drops <= 500 and 0 < mist <= spray.MIN_MIST_CAPACITY
    em.set_budget(100)
    assert em.rings[0].capacity == 100 and em.alive_counts(t) == (0, 0)


def test_landings_in_standing_water_feed_the_ripples():
    em = SprayEmitter(seed=4, budget=3000, film_depth_fn=_puddle(8.0))
    cars = _cars(60.0)
    landed = []
    t, dt = 0.0, 1 / 30
    em.emit(_frame(t, cars))
    for _ in range(20):
        for v in cars:
            v.position = v.position + v.forward() * v.speed_m_s * dt
        t += dt
        em.emit(_frame(t, cars))
        landed += em.landed_in_water()
    assert len(landed) > 50
    pts = np.array(landed)
    assert np.all(pts[:, 2] >= 0.0) and pts[:, 2].sum() > 0.0
    near = np.min([np.hypot(pts[:, 0] - c.position[0], pts[:, 1] - c.position[2]) for c in cars], axis=0)
    assert np.percentile(near, 90) < 25.0  # around the cars that threw them
    film_only = SprayEmitter(seed=4, budget=3000, film_depth_fn=_puddle(0.5))
    _drive(film_only, _cars(60.0), 0.5)
    assert film_only.landed_in_water() == [] and film_only._pending.size == 0


# --- the effect ---------------------------------------------------------------------------------------------

def _truck_scene(gl_ctx, enabled=True, strength=1.0, hour=12.0, film=None):
    from rain_core.scene import Scene
    from rain_core.settings import Settings
    from rain_core.spray import Spray
    from rain_core.vehicles import Autopilot

    s = Settings()
    s.rain.rate_mm_h, s.rain.wetness, s.rain.cracks, s.rain.puddles = 8.0, 1.0, 0.0, 0.0
    s.traffic.count, s.time_of_day.hour = 1, hour
    s.spray.enabled, s.spray.strength, s.spray.budget = enabled, strength, 3000
    effect = Spray(gl_ctx, settings=s, seed=1, film_depth_fn=film)
    scene = Scene(gl_ctx, (96, 54), s, seed=1, effects=[effect])
    v = 100 * KMH
    scene.ego.position[:] = [layout.LANE_CENTRES_X[0], 0.0, 600.0]
    scene.ego.speed_m_s = v
    truck = Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 580.0), 0.0, v, (0.75, 0.75, 0.72))
    scene.traffic.vehicles, scene.traffic.lanes, scene.traffic.desired_speeds_m_s = [truck], [0], [v]
    scene.autopilot = Autopilot(lane_index=0, target_speed_m_s=v, seed=1, wander_m=0.0)
    return scene, effect


def test_effect_draws_spray_behind_a_truck(gl_ctx):
    images, stats = [], []
    for enabled in (True, False):
        scene, effect = _truck_scene(gl_ctx, enabled=enabled, film=_puddle(0.0))
        for _ in range(12):
            scene.step(1 / 30)
            scene.render()
        images.append(scene.renderer.hdr_image())
        stats.append({s.name: s.ran for s in scene.renderer.stats})
        if enabled:
            assert effect.emitter.stats.mist_puffs > 0 and effect.emitter.alive_counts(scene.time_s)[0] > 0
            assert effect.ego_hydroplaning_risk == 0.0  # a wet film, no standing water
            assert len(effect.wheels) == 2 and effect.wheels[1].vehicle.spec.kind == "truck"
        scene.release()
    assert np.isfinite(images[0]).all()
    assert stats[0]["spray.transparent"] and not stats[1]["spray"]
    diff = np.abs(images[0] - images[1]).max(axis=-1)
    assert (diff > 1e-3).mean() > 0.01  # the spray shows


def test_effect_is_skipped_on_a_dry_road_and_reports_hydroplaning(gl_ctx):
    scene, effect = _truck_scene(gl_ctx, film=_puddle(0.0))
    scene.settings.rain.wetness = 0.0
    scene.settings.rain.rate_mm_h = 0.0
    scene.step(1 / 30)
    scene.render()
    assert not {s.name: s.ran for s in scene.renderer.stats}["spray"]
    scene.release()
    scene, effect = _truck_scene(gl_ctx, film=_puddle(8.0))
    scene.ego.speed_m_s = 110 * KMH
    scene.step(1 / 30)
    scene.render()
    assert effect.ego_hydroplaning_risk > 0.5
    assert np.all(effect.hydroplaning_risk(scene.traffic.vehicles[0]) < effect.hydroplaning_risk())
    scene.release()


def test_road_film_depth_is_the_roads_film():
    road = pytest.importorskip("rain_core.road")
    assert spray.WET_FILM_MM == road.WET_FILM_MM
    x, z = np.array([0.0, 3.0, 7.5, 1.75]), np.array([10.0, 20.0, 30.0, 500.0])
    wet = spray.road_film_depth_fn(SimpleNamespace(weather=WeatherState(wetness=0.5), settings=None, world=None))
    assert np.allclose(wet(x, z), [0.5 * spray.WET_FILM_MM, 0.5 * spray.WET_FILM_MM, 0.0, 0.5 * spray.WET_FILM_MM])
    flooded = WeatherState(wetness=1.0, cracks=1.0, puddles=1.0)
    fn = spray.road_film_depth_fn(SimpleNamespace(weather=flooded, settings=None, world=None))
    zz = np.arange(100.0, 1100.0, 0.5)
    assert np.allclose(fn(np.full_like(zz, 5.25), zz), road.film_depth_mm(5.25, zz, 1.0, 1.0, wetness=1.0))
    assert fn(np.full_like(zz, 5.25), zz).max() > 3.0  # standing water where the wheels run


def test_line_of_sight_optical_depth_of_one_puff():
    em = SprayEmitter(seed=0, budget=100)
    rec = np.zeros(1, spray.PARTICLE_DTYPE)
    rec["p0"], rec["v0"], rec["u"], rec["tau"] = (0.0, 1.0, 50.0), (0, 0, 0), (0, 0, 0), 0.8
    rec["life"], rec["sigma0"], rec["growth"], rec["area"] = 3.0, 0.5, 0.0, 0.2
    rec["kind"], rec["glint"] = spray.KIND_MIST, 0.25  # σ_h 0.5 m, σ_v capped at 0.25 m
    em.epoch = 0.0
    em.rings[1].push(rec, np.zeros(1), np.full(1, 3.0))
    through = spray.line_of_sight_optical_depth(em, 1.0, (0.0, 1.0, 60.0), (0.0, 1.0, 40.0))
    assert through == pytest.approx(0.2 / (2 * np.pi * 0.5 * 0.25), rel=1e-6)
    above = spray.line_of_sight_optical_depth(em, 1.0, (0.0, 1.25, 60.0), (0.0, 1.25, 40.0))
    beside = spray.line_of_sight_optical_depth(em, 1.0, (0.25, 1.0, 60.0), (0.25, 1.0, 40.0))
    assert above == pytest.approx(through * np.exp(-0.5), rel=1e-6)  # one σ_v up
    assert beside == pytest.approx(through * np.exp(-0.125), rel=1e-6)  # half a σ_h aside
    assert spray.line_of_sight_optical_depth(em, 1.0, (0.0, 1.0, 60.0), (0.0, 1.0, 55.0)) == 0.0  # not between
    assert spray.line_of_sight_optical_depth(em, 3.5, (0.0, 1.0, 60.0), (0.0, 1.0, 40.0)) == 0.0  # dead
