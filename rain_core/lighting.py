"""Time of day → sun, sky and exposure; street lamps and headlights → the shader's light list.

Radiometry is photometric and physical in scale: illuminance in lux, luminance in cd/m², light intensity in cd.
The exposure follows an incident-light meter (EV100 = log2(E/2.5)), so noon and a lamp-lit night both land in
the tone mapper's range without per-scene tweaks. Geography: +X is east, +Z is south (noon sun to the south).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MAX_LIGHTS = 32  # per frame, nearest to the camera; keep in sync with shaders/common/lighting.glsl


@dataclass(frozen=True)
class Light:
    """A point or spot light. position (m), direction (unit), intensity (cd, on axis), colour (linear RGB, ~1),
    cos_outer/cos_inner of the cone (−1 for an omnidirectional point light), range (m) beyond which it is cut."""

    position: np.ndarray
    direction: np.ndarray
    intensity_cd: float
    color: np.ndarray
    cos_outer: float = -1.0
    cos_inner: float = -1.0
    range_m: float = 80.0
    low_beam: bool = False  # a headlight: the shader applies a vertical cut-off below the horizon


@dataclass(frozen=True)
class Lighting:
    hour: float
    sun_direction: np.ndarray  # unit vector towards the sun
    sun_illuminance: np.ndarray  # lux, linear RGB (perpendicular to the rays)
    sky_zenith: np.ndarray  # cd/m², linear RGB
    sky_horizon: np.ndarray  # cd/m²
    ground_albedo: float
    night_factor: float  # 0 by day, 1 by night: lamps on, lit windows
    ev100: float

    @property
    def exposure(self) -> float:
        """Multiplier from luminance (cd/m²) to tone-mapper input (saturation-based, ISO 100)."""
        return 1.0 / (1.2 * 2.0 ** self.ev100)


def _smoothstep(e0, e1, x):
    t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def sun_elevation_deg(hour: float) -> float:
    """A mid-latitude summer day: sunrise 6 h, noon 62°, sunset 18 h, −35° at midnight."""
    return 62.0 * math.sin(math.pi * (hour - 6.0) / 12.0) if 6.0 <= hour <= 18.0 else \
        -35.0 * math.sin(math.pi * ((hour - 18.0) % 24.0) / 12.0)


def lighting_for_hour(hour: float, overcast: float = 0.0) -> Lighting:
    """Sun and sky for ``hour`` in [0, 24) (12 = noon, 22 = night). ``overcast`` in [0, 1] dims and greys the sun
    and sky (the atmosphere effect drives it from the rain)."""
    if not math.isfinite(hour):
        raise ValueError(f"hour must be finite, got {hour!r}")
    hour = hour % 24.0
    elev = math.radians(sun_elevation_deg(hour))
    azim = math.pi * (hour - 6.0) / 12.0  # east (+X) at 6 h, south (+Z) at noon, west at 18 h
    sun_dir = np.array([math.cos(elev) * math.cos(azim), math.sin(elev), math.cos(elev) * math.sin(azim)])
    sin_e = max(math.sin(elev), 0.0)
    # Air mass reddens and dims a low sun; a clear-sky noon sun gives ~100 klux.
    elev_deg = max(math.degrees(elev), 0.0)
    air_mass = 1.0 / (sin_e + 0.50572 * (elev_deg + 6.07995) ** -1.6364)  # Kasten & Young (1989)
    extinction = np.array([0.08, 0.13, 0.26])  # per air mass, R G B
    above = _smoothstep(-2.0, 3.0, math.degrees(elev))
    sun = 115000.0 * np.exp(-extinction * air_mass) * above
    sun *= 1.0 - 0.92 * overcast
    day = _smoothstep(-8.0, 8.0, math.degrees(elev))
    twilight = _smoothstep(-14.0, -2.0, math.degrees(elev)) * (1.0 - day)
    zenith = (np.array([0.28, 0.45, 0.95]) * 6500.0 * day * (0.3 + 0.7 * sin_e ** 0.5)
              + np.array([0.35, 0.35, 0.6]) * 25.0 * twilight + np.array([0.02, 0.025, 0.05]))
    horizon = (np.array([0.75, 0.82, 1.0]) * 9000.0 * day * (0.35 + 0.65 * sin_e ** 0.5)
               + np.array([1.0, 0.55, 0.3]) * 60.0 * twilight + np.array([0.06, 0.05, 0.05]))
    grey = np.array([0.8, 0.82, 0.85])
    mean_z, mean_h = zenith.mean(), horizon.mean()
    zenith = zenith * (1 - overcast) + grey * mean_z * 0.55 * overcast
    horizon = horizon * (1 - overcast) + grey * mean_h * 0.6 * overcast
    night = 1.0 - _smoothstep(-6.0, 4.0, math.degrees(elev))
    # Metered illuminance on the ground: sun + sky (π·L for a uniform hemisphere) + lamp-lit street at night.
    e_key = float(sun.mean() * sin_e + math.pi * 0.5 * (zenith.mean() + horizon.mean()) + 120.0 * night)
    ev100 = math.log2(max(e_key, 1e-3) / 2.5)
    return Lighting(hour, sun_dir, sun, zenith, horizon, 0.15, night, ev100)


def lights_for_frame(lamps, vehicles, camera_position, lighting: Lighting, shift_z: float, period_m: float,
                     headlights_on: bool, max_lights: int = MAX_LIGHTS) -> list[Light]:
    """Collect street lamps (one world tile, repeated every ``period_m``) and vehicle head/tail lights, nearest to
    the camera first. Positions are returned in the renderer's wrapped frame (world z − ``shift_z``)."""
    cam = np.asarray(camera_position, dtype=np.float64) - np.array([0.0, 0.0, shift_z])
    lights: list[Light] = []
    if lighting.night_factor > 0.01:
        for lamp in lamps:
            p = np.asarray(lamp.position, dtype=np.float64)
            for k in (-1, 0, 1):
                q = p + np.array([0.0, 0.0, k * period_m])
                if abs(q[2] - cam[2]) < 250.0:
                    lights.append(Light(q, np.asarray(lamp.direction, float), lamp.intensity_cd * lighting.night_factor,
                                        np.asarray(lamp.color, float), cos_outer=math.cos(math.radians(75)),
                                        cos_inner=math.cos(math.radians(55)), range_m=70.0))
    if headlights_on:
        for v in vehicles:
            for pos, direction in v.headlights():
                q = np.asarray(pos, dtype=np.float64) - np.array([0.0, 0.0, shift_z])
                lights.append(Light(q, np.asarray(direction, float), 20000.0, np.array([1.0, 0.96, 0.88]),
                                    cos_outer=math.cos(math.radians(30)), cos_inner=math.cos(math.radians(12)),
                                    range_m=150.0, low_beam=True))
            for pos in v.taillights():
                q = np.asarray(pos, dtype=np.float64) - np.array([0.0, 0.0, shift_z])
                lights.append(Light(q, -v.forward(), 60.0, np.array([1.0, 0.05, 0.02]),
                                    cos_outer=-0.2, cos_inner=0.3, range_m=20.0))
    lights.sort(key=lambda light: float(np.sum((light.position - cam) ** 2)))
    return lights[:max_lights]


def pack_lights(lights: list[Light], max_lights: int = MAX_LIGHTS) -> tuple[bytes, bytes, bytes, int]:
    """Uniform arrays for shaders/common/lighting.glsl: pos+range, dir+cos_outer, colour·cd+cos_inner."""
    pos = np.zeros((max_lights, 4), np.float32)
    dirs = np.zeros((max_lights, 4), np.float32)
    col = np.zeros((max_lights, 4), np.float32)
    for i, light in enumerate(lights[:max_lights]):
        pos[i] = (*light.position, -light.range_m if light.low_beam else light.range_m)
        dirs[i] = (*light.direction, light.cos_outer)
        col[i] = (*(light.color * light.intensity_cd), light.cos_inner)
    return pos.tobytes(), dirs.tobytes(), col.tobytes(), min(len(lights), max_lights)
