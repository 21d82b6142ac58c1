"""Property-based tests of rain_core.weather (issue 18): any sequence of valid steps keeps the state finite and in
range; every invalid argument raises ValueError naming it. Also the audit's cases: ``step(1e308)`` with gusts
gave a NaN wind, ``step(dt="1")`` was accepted.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from rain_core.physics import R_MAX_MM_H
from rain_core.weather import LEVELS, MAX_STEP_S, Weather

F_MAX = float(np.finfo(np.float64).max)

rates = st.floats(0.0, R_MAX_MM_H)
dts = st.floats(0.0, MAX_STEP_S) | st.sampled_from([0.0, 5e-324, 1e-300, 1 / 60, MAX_STEP_S])
steps = st.lists(st.tuples(dts, rates), min_size=1, max_size=12)
weathers = st.fixed_dictionaries({
    "seed": st.integers(0, 2**63),
    "time_scale": st.floats(0.0, 1e4),
    "drying_delay_s": st.floats(0.0, F_MAX),
    "drying_stage_gap_s": st.floats(0.0, 1e300),
    "wind_speed_m_s": st.floats(0.0, 100.0),
    "wind_direction_rad": st.floats(-F_MAX, F_MAX),
    "gustiness": st.floats(0.0, 1.0),
})
TEXT = st.text(max_size=4) | st.sampled_from(["1", "0.5", "nan", "1e3"])
NOT_NUMBERS = TEXT | st.none() | st.booleans() | st.lists(st.floats(0, 1), min_size=1, max_size=2)
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])


def assert_valid(state, weather: Weather) -> None:
    for name in LEVELS:
        assert 0.0 <= getattr(state, name) <= 1.0, (name, state)
    assert math.isfinite(state.time_s) and state.time_s >= 0
    assert state.time_since_rain_s >= 0 and not math.isnan(state.time_since_rain_s)
    v = state.wind.velocity_m_s
    assert all(math.isfinite(c) for c in v) and v[1] == 0.0
    # Gusts swing the speed by at most ±100 % of the mean (gustiness ≤ 1).
    assert math.hypot(*v) <= 2.0 * weather._wind_speed + 1e-9
    assert math.isfinite(state.extinction_per_km) and state.extinction_per_km >= 0


@given(kwargs=weathers, script=steps)
@example(kwargs={"seed": 0, "time_scale": 1e4, "drying_delay_s": 0.0, "drying_stage_gap_s": 0.0,
                 "wind_speed_m_s": 100.0, "wind_direction_rad": 0.0, "gustiness": 1.0},
         script=[(MAX_STEP_S, 500.0)] * 12)
def test_any_valid_steps_keep_the_state_finite_and_in_range(kwargs, script):
    w = Weather(**kwargs)
    for dt, rate in script:
        assert_valid(w.step(dt, rate), w)
    assert w.time_s == pytest.approx(sum(dt for dt, _ in script), rel=1e-12)


@given(t=st.floats(-F_MAX, F_MAX), gust=st.floats(0.0, 1.0), seed=st.integers(0, 2**32))
@example(t=1e308, gust=1.0, seed=0)
@example(t=F_MAX, gust=1.0, seed=0)
def test_wind_is_finite_at_any_finite_time(t, gust, seed):
    w = Weather(seed=seed, wind_speed_m_s=40.0, gustiness=gust)
    wind = w.wind_at(t)
    assert all(math.isfinite(c) for c in wind.velocity_m_s)
    assert 0.0 <= wind.gust_speed_m_s <= 80.0 + 1e-9


def test_gusts_do_not_change_over_long_times():
    """The period reduction is exact: the wind at t equals sin(ω·t + φ) evaluated directly, to rounding."""
    w = Weather(seed=3, wind_speed_m_s=10.0, gustiness=1.0)
    g = w._gust_speed
    for t in (0.0, 0.7, 12.5, 3600.0, 86400.0 * 7):
        direct = float(np.dot(g.amp, np.sin(g.omega * t + g.phase)))
        assert g(t) == pytest.approx(direct, abs=1e-9 * max(1.0, t))


def test_the_audits_cases():
    w = Weather(wind_speed_m_s=40.0, gustiness=1.0)
    with pytest.raises(ValueError, match="dt_s"):
        w.step(1e308, 5.0)
    with pytest.raises(ValueError, match="dt_s"):
        w.step("1", 5.0)
    with pytest.raises(ValueError, match="rate_mm_h"):
        w.step(0.1, -1.0)
    state = w.step(MAX_STEP_S, 5.0)
    assert all(math.isfinite(c) for c in state.wind.velocity_m_s)


@given(dt=NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(MAX_STEP_S, exclude_min=True))
def test_step_refuses_bad_dt(dt):
    w = Weather()
    with pytest.raises(ValueError, match="dt_s"):
        w.step(dt, 1.0)
    assert w.time_s == 0.0  # nothing happened


@given(rate=NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(R_MAX_MM_H, exclude_min=True))
def test_step_refuses_bad_rates(rate):
    w = Weather()
    with pytest.raises(ValueError, match="rate_mm_h"):
        w.step(0.1, rate)
    assert w.time_s == 0.0


BAD_ARGS = {
    "time_scale": NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(1e4, exclude_min=True),
    "drying_delay_s": NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300),
    "drying_stage_gap_s": NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300),
    "wind_speed_m_s": NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(100.0, exclude_min=True),
    "wind_direction_rad": NON_FINITE | NOT_NUMBERS,
    "gustiness": NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(1.0, exclude_min=True),
    "seed": NOT_NUMBERS | st.integers(max_value=-1) | st.floats(0.0, 10.0),
}


@pytest.mark.parametrize("name", sorted(BAD_ARGS))
@given(data=st.data())
def test_constructor_refuses_bad_arguments_naming_them(name, data):
    value = data.draw(BAD_ARGS[name], label=name)  # (a bool seed is an int to Python: refused explicitly)
    with pytest.raises(ValueError, match=name):
        Weather(**{name: value})


@pytest.mark.parametrize("name", ["wind_speed_m_s", "wind_direction_rad", "gustiness"])
@given(data=st.data())
def test_set_wind_refuses_bad_arguments_and_keeps_the_old_wind(name, data):
    w = Weather(wind_speed_m_s=5.0, wind_direction_rad=1.0, gustiness=0.5)
    before = w.wind_at(3.0)
    args = {"speed_m_s": 5.0, "direction_rad": 1.0, "gustiness": 0.5}
    key = {"wind_speed_m_s": "speed_m_s", "wind_direction_rad": "direction_rad", "gustiness": "gustiness"}[name]
    args[key] = data.draw(BAD_ARGS[name], label=name)
    with pytest.raises(ValueError, match=name):
        w.set_wind(**args)
    assert w.wind_at(3.0) == before  # validated before anything changed


@pytest.mark.parametrize("level", LEVELS)
@given(value=NON_FINITE | NOT_NUMBERS | st.floats(max_value=-1e-300) | st.floats(1.0, exclude_min=True))
def test_pin_and_reset_refuse_bad_levels(level, value):
    w = Weather()
    with pytest.raises(ValueError, match=level):
        w.pin(level, value)
    with pytest.raises(ValueError, match=level):
        w.reset(**{level: value})
    assert level not in w.pinned


@given(value=st.sampled_from([math.nan, -math.inf, -1.0, "3", None]))
def test_reset_refuses_a_bad_drying_clock(value):
    with pytest.raises(ValueError, match="time_since_rain_s"):
        Weather().reset(time_since_rain_s=value)


def test_wind_at_refuses_non_finite_or_text_times():
    w = Weather()
    for t in (math.nan, math.inf, "1", None):
        with pytest.raises(ValueError, match="time_s"):
            w.wind_at(t)
