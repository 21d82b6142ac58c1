"""Everything the user can set, as one validated tree of dataclasses, with TOML scenario files.

Each leaf is declared in one line with ``field(default, range=(lo, hi), unit=..., choices=..., doc=...)``; its
type comes from the annotation (float, int, bool, str, or ``float | None`` for "unset / automatic"). The same
validation serves every entrance — ``Settings(...)``, ``from_dict``, ``load_scenario`` (TOML), ``set_value``
(CLI, ImGui panel) — and an invalid value raises ``SettingsError`` naming the field path, the value and what is
allowed. Booleans never pass as numbers, integers are accepted for float fields (stored as float), unknown keys
are errors. ``field_info``/``all_fields`` give the panel each field's type, range, unit and choices.

The machinery (``field``, ``FieldInfo``, the checks, ``_Section``) is in ``settings_fields``; this module
declares the sections and the tree, and reads and writes scenarios.

Scenario files are TOML: one table per section (``[rain]``, ``[road]``, ...); missing keys take their defaults,
an unset optional field is simply left out. ``save_scenario`` writes floats with ``repr`` so that save → load
gives back an identical Settings. Shipped presets live in ``assets/scenarios/<name>.toml``.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import re
import tomllib
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, ClassVar

from rain_core import physics
from rain_core.paths import ASSETS_DIR
from rain_core.settings_fields import (
    FieldInfo,
    ScenarioSyntaxError,
    SettingsError,
    _coerce,
    _quote,
    _Section,
    _section,
    _unknown,
    field,
)

SCENARIOS_DIR = ASSETS_DIR / "scenarios"
MAX_SCENARIO_BYTES = 1 << 20  # a scenario file is a few KB; a bigger one is refused before it is parsed


# --- the sections ----------------------------------------------------------------------------------------

_PRESET_CHOICES = ("custom",) + tuple(physics.RAIN_PRESETS)
_LEVEL_DOC = "pin the level (0 dry … 1 full); unset lets the weather drive it"


@dataclass
class RainSection(_Section):
    SECTION: ClassVar[str] = "rain"
    rate_mm_h: float = field(2.0, range=(0.0, physics.R_MAX_MM_H), unit="mm/h", doc="rain rate")
    preset: str = field("custom", choices=_PRESET_CHOICES, doc="the preset this came from (a label)")
    auto_weather: bool = field(True, doc="wetness and floods evolve with rain and time (off: they hold still)")
    time_scale: float = field(1.0, range=(0.0, 1000.0), unit="×", doc="speed of wetting and drying")
    drying_delay_s: float = field(10.0, range=(0.0, 3600.0), unit="s", doc="wait after rain before drying")
    drying_stage_gap_s: float = field(5.0, range=(0.0, 3600.0), unit="s", doc="film → cracks → puddles delay")
    wetness: float | None = field(None, range=(0.0, 1.0), doc=_LEVEL_DOC)
    cracks: float | None = field(None, range=(0.0, 1.0), doc=_LEVEL_DOC)
    puddles: float | None = field(None, range=(0.0, 1.0), doc=_LEVEL_DOC)


@dataclass
class RoadSection(_Section):
    SECTION: ClassVar[str] = "road"
    enabled: bool = field(True, doc="wet road shading")
    puddle_amount: float = field(0.5, range=(0.0, 1.0), doc="how much of the road can hold puddles")
    puddle_seed: int = field(0, range=(0, 2**31 - 1), doc="seed of the puddle noise map")
    wave_strength: float = field(0.5, range=(0.0, 1.0), doc="ambient wind waves on standing water")
    reflections: bool = field(True, doc="planar reflections in water")
    reflection_scale: float = field(0.5, range=(0.125, 1.0), unit="× frame", doc="reflection resolution")
    debug_regions: bool = field(False, doc="colour dry / wet / drenched / puddle regions")
    kerb_streams: bool = field(True, doc="rainwater running along the kerbs to the drains (HEC-22 gutter flow)")
    friction_scale: float = field(1.0, range=(0.0, 2.0), unit="×",
                                  doc="tyre-road grip relative to dry asphalt (OpenSCENARIO frictionScaleFactor)")


@dataclass
class WindSection(_Section):
    SECTION: ClassVar[str] = "wind"
    speed_m_s: float = field(2.0, range=(0.0, 40.0), unit="m/s", doc="mean wind speed")
    direction_deg: float = field(90.0, range=(0.0, 360.0), unit="deg",
                                 doc="heading the wind blows toward, clockwise from −Z (90 = towards +X)")
    gustiness: float = field(0.3, range=(0.0, 1.0), doc="0 steady … 1 gusts swing the speed by ±100 %")
    seed: int = field(0, range=(0, 2**31 - 1), doc="seed of the gust signal")


@dataclass
class WipersSection(_Section):
    SECTION: ClassVar[str] = "wipers"
    mode: str = field("auto", choices=("off", "intermittent", "low", "high", "auto"), doc="wiper speed")
    interval_s: float = field(4.0, range=(1.0, 30.0), unit="s", doc="pause between sweeps (intermittent)")
    low_cycles_per_min: float = field(45.0, range=(20.0, 90.0), unit="cycles/min", doc="sweep rate in low")
    high_cycles_per_min: float = field(70.0, range=(40.0, 120.0), unit="cycles/min", doc="sweep rate in high")
    auto_sensitivity: float = field(1.0, range=(0.25, 4.0), unit="×", doc="rain sensor: higher wipes sooner")
    blade_wear: float = field(0.2, range=(0.0, 1.0), doc="0 new blade … 1 worn (thicker residue streaks)")


@dataclass
class CameraSection(_Section):
    SECTION: ClassVar[str] = "camera"
    mode: str = field("driver", choices=("driver", "chase", "free", "glass"),
                      doc="in-cabin, behind the car, free, or a close-up of the windshield")
    fov_deg: float = field(60.0, range=(20.0, 120.0), unit="deg",
                           doc="vertical field of view of the chase and free cameras")
    driver_fov_deg: float = field(40.0, range=(20.0, 120.0), unit="deg",
                                  doc="vertical field of view from the driver's seat (40: hood and dash ~23%)")
    driver_pitch_deg: float = field(0.0, range=(-15.0, 15.0), unit="deg",
                                    doc="driver's gaze above (+) or below (-) the car's horizon")
    exposure_s: float = field(1.0 / 60.0, range=(1e-4, 0.25), unit="s", doc="shutter time (sets streak length)")
    auto_exposure: bool = field(True, doc="meter what the camera sees and adapt like an eye (off: the hour's "
                                          "incident-light meter)")
    exposure_compensation_ev: float = field(0.0, range=(-4.0, 4.0), unit="EV",
                                            doc="brighter (+) or darker (-) than the meter, in stops")
    adaptation_s: float = field(1.5, range=(0.05, 20.0), unit="s", doc="eye adaptation time constant")
    mirrors: bool = field(True, doc="door mirrors show the scene behind (drawn only while one is in view)")


@dataclass
class TimeOfDaySection(_Section):
    SECTION: ClassVar[str] = "time_of_day"
    hour: float = field(12.0, range=(0.0, 24.0), unit="h", doc="local time (12 noon, 22 night)")


@dataclass
class TrafficSection(_Section):
    SECTION: ClassVar[str] = "traffic"
    count: int = field(5, range=(0, 20), unit="cars", doc="other vehicles on the street")
    seed: int = field(0, range=(0, 2**31 - 1), doc="seed of their placement and speeds")


@dataclass
class QualitySection(_Section):
    SECTION: ClassVar[str] = "quality"
    render_scale: float = field(1.0, range=(0.25, 2.0), unit="× window", doc="internal resolution")
    particle_budget: int = field(50_000, range=(0, 1_000_000), unit="drops", doc="near-rain streak particles")
    ripple_grid: int = field(512, range=(32, 2048), unit="cells", doc="ripple simulation grid per side")
    windshield_resolution: int = field(512, range=(64, 2048), unit="texels", doc="glass water texture side")


@dataclass
class RipplesSection(_Section):
    SECTION: ClassVar[str] = "ripples"
    enabled: bool = field(True, doc="interactive water ripples")
    extent_m: float = field(25.0, range=(5.0, 100.0), unit="m", doc="side of the simulated window around the car")
    speed_m_s: float = field(0.35, range=(0.05, 2.0), unit="m/s", doc="wave speed (capillary-gravity ripples)")
    damping_per_s: float = field(0.5, range=(0.0, 20.0), unit="1/s", doc="amplitude decay rate, independent of dt")
    wheel_strength: float = field(1.0, range=(0.0, 10.0), unit="×", doc="wakes behind wheels in water")
    rain_strength: float = field(1.0, range=(0.0, 10.0), unit="×", doc="rings from raindrops")
    show_heights: bool = field(False, doc="show the simulated height field in the panel")


@dataclass
class RainfallSection(_Section):
    SECTION: ClassVar[str] = "rainfall"
    enabled: bool = field(True, doc="falling rain streaks")
    density_scale: float = field(1.0, range=(0.0, 4.0), unit="×", doc="streaks relative to the physical count")
    streak_brightness: float = field(1.0, range=(0.0, 4.0), unit="×", doc="streak brightness")
    splashes: bool = field(True, doc="impact splashes on the ground")
    container_m: float = field(40.0, range=(10.0, 120.0), unit="m",
                               doc="size of the near-rain box that follows the camera (streaks inside it)")


@dataclass
class SpraySection(_Section):
    SECTION: ClassVar[str] = "spray"
    enabled: bool = field(True, doc="wheel splash and spray")
    strength: float = field(1.0, range=(0.0, 4.0), unit="×", doc="spray relative to the physical water flux")
    budget: int = field(12_000, range=(0, 200_000), unit="droplets",
                        doc="spray droplet parcels alive at most (mist puffs get another 1/32)")


@dataclass
class WindshieldSection(_Section):
    SECTION: ClassVar[str] = "windshield"
    enabled: bool = field(True, doc="drops and film on the glass (driver camera)")
    drop_scale: float = field(1.0, range=(0.0, 4.0), unit="×", doc="drops relative to the physical hit rate")
    refraction: float = field(1.0, range=(0.0, 2.0), unit="×", doc="strength of refraction through water")
    drop_budget: int = field(6000, range=(0, 50_000), unit="drops",
                             doc="most drops simulated one by one (beyond it new water joins the film)")


@dataclass
class AtmosphereSection(_Section):
    SECTION: ClassVar[str] = "atmosphere"
    enabled: bool = field(True, doc="rain fog, extinction and glow")
    fog_scale: float = field(1.0, range=(0.0, 4.0), unit="×", doc="extinction relative to the rain's β")
    glow: float = field(1.0, range=(0.0, 4.0), unit="×", doc="glow around lights")
    haze_per_km: float = field(0.0, range=(0.0, 60.0), unit="1/km",
                               doc="extra haze or fog extinction, independent of the rain (visibility ≈ 3/β km)")
    sky_darkening: float | None = field(None, range=(0.0, 1.0),
                                        doc="rain-grey sky, 0 clear … 1 dark overcast; unset follows the rain rate")
    light_scattering: float = field(1.0, range=(0.0, 4.0), unit="×",
                                    doc="light scattered in the rain around lamps and in headlight beams")
    scatter_lights: int = field(8, range=(0, 32), unit="lights", doc="nearest lights traced per pixel")
    glow_resolution: float = field(0.25, range=(0.0625, 1.0), unit="× frame", doc="resolution of the glow blur")
    cloud_base_m: float = field(1500.0, range=(200.0, 5000.0), unit="m",
                                doc="height of the cloud base: rain falls from it, lightning leaves it")


@dataclass
class RainbowSection(_Section):
    SECTION: ClassVar[str] = "rainbow"
    enabled: bool = field(True, doc="a bow where the sun is low behind you and rain falls in front")
    strength: float = field(1.0, range=(0.0, 4.0), unit="×", doc="bow radiance relative to the physical")
    shower_speed_m_s: float = field(10.0, range=(0.5, 40.0), unit="m/s",
                                    doc="how fast the shower moves off after the rain stops (the bow stays on it)")
    shower_width_m: float = field(3000.0, range=(100.0, 20_000.0), unit="m", doc="depth of the departing shower")


@dataclass
class DripsSection(_Section):
    SECTION: ClassVar[str] = "drips"
    enabled: bool = field(True, doc="water dripping from the bridge, the canopy and awnings")
    strength: float = field(1.0, range=(0.0, 4.0), unit="×", doc="water the roofs catch relative to the rain")
    reach_m: float = field(60.0, range=(10.0, 200.0), unit="m", doc="drips drawn this far along the street")


@dataclass
class LightningSection(_Section):
    SECTION: ClassVar[str] = "lightning"
    enabled: bool = field(True, doc="lightning in convective rain (thunderstorms)")
    flashes_per_min: float | None = field(None, range=(0.0, 60.0), unit="1/min",
                                          doc="storm flash rate; unset: automatic, 0 below 16 mm/h")
    intensity: float = field(1.0, range=(0.0, 4.0), unit="×", doc="flash brightness relative to the physical")
    max_distance_km: float = field(8.0, range=(1.0, 30.0), unit="km", doc="farthest bolts of the storm")


@dataclass
class Settings:
    """The whole settings tree. ``Settings()`` is valid; construction validates every field."""

    rain: RainSection = _section(RainSection)
    road: RoadSection = _section(RoadSection)
    wind: WindSection = _section(WindSection)
    wipers: WipersSection = _section(WipersSection)
    camera: CameraSection = _section(CameraSection)
    time_of_day: TimeOfDaySection = _section(TimeOfDaySection)
    traffic: TrafficSection = _section(TrafficSection)
    quality: QualitySection = _section(QualitySection)
    ripples: RipplesSection = _section(RipplesSection)
    rainfall: RainfallSection = _section(RainfallSection)
    spray: SpraySection = _section(SpraySection)
    windshield: WindshieldSection = _section(WindshieldSection)
    atmosphere: AtmosphereSection = _section(AtmosphereSection)
    drips: DripsSection = _section(DripsSection)
    lightning: LightningSection = _section(LightningSection)
    rainbow: RainbowSection = _section(RainbowSection)

    def __post_init__(self):
        self.validate()

    @classmethod
    def section_types(cls) -> Mapping[str, type[_Section]]:
        """Section name → its dataclass, in file order (read-only). Made once per class: every path lookup
        (``get_value``, ``set_value``) asks for it, and resolving the string annotations each time cost ~0.2 ms,
        2 ms a frame in the Rain Manager, which reads each of its widgets' values by path."""
        cached = cls.__dict__.get("_section_types")
        if cached is None:
            hints = typing.get_type_hints(cls)
            cached = MappingProxyType({f.name: hints[f.name] for f in dataclasses.fields(cls)})
            cls._section_types = cached
        return cached

    def validate(self, source: str | None = None) -> None:
        """Check every field (SettingsError naming the first bad one)."""
        for name, typ in self.section_types().items():
            sec = getattr(self, name)
            if type(sec) is not typ:
                raise SettingsError(name, sec, f"a [{name}] table ({typ.__name__})", source)
            sec.validate(source)

    def to_dict(self) -> dict[str, dict[str, Any]]:
        """Nested plain dict {section: {field: value}}; unset optional fields are None."""
        return {name: dataclasses.asdict(getattr(self, name)) for name in self.section_types()}

    @classmethod
    def from_dict(cls, data: dict, base: Settings | None = None, source: str | None = None) -> Settings:
        """Settings from a nested dict (as read from TOML), on top of ``base`` (default: the defaults).

        Unknown sections or keys, wrong types and out-of-range values raise SettingsError naming the path.
        """
        if not isinstance(data, dict):
            raise SettingsError("<root>", data, "a table of sections", source)
        result = copy.deepcopy(base) if base is not None else cls()
        sections = cls.section_types()
        for sec_name, values in data.items():
            if sec_name not in sections:
                raise _unknown(sec_name, values, "sections are " + ", ".join(sections), source)
            if not isinstance(values, dict):
                raise SettingsError(sec_name, values, f"a [{sec_name}] table", source)
            infos = sections[sec_name].field_infos()
            sec = getattr(result, sec_name)
            for key, value in values.items():
                if key not in infos:
                    raise _unknown(f"{sec_name}.{key}", value, f"[{sec_name}] has " + ", ".join(infos), source)
                setattr(sec, key, _coerce(infos[key], value, source))
        return result

    def copy(self) -> Settings:
        """A deep copy."""
        return copy.deepcopy(self)


