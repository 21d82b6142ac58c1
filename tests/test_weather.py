"""rain_core.weather: calibration, exact integration for any dt, bounds, drying order, pins and wind."""

import dataclasses
import math

import numpy as np
import pytest

from rain_core.settings import Settings, set_value
from rain_core.weather import DRY_PER_S, FILL_PER_S, LEVELS, R_WET_MIN_MM_H, Weather, fill_rates_per_s


def _levels(w: Weather):
    s = w.state
    return np.array([s.wetness, s.cracks, s.puddles])


def test_starts_dry():
    s = Weather().state
    assert (s.wetness, s.cracks, s.puddles, s.rate_mm_h, s.time_s) == (0.0, 0.0, 0.0, 0.0, 0.0)
    assert s.time_since_rain_s == math.inf and s.category == "none"


def test_fill_rates_calibrated_and_continuous_in_rate():
    np.testing.assert_allclose(fill_rates_per_s(0.5), [FILL_PER_S[n][0] for n in LEVELS])
    np.testing.assert_allclose(fill_rates_per_s(2.0), [FILL_PER_S[n][1] for n in LEVELS])
    np.testing.assert_allclose(fill_rates_per_s(8.0), [FILL_PER_S[n][2] for n in LEVELS])
    np.testing.assert_allclose(fill_rates_per_s(200.0), fill_rates_per_s(8.0))
    assert np.all(fill_rates_per_s(np.array([0.0, R_WET_MIN_MM_H])) == 0.0)
    r = np.geomspace(0.01, 500, 20_001)
    f = fill_rates_per_s(r)
    assert f.shape == (r.size, 3)
    assert np.all(np.diff(f, axis=0) >= 0)  # more rain never wets slower
    assert np.max(np.abs(np.diff(f, axis=0))) < 1e-3  # no buckets: tiny steps in R, tiny steps in rate


def test_linear_ramp_then_clamp():
    w = Weather()
    w.step(0.5, 2.0)
    np.testing.assert_allclose(_levels(w), 0.5 * np.array(FILL_PER_S["wetness"][1:2] + FILL_PER_S["cracks"][1:2]
                                                         + FILL_PER_S["puddles"][1:2]))
    w.step(100.0, 2.0)
    assert np.all(_levels(w) == 1.0)
    assert w.state.time_since_rain_s == 0.0


# A weather script: (duration s, rate mm/h). It crosses every drying onset and a fresh shower.
SCRIPT = [(3.0, 8.0), (4.0, 0.0), (2.0, 0.3), (12.0, 0.0), (2.5, 2.0), (40.0, 0.01)]


def _run(script, dt, **kw):
    w = Weather(**kw)
    for duration, rate in script:
        n = round(duration / dt)
        for _ in range(n):
            w.step(dt, rate)
    return w


@pytest.mark.parametrize("kw", [{}, {"time_scale": 3.0}, {"drying_delay_s": 0.0, "drying_stage_gap_s": 0.0}])
def test_one_big_step_equals_many_small_steps(kw):
    big = _run(SCRIPT, 0.5, **kw)  # every segment is a multiple of 0.5 s
    for dt in (0.1, 0.01):
        small = _run(SCRIPT, dt, **kw)
        np.testing.assert_allclose(_levels(small), _levels(big), atol=1e-9, rtol=0)
        assert small.state.time_since_rain_s == pytest.approx(big.state.time_since_rain_s, abs=1e-9)
    one = Weather(**kw)
    for duration, rate in SCRIPT:
        one.step(duration, rate)
    np.testing.assert_allclose(_levels(one), _levels(big), atol=1e-9, rtol=0)
    assert one.state.wind.velocity_m_s == pytest.approx(big.state.wind.velocity_m_s, abs=1e-9)


def test_ten_second_step_equals_hundred_tenths_with_random_splits():
    rng = np.random.default_rng(0)
    for _ in range(20):
        start = rng.uniform(0, 1, 3)
        rate = float(rng.choice([0.0, 0.02, 0.7, 3.0, 30.0]))
        since = float(rng.choice([0.0, 4.0, 12.0, math.inf]))
        a, b = Weather(), Weather()
        for w in (a, b):
            w.reset(*start, time_since_rain_s=since)
        a.step(10.0, rate)
        for _ in range(100):
            b.step(0.1, rate)
        np.testing.assert_allclose(_levels(a), _levels(b), atol=1e-9, rtol=0)


