"""The emitter: parcels from the wheels' water, their mass, budget and landings (rain_core.effects.spray.emitter)."""

from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import layout
from rain_core.effects.spray import emitter as spray_emitter
from rain_core.effects.spray import parcels
from rain_core.effects.spray.emitter import SprayEmitter
from rain_core.effects.spray.flight import flight_position
from rain_core.effects.spray.probe import glsl_probe
from rain_core.effects.spray.water import KMH
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, Vehicle
from rain_core.weather import WeatherState, WindState


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


def test_droplets_never_pass_below_the_road(gl_ctx, shaders, kernel_path):
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
    pos_gl, _, _ = glsl_probe(gl_ctx, shaders, recs["p0"], recs["v0"], recs["tau"], recs["u"], recs["life"],
                          np.zeros(len(recs)))
    assert pos_gl[:, 1].min() >= 0.0
    assert t > 0.9


def test_emitted_parcels_carry_the_thrown_mass(kernel_path):
    em = SprayEmitter(seed=5, budget=3000, film_depth_fn=_puddle(3.0))
    _drive(em, _cars(70.0), 0.5, wetness=1.0)
    pending = sum(float(a.sum()) for a in em._acc.values())
    st = em.stats
    assert st.thrown_kg > 0 and st.emitted_kg > 0.95 * st.thrown_kg
    assert st.emitted_kg + pending == pytest.approx(st.thrown_kg, rel=1e-12)
    assert st.thrown_kg <= st.available_kg * (1 + 1e-12)
    assert st.fates.sum() == pytest.approx(st.emitted_kg, rel=1e-12)


def test_determinism(kernel_path):
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
    assert 0 < drops <= 500 and 0 < mist <= spray_emitter.MIN_MIST_CAPACITY
    em.set_budget(100)
    assert em.rings[0].capacity == 100 and em.alive_counts(t) == (0, 0)


def test_landings_in_standing_water_feed_the_ripples(kernel_path):
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


def test_line_of_sight_optical_depth_of_one_puff():
    em = SprayEmitter(seed=0, budget=100)
    rec = np.zeros(1, parcels.PARTICLE_DTYPE)
    rec["p0"], rec["v0"], rec["u"], rec["tau"] = (0.0, 1.0, 50.0), (0, 0, 0), (0, 0, 0), 0.8
    rec["life"], rec["sigma0"], rec["growth"], rec["area"] = 3.0, 0.5, 0.0, 0.2
    rec["kind"], rec["glint"] = parcels.KIND_MIST, 0.25  # σ_h 0.5 m, σ_v capped at 0.25 m
    em.epoch = 0.0
    em.rings[1].push(rec, np.zeros(1), np.full(1, 3.0))
    through = spray_emitter.line_of_sight_optical_depth(em, 1.0, (0.0, 1.0, 60.0), (0.0, 1.0, 40.0))
    assert through == pytest.approx(0.2 / (2 * np.pi * 0.5 * 0.25), rel=1e-6)
    above = spray_emitter.line_of_sight_optical_depth(em, 1.0, (0.0, 1.25, 60.0), (0.0, 1.25, 40.0))
    beside = spray_emitter.line_of_sight_optical_depth(em, 1.0, (0.25, 1.0, 60.0), (0.25, 1.0, 40.0))
    assert above == pytest.approx(through * np.exp(-0.5), rel=1e-6)  # one σ_v up
    assert beside == pytest.approx(through * np.exp(-0.125), rel=1e-6)  # half a σ_h aside
    assert spray_emitter.line_of_sight_optical_depth(em, 1.0, (0.0, 1.0, 60.0), (0.0, 1.0, 55.0)) == 0.0  # not between
    assert spray_emitter.line_of_sight_optical_depth(em, 3.5, (0.0, 1.0, 60.0), (0.0, 1.0, 40.0)) == 0.0  # dead