RainSettings = Settings


# --- access by path (CLI, panel) -------------------------------------------------------------------------


def _resolve(path: str) -> tuple[str, str, FieldInfo]:
    parts = path.split(".") if isinstance(path, str) else []
    sections = Settings.section_types()
    if len(parts) != 2 or parts[0] not in sections:
        raise _unknown(path if isinstance(path, str) else _quote(path), None,
                       "a path is 'section.key' with section one of " + ", ".join(sections))
    infos = sections[parts[0]].field_infos()
    if parts[1] not in infos:
        raise _unknown(path, None, f"[{parts[0]}] has " + ", ".join(infos))
    return parts[0], parts[1], infos[parts[1]]


def field_info(path: str) -> FieldInfo:
    """Type, range, unit, choices and doc of the setting at ``path`` ("rain.rate_mm_h")."""
    return _resolve(path)[2]


def all_fields() -> list[FieldInfo]:
    """Every setting, in section and declaration order."""
    return [info for typ in Settings.section_types().values() for info in typ.field_infos().values()]


def get_value(settings: Settings, path: str) -> Any:
    """The value at ``path`` ("section.key")."""
    sec, key, _ = _resolve(path)
    return getattr(getattr(settings, sec), key)


def set_value(settings: Settings, path: str, value: Any) -> None:
    """Validate ``value`` for ``path`` ("section.key") and store it in ``settings`` (SettingsError if invalid)."""
    sec, key, info = _resolve(path)
    setattr(getattr(settings, sec), key, _coerce(info, value))