@pytest.mark.parametrize("dt", [1e-6, 1e-3, 0.1, 1.0, 100.0, 1e4, 1e6])
def test_levels_stay_in_unit_interval_for_any_dt(dt):
    w = Weather(time_scale=1000.0, seed=1, wind_speed_m_s=30.0, gustiness=1.0)
    for rate in (500.0, 0.0, 0.04, 80.0, 0.0, 1.0):
        for _ in range(3):
            s = w.step(dt, rate)
            lv = np.array([s.wetness, s.cracks, s.puddles])
            assert np.all((lv >= 0) & (lv <= 1))
            assert math.isfinite(s.time_s) and all(math.isfinite(c) for c in s.wind.velocity_m_s)


def test_drying_waits_then_film_first_cracks_next_puddles_last():
    w = Weather(drying_delay_s=10.0, drying_stage_gap_s=5.0)
    w.step(60.0, 20.0)
    assert np.all(_levels(w) == 1.0)
    w.step(10.0, 0.0)
    assert np.all(_levels(w) == 1.0)  # still within the delay
    emptied = {}
    for k in range(1, 100_000):
        w.step(0.01, 0.0)
        for name in LEVELS:
            if name not in emptied and getattr(w.state, name) == 0.0:
                emptied[name] = k * 0.01
        if len(emptied) == 3:
            break
    assert emptied["wetness"] < emptied["cracks"] < emptied["puddles"]
    # Each empties at onset + 1/rate after the rain.
    onsets = w.drying_onsets_s()
    for name in LEVELS:
        assert emptied[name] + 10.0 == pytest.approx(onsets[name] + 1 / DRY_PER_S[name], abs=0.011)


def test_faint_drizzle_does_not_wet_and_lets_the_road_dry():
    w = Weather(drying_delay_s=0.0, drying_stage_gap_s=0.0)
    w.step(1.0, 0.02)
    assert np.all(_levels(w) == 0.0)
    w.step(30.0, 8.0)
    w.step(1.0, 0.02)
    assert w.state.wetness < 1.0


def test_time_scale_scales_the_levels_not_the_wind():
    a, b = Weather(time_scale=2.0, wind_speed_m_s=5, gustiness=0.8), Weather(wind_speed_m_s=5, gustiness=0.8)
    a.step(0.4, 1.0)
    b.step(0.8, 1.0)
    np.testing.assert_allclose(_levels(a), _levels(b))
    assert a.state.wind == Weather(wind_speed_m_s=5, gustiness=0.8).wind_at(0.4)
    frozen = Weather(time_scale=0.0)
    frozen.step(10.0, 50.0)
    assert np.all(_levels(frozen) == 0.0)


def test_pin_and_unpin():
    w = Weather()
    w.pin("puddles", 0.7)
    w.step(100.0, 50.0)
    s = w.state
    assert s.puddles == 0.7 and s.wetness == 1.0 and s.pinned == ("puddles",)
    assert w.pinned == {"puddles": 0.7}
    w.unpin("puddles")
    w.step(0.1, 8.0)
    assert w.state.puddles == pytest.approx(0.7 + 0.1 * FILL_PER_S["puddles"][2])
    with pytest.raises(ValueError, match="level"):
        w.pin("fog", 0.5)
    with pytest.raises(ValueError, match="wetness"):
        w.pin("wetness", 1.5)


def test_paused_levels_hold_still():
    w = Weather()
    w.paused = True
    w.step(5.0, 10.0)
    assert np.all(_levels(w) == 0.0) and w.state.rate_mm_h == 10.0 and w.state.time_s == 5.0


