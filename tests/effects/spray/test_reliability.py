"""Bad and extreme input to the spray (issue 18): a clear ValueError naming the field at the boundary, finite
parcels for any finite input accepted, and bounded work per step whatever the input."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import layout
from rain_core.effects.spray import emitter as spray_emitter
from rain_core.effects.spray.emitter import MAX_BUDGET, SprayEmitter
from rain_core.effects.spray.water import KMH, allocate_water, hydroplaning_risk
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, Vehicle
from rain_core.weather import WeatherState, WindState


def _frame(t, vehicles, wind=(0.0, 0.0, 0.0), wetness=1.0):
    weather = WeatherState(rate_mm_h=8.0, wetness=wetness, wind=WindState(velocity_m_s=tuple(wind)))
    return SimpleNamespace(time_s=t, dt_s=1 / 30, vehicles=vehicles, ego=vehicles[0] if vehicles else None,
                           weather=weather, settings=None, world=None)


def _depth(mm):
    return lambda x, z: np.full(np.broadcast(np.asarray(x), np.asarray(z)).shape, mm)


def _cars(kmh=100.0):
    return [Vehicle(CAR_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 500.0), 0.0, kmh * KMH),
            Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[1], 0.0, 470.0), 0.0, kmh * KMH)]


def _finite_state(em):
    for ring in em.rings:
        written = ring.death > -np.inf
        for name in ring.data.dtype.names:
            assert np.isfinite(ring.data[name][written]).all(), name
        assert np.isfinite(ring.birth[written]).all() and np.isfinite(ring.death[written]).all()
    assert np.isfinite(em.landed_impacts()).all() and np.isfinite(em._pending).all()


@pytest.mark.parametrize("reference", [False, True])
@pytest.mark.parametrize("wind", [(math.nan, 0.0, 0.0), (0.0, math.inf, 0.0), (0.0, 0.0, -math.inf),
                                  (2000.0, 0.0, 0.0)])
def test_a_bad_wind_is_refused_by_name(reference, wind):
    em = SprayEmitter(seed=1, budget=500, film_depth_fn=_depth(3.0), reference=reference)
    em.emit(_frame(0.0, _cars()))
    with pytest.raises(ValueError, match="wind"):
        em.emit(_frame(1 / 30, _cars(), wind=wind))


@pytest.mark.parametrize("field, value", [("speed_m_s", math.nan), ("speed_m_s", math.inf), ("speed_m_s", 1e6),
                                          ("yaw", math.nan), ("yaw_rate_rad_s", math.inf),
                                          ("position", (math.nan, 0.0, 500.0)), ("position", (1.0, 0.0, math.inf)),
                                          ("position", (1.0, 0.0, 1e300)), ("position", (1.0, -1e12, 5.0))])
def test_a_bad_vehicle_state_is_refused_by_name(field, value):
    cars = _cars()
    setattr(cars[1], field, np.array(value) if isinstance(value, tuple) else value)
    em = SprayEmitter(seed=1, budget=500, film_depth_fn=_depth(3.0))
    with pytest.raises(ValueError, match=rf"vehicles\[1\]\.{field}"):
        em.emit(_frame(0.0, cars))
    with pytest.raises(ValueError, match=field):
        em.observe(_frame(1.0, cars))  # the effect's observe() is checked the same way


@pytest.mark.parametrize("time_s", [math.nan, math.inf, -math.inf])
def test_a_bad_time_is_refused_by_name(time_s):
    em = SprayEmitter(seed=1, budget=500)
    with pytest.raises(ValueError, match="time_s"):
        em.emit(_frame(time_s, _cars()))


@pytest.mark.parametrize("budget", [-5, MAX_BUDGET + 1, 10**7, math.nan, math.inf, "100"])
def test_a_bad_budget_is_refused_by_name(budget):
    with pytest.raises(ValueError, match="budget"):
        SprayEmitter(budget=budget)
    em = SprayEmitter(budget=100)
    with pytest.raises(ValueError, match="budget"):
        em.set_budget(budget)
    assert em.budget == 100 and em.rings[0].capacity == 100


@pytest.mark.parametrize("strength", [-1.0, math.nan, math.inf, 1e9])
def test_a_bad_strength_is_refused_by_name(strength):
    em = SprayEmitter(budget=100)
    with pytest.raises(ValueError, match="strength"):
        em.strength = strength
    assert em.strength == 1.0


def test_public_water_functions_refuse_non_finite_input():
    with pytest.raises(ValueError, match="speed_m_s"):
        hydroplaning_risk(math.nan, 0.003)
    with pytest.raises(ValueError, match="film_depth_m"):
        hydroplaning_risk(20.0, -0.001)
    with pytest.raises(ValueError, match="tyre_pressure_kpa"):
        hydroplaning_risk(20.0, 0.003, 0.0)
    with pytest.raises(ValueError, match="speed_m_s"):
        allocate_water(math.nan, 0.2, 0.003)
    assert np.isfinite(hydroplaning_risk(-30.0, 0.004))  # reversing is valid


@pytest.mark.parametrize("reference", [False, True])
def test_a_bad_film_override_counts_as_dry_or_capped(reference, kernel_path):
    """A film-depth override that returns NaN, inf or negative depths (a user's function) gives finite parcels."""
    values = iter([math.nan, math.inf, -5.0, 1e30])
    em = SprayEmitter(seed=2, budget=800, reference=reference,
                      film_depth_fn=lambda x, z: np.full(np.shape(x), next(values, 3.0)))
    cars = _cars()
    for i in range(8):
        em.emit(_frame(i / 30, cars))
    _finite_state(em)
    assert em.stats.parcels > 0


@pytest.mark.parametrize("reference", [False, True])
def test_the_work_per_step_is_bounded_whatever_the_interval_and_rate(reference, kernel_path):
    """However long the step and however short the lives, one step spawns at most about a ring's worth."""
    em = SprayEmitter(seed=3, budget=300, film_depth_fn=_depth(9.0), reference=reference)
    em.strength = spray_emitter.MAX_STRENGTH
    cars = [Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[i % 4], 0.0, 400.0 + 15 * i), 0.0, 300 * KMH)
            for i in range(12)]
    em.emit(_frame(0.0, cars))
    for t in (1.0, 5.0, 5.0 + 1e-6, 60.0):
        em._life_q90 = [1e-6, 1e-6]  # as short as lives get: the rate asks for capacity / 0.05 s
        em.emit(_frame(t, cars))
        cells = 4 * len(cars) * 6  # rounding up in each (vehicle, wheel, bucket) cell adds at most one each
        assert em.stats.last_parcels <= em.rings[0].capacity + cells
        assert em.stats.last_mist <= em.rings[1].capacity + cells
    _finite_state(em)


