"""The public Weather spec (issue 15): physical units mapped onto the settings, the settings' errors. GL-free."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from rain_core.session.weather import FIELD_PATHS, FOG_PATH, Weather, fog_visibility_to_haze_per_km
from rain_core.settings import Settings, SettingsError, get_value


def test_every_field_maps_onto_its_settings_path():
    w = Weather(rain_mm_h=8.0, hour=18.5, wind_m_s=3.0, wind_direction_deg=45.0, gustiness=0.7,
                fog_visibility_m=500.0, wetness=1.0, cracks=0.5, puddles=0.25, puddle_amount=0.8)
    s = Settings()
    w.apply(s)
    for name, path in FIELD_PATHS.items():
        assert get_value(s, path) == getattr(w, name), path
    # 5 % contrast: visibility × β = −ln 0.05 ≈ 2.996 (the haze alone, in 1/km)
    assert get_value(s, FOG_PATH) == pytest.approx(-math.log(0.05) / 0.5)
    back = Weather.from_settings(s)
    assert back == w.replace(fog_visibility_m=back.fog_visibility_m)
    assert back.fog_visibility_m == pytest.approx(500.0)


def test_unset_fields_leave_the_settings_alone():
    s = Settings()
    before = s.to_dict()
    Weather().apply(s)
    assert s.to_dict() == before
    Weather(rain_mm_h=0.0).apply(s)
    assert s.rain.rate_mm_h == 0.0 and s.time_of_day.hour == before["time_of_day"]["hour"]
    assert Weather.from_settings(Settings()).wetness is None  # an unpinned level reads as None


def test_no_fog_is_infinite_visibility():
    s = Settings()
    Weather(fog_visibility_m=500.0).apply(s)
    Weather(fog_visibility_m=math.inf).apply(s)
    assert s.atmosphere.haze_per_km == 0.0 and Weather.from_settings(s).fog_visibility_m == math.inf
    assert fog_visibility_to_haze_per_km(math.inf) == 0.0


@pytest.mark.parametrize("field, value, fragment", [
    ("rain_mm_h", -1.0, "rain.rate_mm_h"),
    ("rain_mm_h", 501.0, "[0, 500]"),
    ("rain_mm_h", math.nan, "rain.rate_mm_h"),
    ("hour", 25.0, "time_of_day.hour"),
    ("wind_m_s", "3", "wind.speed_m_s"),
    ("wind_direction_deg", 400.0, "wind.direction_deg"),
    ("gustiness", 1.5, "wind.gustiness"),
    ("wetness", 2.0, "rain.wetness"),
    ("puddle_amount", True, "road.puddle_amount"),
    ("fog_visibility_m", 10.0, "[49.9"),
    ("fog_visibility_m", -5.0, "visibility"),
    ("fog_visibility_m", math.nan, "visibility"),
    ("fog_visibility_m", "far", "visibility"),
])
def test_out_of_range_raises_the_settings_error_naming_the_field(field, value, fragment):
    s = Settings()
    before = s.to_dict()
    with pytest.raises(SettingsError) as exc:
        Weather(**{"hour": 20.0, field: value}).apply(s)
    assert isinstance(exc.value, ValueError)
    assert f"Weather.{field}" in str(exc.value) and fragment in str(exc.value), str(exc.value)
    assert s.to_dict() == before  # all or nothing: the good hour was not stored either


def test_weather_is_not_the_simulator():
    import rain_core.weather

    assert Weather is not rain_core.weather.Weather
    assert "rain_core.weather.Weather" in Weather.__doc__ or "simulator" in sys.modules[Weather.__module__].__doc__


def test_import_stays_light_and_gl_free():
    code = ("import sys, rain_core; from rain_core import Session, Weather, Capture, load_dataset; "
            "bad = [m for m in ('moderngl', 'rain_core.scene', 'rain_core.gfx') if m in sys.modules]; "
            "print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        import rain_core

        rain_core.Nope  # noqa: B018
