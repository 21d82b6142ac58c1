"""Time of day → sun, sky and exposure; street lamps and headlights → the shader's light list.

Radiometry is photometric and physical in scale: illuminance in lux, luminance in cd/m², light intensity in cd.
The exposure follows an incident-light meter (EV100 = log2(E/2.5)), so noon and a lamp-lit night both land in
the tone mapper's range without per-scene tweaks. Geography: +X is east, +Z is south (noon sun to the south).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from rain_core import jit
from rain_core.lighting_kernels import gather_nearest, vehicle_lights

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


_LIGHTING_CACHE: dict[tuple[float, float], Lighting] = {}


def lighting_for_hour(hour: float, overcast: float = 0.0) -> Lighting:
    """Sun and sky for ``hour`` in [0, 24) (12 = noon, 22 = night). ``overcast`` in [0, 1] dims and greys the sun
    and sky (the atmosphere effect drives it from the rain). The result's arrays are read-only: a frame's
    lighting is the same object while the hour and the overcast stay (every frame at a fixed hour)."""
    if not math.isfinite(hour):
        raise ValueError(f"hour must be finite, got {hour!r}")
    key = (float(hour), float(overcast))
    lighting = _LIGHTING_CACHE.get(key)
    if lighting is None:
        if len(_LIGHTING_CACHE) > 64:
            _LIGHTING_CACHE.clear()
        lighting = _LIGHTING_CACHE[key] = _lighting_for_hour(*key)
        for array in (lighting.sun_direction, lighting.sun_illuminance, lighting.sky_zenith, lighting.sky_horizon):
            array.flags.writeable = False
    return lighting


def _lighting_for_hour(hour: float, overcast: float) -> Lighting:
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


def with_sky_light(lighting: Lighting, sky_cd_m2) -> Lighting:
    """``lighting`` with ``sky_cd_m2`` (cd/m², RGB) added to the sky's zenith and horizon (a lightning flash lighting
    the cloud base): the sky, the airlight and the ambient light follow; the exposure does not (an eye or a
    camera does not adapt within a flash)."""
    add = np.asarray(sky_cd_m2, dtype=np.float64)
    return dataclasses.replace(lighting, sky_zenith=lighting.sky_zenith + add, sky_horizon=lighting.sky_horizon + add)


# Cone cosines of the light kinds (shaders/common/lighting.glsl reads cos_outer, cos_inner per light).
_LAMP_CONE = (math.cos(math.radians(75)), math.cos(math.radians(55)), 70.0)  # cos_outer, cos_inner, range m
_HEAD_CONE = (math.cos(math.radians(30)), math.cos(math.radians(12)), 150.0)
_TAIL_CONE = (-0.2, 0.3, 20.0)
_HEAD_CD, _HEAD_COLOR = 20000.0, (1.0, 0.96, 0.88)
_TAIL_CD, _TAIL_COLOR = 60.0, (1.0, 0.05, 0.02)


class LightSet:
    """Lights as parallel arrays (what the renderer packs every frame without a Python object per light):
    ``position`` (L, 3) m, ``direction`` (L, 3), ``intensity_cd`` (L,), ``color`` (L, 3), ``cos_outer``,
    ``cos_inner``, ``range_m`` (L,), ``low_beam`` (L,) bool."""

    __slots__ = ("position", "direction", "intensity_cd", "color", "cos_outer", "cos_inner", "range_m", "low_beam",
                 "_rows")

    def __init__(self, position, direction, intensity_cd, color, cos_outer, cos_inner, range_m, low_beam):
        self.position, self.direction, self.intensity_cd, self.color = position, direction, intensity_cd, color
        self.cos_outer, self.cos_inner, self.range_m, self.low_beam = cos_outer, cos_inner, range_m, low_beam
        self._rows = None

    def packed_rows(self) -> np.ndarray:
        """(3, L, 4) float32: every light as ``pack_lights`` writes it (pos + range, dir + cos_outer, colour·cd +
        cos_inner), made once (the arrays are not edited after construction)."""
        if self._rows is None:
            rows = np.empty((3, len(self), 4), np.float32)
            rows[0, :, :3] = self.position
            rows[0, :, 3] = np.where(self.low_beam, -self.range_m, self.range_m)
            rows[1, :, :3] = self.direction
            rows[1, :, 3] = self.cos_outer
            rows[2, :, :3] = self.color * self.intensity_cd[:, None]
            rows[2, :, 3] = self.cos_inner
            self._rows = rows
        return self._rows

    def __len__(self) -> int:
        return len(self.intensity_cd)

    def take(self, index: np.ndarray) -> LightSet:
        return LightSet(*(getattr(self, name)[index] for name in _FIELDS))

    def to_lights(self) -> list[Light]:
        return [Light(self.position[i].copy(), self.direction[i].copy(), float(self.intensity_cd[i]),
                      self.color[i].copy(), float(self.cos_outer[i]), float(self.cos_inner[i]),
                      float(self.range_m[i]), bool(self.low_beam[i])) for i in range(len(self))]


_FIELDS = LightSet.__slots__[:-1]  # the per-light arrays, in the constructor's order


def _kind(position, direction, cd, color, cone, low_beam: bool) -> LightSet:
    k = len(position)
    return LightSet(position, direction, np.broadcast_to(np.asarray(cd, np.float64), (k,)),
                    np.broadcast_to(np.asarray(color, np.float64), (k, 3)), np.full(k, cone[0]), np.full(k, cone[1]),
                    np.full(k, cone[2]), np.full(k, low_beam))


_LAMP_TABLES: dict[int, tuple[object, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}


def _lamp_table(lamps) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(positions, directions, cd, colours) of a lamp list, built once per list (a world's lamps never move)."""
    entry = _LAMP_TABLES.get(id(lamps))
    if entry is None or entry[0] is not lamps:
        if len(_LAMP_TABLES) > 8:
            _LAMP_TABLES.clear()
        entry = (lamps, np.array([np.asarray(lamp.position, float) for lamp in lamps]).reshape(-1, 3),
                 np.array([np.asarray(lamp.direction, float) for lamp in lamps]).reshape(-1, 3),
                 np.array([float(lamp.intensity_cd) for lamp in lamps]),
                 np.array([np.asarray(lamp.color, float) for lamp in lamps]).reshape(-1, 3))
        _LAMP_TABLES[id(lamps)] = entry
    return entry[1:]