def test_huge_time_jumps_and_long_runs_keep_float32_births_precise(kernel_path):
    """The effect clock restarts when it passes REBASE_S, so births stay small and finite in float32 however far
    the time goes (a jump of 1e300 s included); the landings move with it."""
    em = SprayEmitter(seed=4, budget=600, film_depth_fn=_depth(4.0))
    cars = _cars()
    t = 0.0
    for t in np.arange(0.0, 0.5, 1 / 30):
        em.emit(_frame(t, cars))
    for jump in (spray_emitter.REBASE_S + 3.0, 1e9, 1e300):
        t0 = jump
        for k in range(6):
            for v in cars:
                v.position = v.position + v.forward() * v.speed_m_s / 30
            em.emit(_frame(t0 + k / 30, cars))
        now = em.clock(t0 + 5 / 30)
        assert 0.0 <= now <= spray_emitter.REBASE_S
        alive = em.rings[0].death > now
        assert alive.any() and np.all(np.abs(em.rings[0].data["birth"][alive]) < spray_emitter.REBASE_S)
        assert em.alive_until() > now
        _finite_state(em)


@pytest.mark.parametrize("reference", [False, True])
def test_random_valid_inputs_give_finite_bounded_parcels(reference, kernel_path):
    """Random valid frames (speeds from reversing to 300 km/h, yaw rates, winds to 40 m/s, depths 0–10 mm, steps
    0–1 s, strengths 0–4) → finite parcels, no more alive than the budget."""
    rng = np.random.default_rng(18)
    for case in range(6):
        budget = int(rng.integers(0, 3000))
        em = SprayEmitter(seed=case, budget=budget, film_depth_fn=_depth(float(rng.uniform(0.0, 10.0))),
                          reference=reference)
        em.strength = float(rng.uniform(0.0, 4.0))
        cars = []
        for i in range(int(rng.integers(0, 5))):
            at = (float(rng.uniform(-6, 6)), 0.0, float(rng.uniform(0, 1200)))
            v = Vehicle(CAR_SPEC if i % 2 else TRUCK_SPEC, at, float(rng.uniform(-math.pi, math.pi)),
                        float(rng.uniform(-6.0, 85.0)))
            v.yaw_rate_rad_s = float(rng.uniform(-0.5, 0.5))
            cars.append(v)
        t = float(rng.uniform(0.0, 100.0))
        for _ in range(8):
            t += float(rng.choice([0.0, 1 / 60, 1 / 30, 0.2, 1.0]))
            wind = rng.uniform(-40.0, 40.0, 3) * [1.0, 0.1, 1.0]
            em.emit(_frame(t, cars, wind=wind, wetness=float(rng.uniform(0.0, 1.0))))
        _finite_state(em)
        drops, mist = em.alive_counts(t)
        assert drops <= em.rings[0].capacity and mist <= em.rings[1].capacity


@pytest.mark.parametrize("args, field", [
    ((1.0, -1.0), "launch_speed_m_s"),  # issue 18: a negative speed was accepted
    ((0.0, 5.0), "d_mm"),
    ((float("nan"), 5.0), "d_mm"),
    ((1.0, float("inf")), "launch_speed_m_s"),
    ((1.0, "5"), "launch_speed_m_s"),
    ((1.0, 5.0, -4.0), "terminal_m_s"),
])
def test_drag_time_constant_refuses_invalid_arguments(args, field):
    from rain_core.effects.spray.flight import drag_time_constant

    with pytest.raises(ValueError, match=field):
        drag_time_constant(*args)


def test_drag_time_constant_checked_equals_unchecked():
    from rain_core.effects.spray.flight import drag_time_constant, drag_time_constant_unchecked

    d = np.array([0.2, 1.0, 3.0])
    s = np.array([0.0, 5.0, 30.0])
    np.testing.assert_array_equal(drag_time_constant(d, s), drag_time_constant_unchecked(d, s))
    assert np.all(np.isfinite(drag_time_constant(d, s))) and np.all(drag_time_constant(d, s) > 0)
