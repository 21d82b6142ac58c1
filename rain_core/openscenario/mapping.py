"""How an OpenSCENARIO ``Environment`` maps onto Rainroad's settings, both ways, and the conventions used.

- Frames. OpenSCENARIO's world is right-handed with z up, x/y the ground (x east, y north in a georeferenced
  map). Rainroad's is right-handed with +Y up, the road along Z, +X east and +Z south. So an OpenSCENARIO heading
  h (rad, from +x towards +y) is the direction (cos h, 0, −sin h) here.
- ``Weather/Wind@direction`` (rad) is the heading the wind blows *towards* (the standard: "the target
  direction, not the origin"), ``@speed`` m/s. Rainroad's ``wind.direction_deg`` is the heading towards, clockwise
  from −Z (north) seen from above: direction_deg = 90° − degrees(h), wrapped into [0, 360).
- ``TimeOfDay@dateTime`` (ISO 8601) gives ``time_of_day.hour`` (hours + minutes/60 + seconds/3600; the date and
  any time zone are not used: the street's sun is a fixed mid-latitude summer day). Without a TimeOfDay, a
  ``Sun@elevation`` (rad) picks the hour at which that sun stands that high — in the morning if its azimuth lies
  east (0 < azimuth < π, OpenSCENARIO's azimuth is 0 north, π/2 east), else in the afternoon; a sun below the
  horizon gives night (22 h).
- ``Precipitation@precipitationIntensity`` is mm/h (1.1+). The deprecated 1.0 ``@intensity`` (0…1) maps onto
  the same 0…1 scale the presets span: rate = 50·intensity² mm/h (0.1 → 0.5 drizzle, 0.2 → 2 moderate,
  0.4 → 8 heavy, 1 → 50 extreme), with a warning. ``precipitationType`` snow is refused; dry means 0 mm/h.
- ``Fog@visualRange`` (m) is the meteorological optical range of the whole atmosphere (5 % contrast): the rain's
  own extinction at its rate counts towards it and haze (``atmosphere.haze_per_km``) makes up the rest; if the
  rain alone already sees less far, a warning says so and the rain is kept.
- ``RoadCondition@wetness`` (1.2) pins the road's water levels (``rain.wetness/cracks/puddles``, unpin them in the
  Rain Manager to let the weather drive them again) and sets how much of the road can flood
  (``road.puddle_amount``); ``@frictionScaleFactor`` goes to ``road.friction_scale``.
"""

from __future__ import annotations

import math

# RoadCondition@wetness → (wetness, cracks, puddles, puddle_amount)
WETNESS_LEVELS = {
    "dry": (0.0, 0.0, 0.0, None),
    "moist": (0.6, 0.0, 0.0, None),
    "wetWithPuddles": (1.0, 1.0, 0.6, 0.5),
    "lowFlooded": (1.0, 1.0, 1.0, 0.7),
    "highFlooded": (1.0, 1.0, 1.0, 1.0),
}
DEPRECATED_INTENSITY_MAX_MM_H = 50.0


def wind_direction_deg(heading_rad: float) -> float:
    """OpenSCENARIO wind heading (rad, from +x towards +y, the way it blows) → wind.direction_deg."""
    return (90.0 - math.degrees(heading_rad)) % 360.0


def wind_heading_rad(direction_deg: float) -> float:
    """wind.direction_deg → OpenSCENARIO heading (rad, in [0, 2π))."""
    return math.radians((90.0 - direction_deg) % 360.0)


def rate_from_intensity(intensity: float) -> float:
    """The deprecated 0…1 ``intensity`` → mm/h: 50·intensity² (the presets' 0.5 … 50 mm/h spread)."""
    return DEPRECATED_INTENSITY_MAX_MM_H * intensity * intensity


def hour_from_iso(text: str) -> float:
    """Hours of the day in an ISO 8601 date-time ("2021-06-25T17:30:00", a zone suffix ignored)."""
    from datetime import datetime

    clean = text.strip()
    if clean.endswith("Z"):
        clean = clean[:-1]
    stamp = datetime.fromisoformat(clean)
    return stamp.hour + stamp.minute / 60.0 + (stamp.second + stamp.microsecond * 1e-6) / 3600.0


def iso_from_hour(hour: float) -> str:
    h = int(hour) % 24
    minutes = (hour - int(hour)) * 60.0
    m = int(minutes)
    s = int(round((minutes - m) * 60.0))
    if s == 60:
        m, s = m + 1, 0
    if m == 60:
        h, m = (h + 1) % 24, 0
    return f"2026-06-21T{h:02d}:{m:02d}:{s:02d}"


def hour_from_sun(elevation_rad: float, azimuth_rad: float | None) -> float:
    """The hour at which the street's sun (rain_core.lighting.sun_elevation_deg) stands at elevation_rad: in the
    morning when the azimuth lies east, else in the afternoon; 22 h for a sun below the horizon."""
    elevation = math.degrees(elevation_rad)
    if elevation <= 0.0:
        return 22.0
    fraction = math.asin(min(elevation / 62.0, 1.0)) / math.pi  # elevation = 62°·sin(π(h − 6)/12)
    morning = azimuth_rad is not None and 0.0 < (azimuth_rad % (2 * math.pi)) < math.pi
    return 6.0 + 12.0 * fraction if morning else 18.0 - 12.0 * fraction


def wetness_name(wetness: float | None, cracks: float | None, puddles: float | None) -> str:
    """The RoadCondition@wetness word nearest the road's pinned levels (unpinned levels count as dry)."""
    w, c, p = (v or 0.0 for v in (wetness, cracks, puddles))
    if p >= 0.95 and c >= 0.95:
        return "lowFlooded"
    if p > 0.0 or c > 0.0:
        return "wetWithPuddles"
    if w > 0.0:
        return "moist"
    return "dry"