_LENS_TABLES: dict = {}


def _lens_table(spec) -> np.ndarray:
    """(4, 3) local lens centres of a vehicle spec, heads then tails (``vehicles.light_positions_local``)."""
    table = _LENS_TABLES.get(id(spec))
    if table is None or table[0] is not spec:
        from rain_core.vehicles import light_positions_local

        table = _LENS_TABLES[id(spec)] = (spec, np.concatenate(light_positions_local(spec)))
    return table[1]


_VEHICLE_TABLES: dict = {}


def _vehicle_table(vehicles) -> tuple:
    """What the lights of a vehicle list hold whatever the vehicles do, built once per list of specs: local lens
    centres (n, 4, 3) and, per light (4n: two heads then two tails per vehicle), cd, colour, cones and kind."""
    specs = tuple(v.spec for v in vehicles)
    key = tuple(id(spec) for spec in specs)
    entry = _VEHICLE_TABLES.get(key)
    if entry is None or any(a is not b for a, b in zip(entry[0], specs, strict=True)):
        if len(_VEHICLE_TABLES) > 8:
            _VEHICLE_TABLES.clear()
        n = len(specs)
        is_head = np.tile([True, True, False, False], n)
        entry = _VEHICLE_TABLES[key] = (
            specs, np.stack([_lens_table(spec) for spec in specs]), is_head,
            np.where(is_head, _HEAD_CD, _TAIL_CD), np.where(is_head[:, None], _HEAD_COLOR, _TAIL_COLOR),
            np.where(is_head, _HEAD_CONE[0], _TAIL_CONE[0]), np.where(is_head, _HEAD_CONE[1], _TAIL_CONE[1]),
            np.where(is_head, _HEAD_CONE[2], _TAIL_CONE[2]))
        for array in entry[1:]:
            array.flags.writeable = False  # shared by every frame's light set
    return entry[1:]


