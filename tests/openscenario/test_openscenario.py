"""OpenSCENARIO weather: files of several versions read into settings, the round trip, the conventions, and every
error naming the file/line or the element and attribute."""

from __future__ import annotations

import math
import warnings

import pytest

from rain_core import openscenario
from rain_core.atmosphere import visibility_m
from rain_core.openscenario import mapping
from rain_core.settings import Settings

V12 = """<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" description="t" author="t"/>
  <ParameterDeclarations/>
  <CatalogLocations/>
  <RoadNetwork/>
  <Entities/>
  <Storyboard>
    <Init>
      <Actions>
        <GlobalAction>
          <EnvironmentAction>
            <Environment name="Storm">
              <TimeOfDay animation="false" dateTime="2024-06-21T17:30:00"/>
              <Weather fractionalCloudCover="sevenOktas">
                <Sun azimuth="4.0" elevation="0.3" illuminance="20000"/>
                <Fog visualRange="{fog}"/>
                <Precipitation precipitationType="{kind}" precipitationIntensity="{rate}"/>
                <Wind direction="{heading}" speed="6.5"/>
              </Weather>
              <RoadCondition frictionScaleFactor="0.7" wetness="{wetness}"/>
            </Environment>
          </EnvironmentAction>
        </GlobalAction>
      </Actions>
    </Init>
    <StopTrigger/>
  </Storyboard>
</OpenSCENARIO>
"""

V10 = """<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="0" date="2020-01-01T00:00:00" description="old" author="t"/>
  <Storyboard>
    <Init>
      <Actions>
        <GlobalAction>
          <EnvironmentAction>
            <Environment name="Old">
              <TimeOfDay animation="false" dateTime="2020-05-01T08:15:00"/>
              <Weather cloudState="rainy">
                <Sun intensity="1000" azimuth="1.0" elevation="0.5"/>
                <Fog visualRange="100000"/>
                <Precipitation precipitationType="rain" intensity="0.4"/>
              </Weather>
              <RoadCondition frictionScaleFactor="0.9"/>
            </Environment>
          </EnvironmentAction>
        </GlobalAction>
      </Actions>
    </Init>
  </Storyboard>
</OpenSCENARIO>
"""


def _write(tmp_path, text, name="s.xosc", **values):
    defaults = {"fog": "2000", "kind": "rain", "rate": "8.0", "heading": "0.0", "wetness": "wetWithPuddles"}
    path = tmp_path / name
    path.write_text(text.format(**{**defaults, **values}) if "{" in text else text, encoding="utf-8")
    return path


def test_version_1_2(tmp_path):
    s = openscenario.load(_write(tmp_path, V12, heading=str(math.pi / 2)))
    assert s.rain.rate_mm_h == 8.0 and s.time_of_day.hour == pytest.approx(17.5)
    assert s.wind.speed_m_s == 6.5 and s.wind.direction_deg == pytest.approx(0.0)  # +y (north) = −Z here
    assert s.road.friction_scale == 0.7 and s.rain.puddles == 0.6 and s.rain.wetness == 1.0
    assert visibility_m(s) == pytest.approx(2000.0, rel=1e-9)  # rain + haze make up the visual range


def test_version_1_0_deprecated_intensity_warns(tmp_path):
    with pytest.warns(UserWarning, match="deprecated"):
        s = openscenario.load(_write(tmp_path, V10))
    assert s.rain.rate_mm_h == pytest.approx(mapping.rate_from_intensity(0.4)) == pytest.approx(8.0)
    assert s.time_of_day.hour == pytest.approx(8.25) and s.road.friction_scale == 0.9


def test_catalog_reference(tmp_path):
    (tmp_path / "catalogs").mkdir()
    env = V12.split("<Environment ")[1].split("</Environment>")[0].format(
        fog="100000", kind="rain", rate="3", heading="0", wetness="moist")
    (tmp_path / "catalogs" / "env.xosc").write_text(
        '<?xml version="1.0"?><OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" '
        'description="c" author="t"/><Catalog name="Weathers"><Environment ' + env + "</Environment></Catalog>"
        "</OpenSCENARIO>")
    main = V12.replace("<CatalogLocations/>", '<CatalogLocations><EnvironmentCatalog><Directory path="catalogs"/>'
                       "</EnvironmentCatalog></CatalogLocations>")
    start = main.index("<Environment ")
    end = main.index("</Environment>") + len("</Environment>")
    main = main[:start] + '<CatalogReference catalogName="Weathers" entryName="Storm"/>' + main[end:]
    with pytest.warns(UserWarning, match="visualRange"):  # 100 km asked, the 3 mm/h rain sees 4 km
        s = openscenario.load(_write(tmp_path, main))
    assert s.rain.rate_mm_h == 3.0 and s.rain.wetness == 0.6 and s.rain.cracks == 0.0


@pytest.mark.parametrize("hour,rate,direction,wetness,fog_km", [
    (12.0, 0.0, 90.0, None, 0.0), (17.5, 8.0, 10.0, 1.0, 2.0), (22.25, 50.0, 271.5, 0.6, 0.0),
    (6.5, 2.0, 180.0, None, 20.0)])