def test_state_is_frozen_and_copyable():
    s = Weather().step(1.0, 3.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.wetness = 1.0
    assert dataclasses.replace(s, wetness=0.5).wetness == 0.5 and s.wetness != 0.5
    assert s.extinction_per_km == pytest.approx(0.312 * 3.0**0.67)


def test_wind_direction_gusts_and_determinism():
    calm = Weather(wind_speed_m_s=4.0, wind_direction_rad=0.0)
    assert calm.state.wind.velocity_m_s == pytest.approx((0.0, 0.0, -4.0))  # towards −Z
    east = Weather(wind_speed_m_s=4.0, wind_direction_rad=math.pi / 2)
    assert east.state.wind.velocity_m_s == pytest.approx((4.0, 0.0, 0.0), abs=1e-12)
    t = np.linspace(0, 300, 30_001)
    a = Weather(seed=5, wind_speed_m_s=10.0, gustiness=1.0)
    va = np.array([a.wind_at(x).velocity_m_s for x in t])
    vb = np.array([Weather(seed=5, wind_speed_m_s=10.0, gustiness=1.0).wind_at(x).velocity_m_s for x in t[:50]])
    vc = np.array([Weather(seed=6, wind_speed_m_s=10.0, gustiness=1.0).wind_at(x).velocity_m_s for x in t[:50]])
    assert np.array_equal(va[:50], vb) and not np.allclose(va[:50], vc)
    speed = np.linalg.norm(va, axis=1)
    assert np.all(va[:, 1] == 0) and np.all(speed >= 0) and np.all(speed <= 20.0)
    assert speed.std() > 0.5  # it does gust
    # Smooth: the acceleration stays bounded (a jump would show as a huge difference over 0.01 s).
    accel = np.diff(va, axis=0) / np.diff(t)[:, None]
    assert np.max(np.abs(np.diff(accel, axis=0))) < 0.5


@pytest.mark.parametrize("bad", [math.nan, -1.0, math.inf, True])
def test_bad_inputs_raise(bad):
    w = Weather()
    with pytest.raises(ValueError, match="dt_s"):
        w.step(bad, 1.0)
    with pytest.raises(ValueError, match="rate_mm_h"):
        w.step(0.1, bad)
    with pytest.raises(ValueError, match="time_scale"):
        w.time_scale = bad
    with pytest.raises(ValueError, match="gustiness"):
        w.set_wind(1.0, 0.0, bad if bad is not True else 2.0)
    with pytest.raises(ValueError, match="rate_mm_h"):
        w.step(0.1, 501.0)
    with pytest.raises(ValueError, match="seed"):
        Weather(seed=-1)


def test_configured_from_settings():
    s = Settings()
    set_value(s, "rain.time_scale", 4.0)
    set_value(s, "rain.cracks", 0.25)
    set_value(s, "wind.speed_m_s", 6.0)
    set_value(s, "wind.direction_deg", 180.0)
    set_value(s, "wind.gustiness", 0.0)
    w = Weather.from_settings(s)
    assert w.time_scale == 4.0 and w.pinned == {"cracks": 0.25}
    assert w.state.wind.velocity_m_s == pytest.approx((0.0, 0.0, 6.0), abs=1e-12)  # towards +Z
    set_value(s, "rain.cracks", None)
    set_value(s, "rain.auto_weather", False)
    w.apply_settings(s)
    assert w.pinned == {} and w.paused


def test_settings_applied_again_after_a_direct_change():
    """apply_settings skips unchanged settings, but not what a direct call changed since (pins, wind, delays)."""
    s = Settings()
    set_value(s, "rain.cracks", 0.25)
    w = Weather.from_settings(s)
    w.pin("cracks", 0.75)
    w.unpin("puddles")
    w.pin("puddles", 0.5)
    w.set_wind(9.0, 1.0, 1.0)
    w.time_scale = 3.0
    w.apply_settings(s)
    assert w.pinned == {"cracks": 0.25} and w.time_scale == s.rain.time_scale
    assert w.state.wind.speed_m_s == s.wind.speed_m_s
    w.paused = True
    w.apply_settings(s)  # nothing changed: the pause still follows rain.auto_weather
    assert not w.paused


@pytest.mark.parametrize("seed", [0, 1, 7, 123])
def test_gust_pair_is_each_signals_own_value(seed):
    """Both gusts in one pass give each signal's own bits (the wind evaluates them together)."""
    w = Weather(seed=seed)
    times = np.concatenate([np.linspace(0.0, 600.0, 701), [-3.5, 1e9 + 0.25, 1e300]])
    for t in times.tolist():
        assert w._gusts(t) == (w._gust_speed(t), w._gust_direction(t))