def light_candidates(lamps, vehicles, camera_z_m: float, lighting: Lighting, shift_z: float, period_m: float,
                     headlights_on: bool) -> LightSet:
    """Every light that may reach the camera's surroundings, in the wrapped frame (world z − ``shift_z``), before
    the nearest are chosen: street lamps of the tiles within 250 m along z of ``camera_z_m`` (wrapped) at night,
    and the vehicles' head and tail lights when ``headlights_on``."""
    parts: list[LightSet] = []
    if lighting.night_factor > 0.01 and len(lamps):
        pos, dirs, cd, color = _lamp_table(lamps)
        offsets = np.array([[0.0, 0.0, k * period_m] for k in (-1, 0, 1)])
        tiles = (pos[:, None, :] + offsets[None, :, :]).reshape(-1, 3)  # lamp-major, as the list was built
        index = np.flatnonzero(np.abs(tiles[:, 2] - camera_z_m) < 250.0)
        lamp = index // 3
        parts.append(_kind(tiles[index], dirs[lamp], cd[lamp] * lighting.night_factor, color[lamp], _LAMP_CONE,
                           False))
    if headlights_on and vehicles:
        from rain_core.vehicles import HEADLIGHT_PITCH_RAD

        n = len(vehicles)
        local, is_head, cd, color, cos_outer, cos_inner, range_m = _vehicle_table(vehicles)
        yaw = np.fromiter((v.yaw for v in vehicles), dtype=np.float64, count=n)
        centre = np.array([v.position for v in vehicles], dtype=np.float64).reshape(n, 3)
        cos, sin = np.cos(yaw), np.sin(yaw)
        pitch_c, pitch_s = math.cos(HEADLIGHT_PITCH_RAD), math.sin(HEADLIGHT_PITCH_RAD)
        if jit.active():  # one call (lighting_kernels.vehicle_lights) for the NumPy below, its twin
            pos, dirs = np.empty((4 * n, 3)), np.empty((4 * n, 3))
            vehicle_lights(cos, sin, centre, local, float(shift_z), pitch_c, pitch_s, pos, dirs)
        else:
            c, s_ = cos[:, None], sin[:, None]
            # Vehicle.model_matrix: rotation about +Y by yaw, [[c, 0, s], [0, 1, 0], [−s, 0, c]], then the position.
            # Written into one array, not np.stack'ed (its Python-level wrapper cost a third of this function).
            lx, ly, lz = local[..., 0], local[..., 1], local[..., 2]
            pos = np.empty((n, 4, 3))
            pos[..., 0] = c * lx + s_ * lz + centre[:, None, 0]
            pos[..., 1] = ly + centre[:, None, 1]
            pos[..., 2] = -s_ * lx + c * lz + centre[:, None, 2]
            pos = pos.reshape(4 * n, 3)
            pos[:, 2] -= shift_z
            fwd = np.empty((n, 3))  # Vehicle.forward(): (−sin, 0, −cos)
            fwd[:, 0], fwd[:, 1], fwd[:, 2] = -sin, 0.0, -cos
            head_dir = fwd * pitch_c + np.array([0.0, pitch_s, 0.0])
            dirs = np.empty((n, 4, 3))
            dirs[:, 0] = dirs[:, 1] = head_dir
            dirs[:, 2] = dirs[:, 3] = -fwd
            dirs = dirs.reshape(4 * n, 3)
        parts.append(LightSet(pos, dirs, cd, color, cos_outer, cos_inner, range_m, is_head))
    if not parts:
        return _kind(np.zeros((0, 3)), np.zeros((0, 3)), 0.0, (0.0, 0.0, 0.0), (-1.0, -1.0, 0.0), False)
    return parts[0] if len(parts) == 1 else LightSet(
        *(np.concatenate([getattr(part, name) for part in parts]) for name in _FIELDS))


def concat_lights(sets) -> LightSet:
    """One LightSet of several, in order."""
    sets = list(sets)
    if len(sets) == 1:
        return sets[0]
    return LightSet(*(np.concatenate([getattr(s, name) for s in sets]) for name in _FIELDS))


def wrap_lights(lights: LightSet, shift_z: float) -> LightSet:
    """The same lights with world positions moved into the renderer's wrapped frame (z − shift_z, m)."""
    if shift_z == 0.0:
        return lights
    position = np.array(lights.position, dtype=np.float64)
    position[:, 2] -= shift_z
    return LightSet(position, *(getattr(lights, name) for name in _FIELDS[1:]))


def nearest_lights(lights: LightSet, camera_position_wrapped, max_lights: int = MAX_LIGHTS) -> LightSet:
    """The ``max_lights`` of ``lights`` nearest to the camera (wrapped frame), nearest first (stable order)."""
    cam = np.asarray(camera_position_wrapped, dtype=np.float64)
    order = ((lights.position - cam) ** 2).sum(axis=1).argsort(kind="stable")[:max_lights]  # methods: no wrappers
    return lights.take(order)