def apply_rain_preset(settings: Settings, name: str) -> None:
    """Set rain.rate_mm_h to the named preset's rate and label rain.preset with it (the rest is untouched)."""
    try:
        rate = physics.preset_rate(name)
    except ValueError:
        raise SettingsError("rain.preset", name, "one of " + ", ".join(physics.RAIN_PRESETS)) from None
    key = name.strip().lower().replace(" ", "_").replace("-", "_")
    set_value(settings, "rain.rate_mm_h", rate)
    set_value(settings, "rain.preset", key)


# --- TOML files ------------------------------------------------------------------------------------------


def load_scenario(path: str | Path, base: Settings | None = None) -> Settings:
    """Read a TOML scenario file into Settings (on top of ``base``; default: the defaults).

    The file is UTF-8, with or without a byte-order mark. A syntax error raises ScenarioSyntaxError (a
    SettingsError) naming the file and line, as does a value nested too deeply to parse (a scenario needs only
    ``[section]`` tables of ``key = value``); a bad value raises SettingsError naming the file, the field path,
    the value (cut to a readable length) and the allowed range. A file over MAX_SCENARIO_BYTES is refused
    unread (a ScenarioSyntaxError).
    """
    path = Path(path)
    with path.open("rb") as f:
        raw = f.read(MAX_SCENARIO_BYTES + 1)
    if len(raw) > MAX_SCENARIO_BYTES:
        raise ScenarioSyntaxError(str(path), f"larger than {MAX_SCENARIO_BYTES // 1024} KiB; a scenario is a few "
                                  "KB of [section] tables of key = value", None)
    try:
        data = tomllib.loads(raw.decode("utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise ScenarioSyntaxError(str(path), f"not UTF-8 ({exc.reason} at byte {exc.start})", None) from None
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise ScenarioSyntaxError(str(path), str(exc), int(m.group(1)) if m else None) from None
    except RecursionError:  # tomllib parses nested arrays, inline tables and dotted keys recursively
        raise ScenarioSyntaxError(str(path), "a value or key is nested too deeply to read (a scenario needs only "
                                  "[section] tables of key = value)", None) from None
    return Settings.from_dict(data, base=base, source=str(path))


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)  # shortest string that reads back to the same float; always has '.' or 'e'
    return json.dumps(value)  # a JSON string is a valid TOML basic string


def to_toml(settings: Settings, title: str = "") -> str:
    """The TOML text of a scenario file, with each field's unit and range as a comment."""
    settings.validate()
    lines = [f"# {line}" for line in title.splitlines()] if title else []
    lines.append("# Rainroad scenario. Units and allowed values in the comments; missing keys take defaults.")
    for sec_name, typ in Settings.section_types().items():
        lines += ["", f"[{sec_name}]"]
        sec = getattr(settings, sec_name)
        for key, info in typ.field_infos().items():
            value = getattr(sec, key)
            comment = f"  # {info.allowed()}"
            if value is None:
                lines.append(f"# {key} = (unset){comment}")
            else:
                lines.append(f"{key} = {_toml_value(value)}{comment}")
    return "\n".join(lines) + "\n"


def save_scenario(settings: Settings, path: str | Path, title: str = "") -> Path:
    """Write ``settings`` as a TOML scenario file (parents created); load_scenario gives back an equal Settings."""
    path = Path(path)
    text = to_toml(settings, title)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def list_presets() -> list[str]:
    """Names of the shipped scenario files: the rain presets in intensity order, then any others by name."""
    names = sorted(p.stem for p in SCENARIOS_DIR.glob("*.toml")) if SCENARIOS_DIR.is_dir() else []
    order = {name: i for i, name in enumerate(physics.RAIN_PRESETS)}
    return sorted(names, key=lambda n: (order.get(n, len(order)), n))


def preset_settings(name: str) -> Settings:
    """Settings of the shipped scenario ``assets/scenarios/<name>.toml`` ("very heavy" = "very_heavy")."""
    key = str(name).strip().lower().replace(" ", "_").replace("-", "_")
    available = list_presets()
    if key not in available:
        raise SettingsError("preset", name, "one of " + ", ".join(available))
    return load_scenario(SCENARIOS_DIR / f"{key}.toml")
