"""Read the weather of an OpenSCENARIO file (1.0, 1.1, 1.2, 1.3) into Settings (``load``).

The first ``Environment`` of the storyboard's ``Init`` (``GlobalAction/EnvironmentAction``) is read — inline, or
through a ``CatalogReference`` into an environment catalog found under ``CatalogLocations/EnvironmentCatalog``.
Errors are ``ValueError``s that name the file and line (malformed XML) or the element and attribute (a missing or
out-of-range value). The mapping and its conventions are in ``mapping.py``.
"""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

from rain_core.openscenario import mapping
from rain_core.settings import Settings, set_value

RATE_MAX_MM_H = 500.0


class OpenScenarioError(ValueError):
    """A bad OpenSCENARIO file or value; the message names the file and the element/attribute."""


def _parse(path: Path) -> ET.Element:
    if not path.is_file():
        raise OpenScenarioError(f"{path}: no such OpenSCENARIO file")
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        line, column = exc.position
        raise OpenScenarioError(f"{path}:{line}:{column}: malformed XML ({exc.msg if hasattr(exc, 'msg') else exc})"
                                ) from None


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _child(element: ET.Element, name: str) -> ET.Element | None:
    return next((c for c in element if _local(c.tag) == name), None)


def _find_path(element: ET.Element, *names: str) -> ET.Element | None:
    for name in names:
        if element is None:
            return None
        element = _child(element, name)
    return element


def _number(element: ET.Element, attribute: str, lo: float, hi: float, unit: str, source: str,
            required: bool = False) -> float | None:
    name = _local(element.tag)
    text = element.get(attribute)
    if text is None:
        if required:
            raise OpenScenarioError(f"{source}: {name}@{attribute} is missing ({unit}, in [{lo:g}, {hi:g}])")
        return None
    if text.strip().startswith("$"):
        raise OpenScenarioError(f"{source}: {name}@{attribute} is a parameter reference ({text}); parameters are "
                                f"not resolved here — give the value")
    try:
        value = float(text)
    except ValueError:
        raise OpenScenarioError(f"{source}: {name}@{attribute} must be a number ({unit}), got {text!r}") from None
    if not math.isfinite(value) or not (lo <= value <= hi):
        bound = f"≥ {lo:g} {unit}" if hi == math.inf else f"in [{lo:g}, {hi:g}] {unit}"
        raise OpenScenarioError(f"{source}: {name}@{attribute} must be {bound}, got {text}")
    return value


def _environment(root: ET.Element, path: Path) -> tuple[ET.Element, str]:
    """The first Environment of Storyboard/Init, resolved through a catalog if it is a reference."""
    init = _find_path(root, "Storyboard", "Init", "Actions")
    if init is None:
        raise OpenScenarioError(f"{path}: no Storyboard/Init/Actions (is this an OpenSCENARIO scenario file?)")
    for action in init.iter():
        if _local(action.tag) != "EnvironmentAction":
            continue
        env = _child(action, "Environment")
        if env is not None:
            return env, str(path)
        ref = _child(action, "CatalogReference")
        if ref is not None:
            return _from_catalog(root, path, ref)
    raise OpenScenarioError(f"{path}: Storyboard/Init has no EnvironmentAction (no weather to read)")


def _from_catalog(root: ET.Element, path: Path, ref: ET.Element) -> tuple[ET.Element, str]:
    catalog_name, entry = ref.get("catalogName"), ref.get("entryName")
    if not catalog_name or not entry:
        raise OpenScenarioError(f"{path}: CatalogReference needs catalogName and entryName")
    directory = _find_path(root, "CatalogLocations", "EnvironmentCatalog", "Directory")
    if directory is None or not directory.get("path"):
        raise OpenScenarioError(f"{path}: CatalogReference to {catalog_name}/{entry} but no "
                                f"CatalogLocations/EnvironmentCatalog/Directory@path")
    folder = (path.parent / directory.get("path")).resolve()
    for file in sorted(folder.glob("*.xosc")):
        catalog = _child(_parse(file), "Catalog")
        if catalog is None or catalog.get("name") != catalog_name:
            continue
        for env in catalog:
            if _local(env.tag) == "Environment" and env.get("name") == entry:
                return env, str(file)
    raise OpenScenarioError(f"{path}: environment {entry!r} of catalog {catalog_name!r} not found in {folder}")