def pack_nearest(lights: LightSet, camera_position_wrapped, max_lights: int = MAX_LIGHTS) -> tuple:
    """``pack_lights(nearest_lights(lights, camera, max_lights), max_lights)``, the same bytes, gathered from the
    set's rows packed once (``packed_rows``): the renderer packs each view's lights every frame (main and road
    mirror) from one candidate set."""
    cam = np.asarray(camera_position_wrapped, dtype=np.float64)
    if jit.active():
        # one call (lighting_kernels.gather_nearest) into a buffer kept per size: the bytes returned are copies
        packed = _PACKED.get(max_lights)
        if packed is None:
            packed = _PACKED[max_lights] = np.zeros((3, max_lights, 4), np.float32)
        count = gather_nearest(lights.position, cam, lights.packed_rows(), packed)
        data, size = packed.tobytes(), 16 * max_lights
        return data[:size], data[size:2 * size], data[2 * size:], count
    order = ((lights.position - cam) ** 2).sum(axis=1).argsort(kind="stable")[:max_lights]  # methods: no wrappers
    packed = np.zeros((3, max_lights, 4), np.float32)
    packed[:, : len(order)] = lights.packed_rows()[:, order]
    return packed[0].tobytes(), packed[1].tobytes(), packed[2].tobytes(), len(order)


_PACKED: dict[int, np.ndarray] = {}  # max_lights → pack_nearest's kernel output, reused (its bytes are copied)


def light_set_for_frame(lamps, vehicles, camera_position, lighting: Lighting, shift_z: float, period_m: float,
                        headlights_on: bool, max_lights: int = MAX_LIGHTS) -> LightSet:
    """``lights_for_frame`` as a ``LightSet`` (arrays, vectorised): what the renderer uses every frame."""
    cam = np.asarray(camera_position, dtype=np.float64) - np.array([0.0, 0.0, shift_z])
    candidates = light_candidates(lamps, vehicles, float(cam[2]), lighting, shift_z, period_m, headlights_on)
    return nearest_lights(candidates, cam, max_lights)


def lights_for_frame(lamps, vehicles, camera_position, lighting: Lighting, shift_z: float, period_m: float,
                     headlights_on: bool, max_lights: int = MAX_LIGHTS) -> list[Light]:
    """Collect street lamps (one world tile, repeated every ``period_m``) and vehicle head/tail lights, nearest to
    the camera first. Positions are returned in the renderer's wrapped frame (world z − ``shift_z``)."""
    return light_set_for_frame(lamps, vehicles, camera_position, lighting, shift_z, period_m, headlights_on,
                               max_lights).to_lights()


def pack_lights(lights, max_lights: int = MAX_LIGHTS) -> tuple[bytes, bytes, bytes, int]:
    """Uniform arrays for shaders/common/lighting.glsl: pos+range, dir+cos_outer, colour·cd+cos_inner.
    ``lights``: a list of ``Light`` or a ``LightSet``."""
    if not isinstance(lights, LightSet):
        lights = list(lights)[:max_lights]
        if not lights:
            lights = _kind(np.zeros((0, 3)), np.zeros((0, 3)), 0.0, (0.0, 0.0, 0.0), (-1.0, -1.0, 0.0), False)
        else:
            lights = LightSet(np.array([lt.position for lt in lights], float),
                              np.array([lt.direction for lt in lights], float),
                              np.array([lt.intensity_cd for lt in lights], float),
                              np.array([lt.color for lt in lights], float),
                              np.array([lt.cos_outer for lt in lights], float),
                              np.array([lt.cos_inner for lt in lights], float),
                              np.array([lt.range_m for lt in lights], float),
                              np.array([lt.low_beam for lt in lights], bool))
    count = min(len(lights), max_lights)
    packed = np.zeros((3, max_lights, 4), np.float32)
    if count:
        if count < len(lights):
            lights = lights.take(np.arange(count))
        packed[0, :count, :3] = lights.position
        packed[0, :count, 3] = np.where(lights.low_beam, -lights.range_m, lights.range_m)
        packed[1, :count, :3] = lights.direction
        packed[1, :count, 3] = lights.cos_outer
        packed[2, :count, :3] = lights.color * lights.intensity_cd[:, None]
        packed[2, :count, 3] = lights.cos_inner
    return packed[0].tobytes(), packed[1].tobytes(), packed[2].tobytes(), count
