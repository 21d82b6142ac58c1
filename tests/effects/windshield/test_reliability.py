"""Issue 18, the windshield: every bad input is a ValueError naming the field (checked where GlassInputs are made,
the simulation's boundary), and every valid input, however extreme, gives bounded work and a finite state."""

import math

import numpy as np
import pytest

from rain_core.effects.windshield import GlassInputs, WindshieldSim
from rain_core.effects.windshield.constants import MAX_ARRIVALS_PER_SUBSTEP
from rain_core.effects.windshield.reference import WindshieldSimReference


def _raises(field: str, **kwargs):
    with pytest.raises(ValueError, match=field):
        GlassInputs(**kwargs)


@pytest.mark.parametrize(
    "field, value",
    [
        ("wiper_interval_s", 0.0),
        ("wiper_interval_s", math.nan),
        ("drop_scale", math.nan),
        ("drop_scale", -1.0),
        ("drop_scale", 1e6),
        ("drop_budget", -5),
        ("drop_budget", 10**7),
        ("drop_budget", 2.5),
        ("drop_budget", True),
        ("blade_wear", math.nan),
        ("blade_wear", 1.5),
        ("rate_mm_h", -1.0),
        ("rate_mm_h", 501.0),
        ("rate_mm_h", math.inf),
        ("rate_mm_h", "1"),
        ("wiper_low_cpm", 0.0),
        ("wiper_high_cpm", 1e9),
        ("wiper_sensitivity", 0.0),
        ("wiper_mode", "turbo"),
        ("sheltered", "yes"),
    ],
)
def test_out_of_range_settings_name_the_field(field, value):
    _raises(field, **{field: value})


def test_the_message_names_the_field_and_its_range():
    with pytest.raises(ValueError) as err:
        GlassInputs(wiper_interval_s=0.0)
    assert "wiper_interval_s" in str(err.value) and "wipers.interval_s" in str(err.value)
    assert "[1, 30]" in str(err.value)


@pytest.mark.parametrize(
    "velocity",
    [(math.nan, 0.0, 0.0), (0.0, 0.0, math.inf), (0.0, 0.0, -1000 / 3.6), (1.0, 2.0), "fast"],
)
def test_bad_car_velocity_is_refused(velocity):
    _raises("car_velocity_m_s", car_velocity_m_s=velocity)


def test_1000_km_h_and_a_gale_of_a_million_m_s_are_refused():
    with pytest.raises(ValueError, match="car_velocity_m_s"):
        GlassInputs.for_speed(1000.0, 4.0)
    _raises("wind_m_s", wind_m_s=(0.0, 0.0, 1e6))
    _raises("wind_m_s", wind_m_s=(math.nan, 0.0, 0.0))


@pytest.mark.parametrize(
    "rotation",
    [np.zeros((3, 3)), np.full((3, 3), math.nan), 2.0 * np.eye(3), np.diag([1.0, 1.0, -1.0]), np.eye(4)],
)
def test_a_rotation_that_is_not_one_is_refused(rotation):
    _raises("car_rotation", car_rotation=rotation)


def test_inputs_are_frozen_once_checked():
    inputs = GlassInputs.for_speed(50.0, 4.0)
    with pytest.raises(AttributeError):
        inputs.blade_wear = math.nan
    with pytest.raises(ValueError):
        inputs.car_velocity_m_s[2] = math.nan  # read-only: what was checked stays what the step sees


@pytest.mark.parametrize("sim_class", [WindshieldSim, WindshieldSimReference])
def test_step_refuses_a_bad_dt_or_something_else_than_inputs(sim_class):
    sim = sim_class(seed=1)
    inputs = GlassInputs.for_speed(50.0, 4.0)
    for dt in (math.nan, -1.0, math.inf, "1"):
        with pytest.raises(ValueError, match="dt_s"):
            sim.step(dt, inputs)
    with pytest.raises(ValueError, match="GlassInputs"):
        sim.step(1 / 30, {"rate_mm_h": 4.0})


def _finite_and_bounded(sim: WindshieldSim, budget: int) -> None:
    assert sim.count <= budget
    for name in ("pos", "vel", "mass", "trail"):
        assert np.all(np.isfinite(getattr(sim, name))), name
    assert np.all(np.isfinite(sim.film)) and np.all(sim.film >= 0.0)
    assert np.all(np.isfinite(sim.beads)) and np.all(sim.beads >= 0.0)
    assert np.all(sim.mass > 0.0)
    assert sim.glass.contains(sim.pos).all()
    assert abs(sim.balance_error_kg()) <= 1e-9 * max(sim.arrived, 1e-12)


def test_the_extreme_valid_storm_that_exhausted_memory_now_does_bounded_work():
    """200 km/h, 500 mm/h, drop_scale 4, a 40 m/s headwind gusting to 80: the merge step used to ask for
    gigabytes. Now every step is bounded: arrivals by MAX_ARRIVALS_PER_SUBSTEP, drops by the budget, merge work
    by the PairFinder's caps."""
    sim = WindshieldSim(seed=3)
    budget = 50_000
    storm = GlassInputs.for_speed(
        200.0, 500.0, drop_scale=4.0, drop_budget=budget, wind_m_s=np.array([0.0, 0.0, 80.0]), wiper_mode="high"
    )
    rate = sim.arrival_rate_per_s(storm)[0]
    assert rate * (1 / 30) > MAX_ARRIVALS_PER_SUBSTEP  # the cap is what bounds this storm
    for _ in range(6):
        sim.step(0.25, storm)  # the longest frame: 8 sub-steps
        _finite_and_bounded(sim, budget)
    assert sim.arrival_count > 0 and sim.count > 1000


@pytest.mark.parametrize("speed_kmh, wind_z", [(200.0, 40.0), (-30.0, -40.0), (0.0, 80.0)])
def test_stress_huge_dt_and_extreme_valid_settings_stay_finite_and_bounded(speed_kmh, wind_z):
    sim = WindshieldSim(seed=4)
    budget = 3000
    for k in range(40):
        inputs = GlassInputs.for_speed(
            speed_kmh * (1.0 if k % 7 else 0.3),
            (500.0, 0.0, 80.0)[k % 3],
            drop_scale=4.0,
            drop_budget=budget,
            wind_m_s=np.array([30.0 * math.sin(k), 0.0, wind_z]),
            wiper_mode=("high", "auto", "off", "intermittent", "low")[k % 5],
            wiper_interval_s=1.0,
            blade_wear=1.0,
            sheltered=k % 11 == 5,
        )
        sim.step((1e308, 0.25, 5e-324, 1 / 30)[k % 4], inputs)  # dt is clamped to a frame of 0.25 s at most
        _finite_and_bounded(sim, budget)
    if wind_z > 0:  # (reversing before a following gale, the rain comes from behind: a dry glass)
        assert sim.arrived > 0 and sim.wiped > 0


def test_a_zero_budget_keeps_every_drop_in_the_film():
    sim = WindshieldSim(seed=5)
    inputs = GlassInputs.for_speed(120.0, 200.0, drop_budget=0, drop_scale=4.0)
    for _ in range(10):
        sim.step(0.25, inputs)
    assert sim.count == 0 and sim.film.sum() > 0.0
    _finite_and_bounded(sim, 0)