def read_environment(env: ET.Element, source: str, settings: Settings) -> Settings:
    """Apply one ``Environment`` element onto ``settings`` (returned)."""
    weather = _child(env, "Weather")
    time_of_day = _child(env, "TimeOfDay")
    rate = None
    if weather is not None:
        precipitation = _child(weather, "Precipitation")
        if precipitation is not None:
            kind = precipitation.get("precipitationType", "rain")
            if kind not in ("dry", "rain", "snow"):
                raise OpenScenarioError(f"{source}: Precipitation@precipitationType must be dry, rain or snow, "
                                        f"got {kind!r}")
            if kind == "snow":
                raise OpenScenarioError(f"{source}: Precipitation@precipitationType snow is not supported "
                                        f"(Rainroad renders rain)")
            mm_h = _number(precipitation, "precipitationIntensity", 0.0, RATE_MAX_MM_H, "mm/h", source)
            if mm_h is None and precipitation.get("intensity") is not None:
                old = _number(precipitation, "intensity", 0.0, 1.0, "(0…1)", source)
                mm_h = mapping.rate_from_intensity(old)
                warnings.warn(f"{source}: Precipitation@intensity is deprecated (OpenSCENARIO 1.0); {old:g} read as "
                              f"{mm_h:.3g} mm/h (50·intensity²)", stacklevel=3)
            rate = 0.0 if kind == "dry" else (mm_h if mm_h is not None else 0.0)
            set_value(settings, "rain.rate_mm_h", rate)
        wind = _child(weather, "Wind")
        if wind is not None:
            heading = _number(wind, "direction", 0.0, 2 * math.pi, "rad", source, required=True)
            speed = _number(wind, "speed", 0.0, 40.0, "m/s", source, required=True)
            set_value(settings, "wind.direction_deg", mapping.wind_direction_deg(heading))
            set_value(settings, "wind.speed_m_s", speed)
        sun = _child(weather, "Sun")
        if sun is not None and time_of_day is None:
            elevation = _number(sun, "elevation", -math.pi, math.pi, "rad", source)
            azimuth = _number(sun, "azimuth", 0.0, 2 * math.pi, "rad", source)
            if elevation is not None:
                set_value(settings, "time_of_day.hour", mapping.hour_from_sun(elevation, azimuth))
        fog = _child(weather, "Fog")
        if fog is not None:
            _apply_visibility(settings, _number(fog, "visualRange", 0.0, math.inf, "m", source, required=True),
                              source)
    if time_of_day is not None:
        text = time_of_day.get("dateTime")
        if text is None:
            raise OpenScenarioError(f"{source}: TimeOfDay@dateTime is missing (ISO 8601, e.g. 2021-06-25T17:30:00)")
        try:
            set_value(settings, "time_of_day.hour", mapping.hour_from_iso(text) % 24.0)
        except ValueError:
            raise OpenScenarioError(f"{source}: TimeOfDay@dateTime must be ISO 8601 (2021-06-25T17:30:00), "
                                    f"got {text!r}") from None
    road = _child(env, "RoadCondition")
    if road is not None:
        friction = _number(road, "frictionScaleFactor", 0.0, 2.0, "×", source)
        if friction is not None:
            set_value(settings, "road.friction_scale", friction)
        wet = road.get("wetness")
        if wet is not None:
            if wet not in mapping.WETNESS_LEVELS:
                raise OpenScenarioError(f"{source}: RoadCondition@wetness must be one of "
                                        f"{', '.join(mapping.WETNESS_LEVELS)}, got {wet!r}")
            w, c, p, amount = mapping.WETNESS_LEVELS[wet]
            for name, value in (("wetness", w), ("cracks", c), ("puddles", p)):
                set_value(settings, f"rain.{name}", value)
            if amount is not None:
                set_value(settings, "road.puddle_amount", amount)
    return settings


def _apply_visibility(settings: Settings, visual_range_m: float, source: str) -> None:
    from rain_core.effects.atmosphere.visibility import haze_for_visibility

    if visual_range_m <= 0.0:
        raise OpenScenarioError(f"{source}: Fog@visualRange must be > 0 m, got {visual_range_m:g}")
    haze, shortfall = haze_for_visibility(visual_range_m, settings.rain.rate_mm_h, settings.atmosphere.fog_scale)
    if shortfall > 0.0:
        warnings.warn(f"{source}: Fog@visualRange asks for {visual_range_m:g} m but the rain at "
                      f"{settings.rain.rate_mm_h:g} mm/h alone sees only {visual_range_m - shortfall:.0f} m; the "
                      f"rain is kept (no haze)", stacklevel=4)
    set_value(settings, "atmosphere.haze_per_km", min(haze, 60.0))


def load(path, base: Settings | None = None) -> Settings:
    """The weather of the OpenSCENARIO file at ``path`` as Settings (on top of ``base``, default the defaults).
    Raises OpenScenarioError (a ValueError) naming the file and line or the element and attribute."""
    path = Path(path)
    root = _parse(path)
    if _local(root.tag) != "OpenSCENARIO":
        raise OpenScenarioError(f"{path}: the root element is <{_local(root.tag)}>, not <OpenSCENARIO>")
    env, source = _environment(root, path)
    import copy

    settings = copy.deepcopy(base) if base is not None else Settings()
    return read_environment(env, source, settings)
