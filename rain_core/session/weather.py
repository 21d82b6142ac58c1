"""``Weather``: the public weather spec of the Python API, in physical units, mapped onto the settings tree.

Not to be confused with ``rain_core.weather.Weather``, the simulator a Scene steps every frame (the road's wet
levels filling and drying, the gust signal). This one is a *request*: every field is optional (None leaves the
setting as it is), each maps onto one settings path, and ``apply`` stores the values through
``rain_core.settings.set_value`` — so the settings' validation and ranges are the only ones, and an
out-of-range value raises the same ``SettingsError`` (a ValueError) prefixed with the Weather field's name.
The simulator then follows the settings on its next step.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from rain_core.effects.atmosphere.model import CONTRAST_THRESHOLD
from rain_core.settings import Settings, SettingsError, field_info, get_value, set_value

# −ln(contrast): visibility (m) × β (1/m) for the contrast threshold the atmosphere effect reports (5 %).
_VISIBILITY_TIMES_BETA = -math.log(CONTRAST_THRESHOLD)

# Weather field → settings path, for the fields stored as they are.
FIELD_PATHS: dict[str, str] = {
    "rain_mm_h": "rain.rate_mm_h",
    "hour": "time_of_day.hour",
    "wind_m_s": "wind.speed_m_s",
    "wind_direction_deg": "wind.direction_deg",
    "gustiness": "wind.gustiness",
    "wetness": "rain.wetness",
    "cracks": "rain.cracks",
    "puddles": "rain.puddles",
    "puddle_amount": "road.puddle_amount",
}
# Stored converted: the fog's own visibility (m) becomes the haze extinction (1/km) at the same contrast.
FOG_PATH = "atmosphere.haze_per_km"


def fog_visibility_to_haze_per_km(visibility_m: float) -> float:
    """Haze β (1/km) whose visibility alone (5 % contrast, no rain, no clear air) is ``visibility_m``; inf → 0."""
    return 0.0 if visibility_m == math.inf else _VISIBILITY_TIMES_BETA / visibility_m * 1000.0


@dataclass(frozen=True)
class Weather:
    """What the weather should be. Every field optional: None leaves that setting unchanged.

    rain_mm_h: rain rate, mm/h [0, 500] (rain.rate_mm_h). hour: local time, h [0, 24] (time_of_day.hour).
    wind_m_s: mean wind speed, m/s [0, 40] (wind.speed_m_s). wind_direction_deg: heading the wind blows toward,
    degrees clockwise from −Z (90 = towards +X), [0, 360] (wind.direction_deg). gustiness: 0 steady … 1 gusts
    of ±100 % (wind.gustiness). fog_visibility_m: visibility (m, 5 % contrast) of a fog or haze on its own, rain
    adds its own extinction on top; ≥ 50 m, inf for none (atmosphere.haze_per_km = 2.996/visibility km⁻¹).
    wetness, cracks, puddles: pin the road's film / crack / puddle level, 0 dry … 1 full (rain.wetness …);
    the levels otherwise follow the rain over time. puddle_amount: how much of the road can hold puddles,
    0 … 1 (road.puddle_amount).
    """

    rain_mm_h: float | None = None
    hour: float | None = None
    wind_m_s: float | None = None
    wind_direction_deg: float | None = None
    gustiness: float | None = None
    fog_visibility_m: float | None = None
    wetness: float | None = None
    cracks: float | None = None
    puddles: float | None = None
    puddle_amount: float | None = None

    def settings_values(self) -> dict[str, object]:
        """{settings path: value} of the fields that are set (the fog converted to haze), not yet validated."""
        out: dict[str, object] = {}
        for name, path in FIELD_PATHS.items():
            value = getattr(self, name)
            if value is not None:
                out[path] = value
        if self.fog_visibility_m is not None:
            out[FOG_PATH] = self.fog_visibility_m
        return out

    def apply(self, settings: Settings) -> None:
        """Store the set fields in ``settings``. All or nothing: a bad field raises SettingsError naming the
        Weather field, the settings path and its range, and leaves ``settings`` unchanged."""
        if not isinstance(settings, Settings):
            raise TypeError(f"settings: expected a rain_core.settings.Settings, got {type(settings).__name__}")
        trial = settings.copy()
        for name in (*FIELD_PATHS, "fog_visibility_m"):
            value = getattr(self, name)
            if value is not None:
                _store(trial, name, value)
        for path in self.settings_values():
            set_value(settings, path, get_value(trial, path))

    @classmethod
    def from_settings(cls, settings: Settings) -> Weather:
        """The weather ``settings`` describe (every field set; unpinned levels are None)."""
        values = {name: get_value(settings, path) for name, path in FIELD_PATHS.items()}
        haze = settings.atmosphere.haze_per_km
        values["fog_visibility_m"] = math.inf if haze == 0.0 else _VISIBILITY_TIMES_BETA / haze * 1000.0
        return cls(**values)

    def replace(self, **changes) -> Weather:
        """A copy with ``changes`` (field=value; None unsets)."""
        return dataclasses.replace(self, **changes)


def _store(settings: Settings, name: str, value) -> None:
    if name != "fog_visibility_m":
        path = FIELD_PATHS[name]
        try:
            set_value(settings, path, value)
        except SettingsError as exc:
            raise SettingsError(path, value, exc.allowed, message=f"Weather.{name}: {exc}") from None
        return
    lo_haze, hi_haze = field_info(FOG_PATH).range
    shortest = _VISIBILITY_TIMES_BETA / hi_haze * 1000.0
    allowed = f"a visibility in [{shortest:g}, inf] m (atmosphere.haze_per_km in [{lo_haze:g}, {hi_haze:g}] 1/km)"
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if not number or math.isnan(value) or not shortest <= value <= math.inf:
        raise SettingsError("fog_visibility_m", value, allowed,
                            message=f"Weather.fog_visibility_m = {value!r} is not allowed: expected {allowed}")
    set_value(settings, FOG_PATH, min(fog_visibility_to_haze_per_km(float(value)), hi_haze))