def test_round_trip(tmp_path, hour, rate, direction, wetness, fog_km):
    s = Settings()
    s.time_of_day.hour, s.rain.rate_mm_h, s.wind.direction_deg, s.wind.speed_m_s = hour, rate, direction, 4.0
    s.atmosphere.haze_per_km = fog_km
    if wetness is not None:
        s.rain.wetness = wetness
        s.rain.cracks = s.rain.puddles = 1.0 if wetness == 1.0 else 0.0
    path = openscenario.save(s, tmp_path / "out.xosc")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = openscenario.load(path)
    again = openscenario.load(openscenario.save(back, tmp_path / "again.xosc"))
    for t in (back, again):
        assert t.rain.rate_mm_h == pytest.approx(rate) and t.time_of_day.hour == pytest.approx(hour, abs=1 / 3600)
        assert t.wind.direction_deg == pytest.approx(direction % 360.0, abs=1e-9)
        assert t.wind.speed_m_s == pytest.approx(4.0)
        assert visibility_m(t) == pytest.approx(visibility_m(s), rel=1e-6)
    assert mapping.wetness_name(back.rain.wetness, back.rain.cracks, back.rain.puddles) == \
        mapping.wetness_name(s.rain.wetness, s.rain.cracks, s.rain.puddles)
    assert back.rain.wetness == again.rain.wetness and back.rain.puddles == again.rain.puddles


def test_fog_thinner_than_the_rain_warns_and_keeps_the_rain(tmp_path):
    with pytest.warns(UserWarning, match="rain .* alone sees only"):
        s = openscenario.load(_write(tmp_path, V12, fog="5000", rate="50"))
    assert s.rain.rate_mm_h == 50.0 and s.atmosphere.haze_per_km == 0.0


def test_wind_convention():
    assert mapping.wind_direction_deg(0.0) == 90.0  # towards +x (east) → towards +X
    assert mapping.wind_direction_deg(math.pi / 2) == 0.0  # towards +y (north) → towards −Z
    for d in (0.0, 33.0, 90.0, 359.0):
        assert mapping.wind_direction_deg(mapping.wind_heading_rad(d)) == pytest.approx(d)


def test_hour_from_the_sun_alone():
    from rain_core.lighting import sun_elevation_deg

    for hour in (8.0, 11.0, 15.5):
        azimuth = 1.0 if hour < 12 else 4.0
        h = mapping.hour_from_sun(math.radians(sun_elevation_deg(hour)), azimuth)
        assert h == pytest.approx(hour, abs=1e-9)
    assert mapping.hour_from_sun(-0.1, 1.0) == 22.0


@pytest.mark.parametrize("text,match", [
    ("<OpenSCENARIO><Storyboard>", r"s\.xosc:1:\d+: malformed XML"),
    ("<Scenario/>", "root element is <Scenario>"),
    ("<OpenSCENARIO><Storyboard><Init><Actions/></Init></Storyboard></OpenSCENARIO>", "no EnvironmentAction"),
])
def test_structural_errors(tmp_path, text, match):
    with pytest.raises(ValueError, match=match):
        openscenario.load(_write(tmp_path, text))


@pytest.mark.parametrize("values,match", [
    ({"rate": "-3"}, r"Precipitation@precipitationIntensity must be in \[0, 500\] mm/h, got -3"),
    ({"rate": "lots"}, r"Precipitation@precipitationIntensity must be a number"),
    ({"kind": "snow"}, "snow is not supported"),
    ({"kind": "hail"}, "precipitationType must be dry, rain or snow"),
    ({"heading": "9"}, r"Wind@direction must be in \[0, 6.28319\] rad, got 9"),
    ({"wetness": "soaked"}, "RoadCondition@wetness must be one of"),
    ({"fog": "-5"}, r"Fog@visualRange must be ≥ 0 m, got -5"),
    ({"rate": "$Rate"}, "parameter reference"),
])
def test_value_errors_name_element_and_attribute(tmp_path, values, match):
    with pytest.raises(ValueError, match=match):
        openscenario.load(_write(tmp_path, V12, **values))


def test_missing_file_and_unwritable_output(tmp_path):
    with pytest.raises(ValueError, match="no such OpenSCENARIO file"):
        openscenario.load(tmp_path / "missing.xosc")
    with pytest.raises(ValueError, match="does not exist"):
        openscenario.save(Settings(), tmp_path / "nope" / "x.xosc")


def test_cli_flag(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    bad = _write(tmp_path, V12, rate="-3")
    result = subprocess.run([sys.executable, "-m", "app", "--headless", "--openscenario", str(bad)], cwd=root,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "precipitationIntensity" in result.stderr
    from app.__main__ import settings_from_args
    from app.cli import parse_args

    args = parse_args(["--headless", "--openscenario", str(_write(tmp_path, V12, name="ok.xosc")), "--hour", "9"])
    s = settings_from_args(args)
    assert s.rain.rate_mm_h == 8.0 and s.time_of_day.hour == 9.0  # the flag wins over the file
