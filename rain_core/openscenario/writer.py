"""Write the current weather as a minimal, valid OpenSCENARIO 1.2 file (``save``): a header, no road network or
entities, and a storyboard whose ``Init`` sets the ``Environment``; ``load`` of it gives back the rain rate, the
hour, the wind, the visibility and the road's wetness (conventions in ``mapping.py``)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from datetime import date
from pathlib import Path

from rain_core.openscenario import mapping
from rain_core.openscenario.reader import OpenScenarioError


def _sub(parent: ET.Element, tag: str, **attributes) -> ET.Element:
    return ET.SubElement(parent, tag, {k: str(v) for k, v in attributes.items()})


def _g(value: float) -> str:
    return repr(float(value))  # shortest text that reads back to the same float


def environment_element(settings, name: str = "RainroadWeather") -> ET.Element:
    """The ``Environment`` of ``settings`` (rain_core.settings.Settings)."""
    from rain_core.effects.atmosphere.visibility import visibility_m

    env = ET.Element("Environment", {"name": name})
    _sub(env, "TimeOfDay", animation="false", dateTime=mapping.iso_from_hour(settings.time_of_day.hour))
    weather = _sub(env, "Weather", fractionalCloudCover="eightOktas" if settings.rain.rate_mm_h > 0 else "zeroOktas")
    rate = settings.rain.rate_mm_h
    _sub(weather, "Fog", visualRange=_g(visibility_m(settings)))
    _sub(weather, "Precipitation", precipitationType="rain" if rate > 0 else "dry",
         precipitationIntensity=_g(rate))
    _sub(weather, "Wind", direction=_g(mapping.wind_heading_rad(settings.wind.direction_deg)),
         speed=_g(settings.wind.speed_m_s))
    r = settings.rain
    _sub(env, "RoadCondition", frictionScaleFactor=_g(settings.road.friction_scale),
         wetness=mapping.wetness_name(r.wetness, r.cracks, r.puddles))
    return env


def save(settings, path, description: str = "Rainroad weather") -> Path:
    """Write ``settings``' weather to ``path`` (.xosc) as OpenSCENARIO 1.2; returns the path. The folder must
    exist and be writable (an OpenScenarioError names the path otherwise)."""
    path = Path(path)
    if not path.parent.is_dir():
        raise OpenScenarioError(f"{path}: the folder {path.parent} does not exist")
    root = ET.Element("OpenSCENARIO")
    _sub(root, "FileHeader", revMajor="1", revMinor="2", date=f"{date.today().isoformat()}T00:00:00",
         description=description, author="Rainroad")
    _sub(root, "ParameterDeclarations")
    _sub(root, "CatalogLocations")
    _sub(root, "RoadNetwork")
    _sub(root, "Entities")
    story = _sub(root, "Storyboard")
    actions = _sub(_sub(story, "Init"), "Actions")
    _sub(_sub(actions, "GlobalAction"), "EnvironmentAction").append(environment_element(settings))
    stop = _sub(_sub(_sub(story, "StopTrigger"), "ConditionGroup"), "Condition", name="end", delay="0",
                conditionEdge="rising")
    _sub(_sub(stop, "ByValueCondition"), "SimulationTimeCondition", value=_g(3600.0),
         rule="greaterThan")
    ET.indent(root)
    try:
        ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    except OSError as exc:
        raise OpenScenarioError(f"{path}: cannot write ({exc.strerror or exc})") from None
    return path
