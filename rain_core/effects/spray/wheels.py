"""The wheels: the water model at each contact patch (film depth, the budget it makes, the hydroplaning risk) and
the per-wheel geometry the launches use."""

from __future__ import annotations

from dataclasses import astuple, dataclass

import numpy as np

from rain_core import jit, physics
from rain_core.effects.spray import kernels, water
from rain_core.effects.spray.body import BodyBox
from rain_core.effects.spray.water import (
    TYRE_PRESSURE_KPA,
    WaterBudget,
    allocate_water,
    allocate_water_unchecked,
    hydroplaning_risk,
    hydroplaning_risk_unchecked,
    hydroplaning_speed_m_s,
)
from rain_core.gutter import frame_spread_coefficient
from rain_core.water_film import film_depth_sampler


def road_film_depth_fn(frame):
    """The film depth (mm) under points x, z (m) for this frame: ``rain_core.water_film.film_depth_mm``, the one
    model of the film the road draws (standing water in cracks and puddles from the weather's flood levels and
    settings.road's puddle map, and the wet film of the weather's wetness, none under roofs). Returns a callable
    (x, z) → mm."""
    weather = getattr(frame, "weather", None)
    wetness = float(getattr(weather, "wetness", 0.0) or 0.0)
    cracks = float(getattr(weather, "cracks", 0.0) or 0.0)
    puddles = float(getattr(weather, "puddles", 0.0) or 0.0)
    road_settings = getattr(getattr(frame, "settings", None), "road", None)
    amount = float(getattr(road_settings, "puddle_amount", 0.5))
    seed = int(getattr(road_settings, "puddle_seed", 0))
    world = getattr(frame, "world", None)
    gutter_k = frame_spread_coefficient(frame)  # the kerb streams: more water, more spray near the kerb
    # The sampler (its arguments checked once) is kept while they stay the same: the weather's levels change
    # slowly, or not at all once settled or pinned.
    key = (wetness, cracks, puddles, amount, seed, gutter_k)
    hit = _SAMPLER_CACHE.get(key)
    if hit is None or hit[0] is not world:
        if len(_SAMPLER_CACHE) > 16:
            _SAMPLER_CACHE.clear()
        hit = (world, film_depth_sampler(cracks, puddles, puddle_amount=amount, seed=seed, world=world,
                                         wetness=wetness, gutter_k=gutter_k))
        _SAMPLER_CACHE[key] = hit
    sampler = hit[1]

    def depth(x, z):
        x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
        if x.shape != z.shape:
            x, z = np.broadcast_arrays(x, z)
        return sampler(x, z)

    return depth


_SAMPLER_CACHE: dict[tuple, tuple] = {}  # road_film_depth_fn's arguments → (world, film_depth_sampler)


@dataclass
class WheelWater:
    """One vehicle's four wheels this frame (FL, FR, RL, RR). contacts (4, 3) m; speed_m_s (4,) signed;
    width_m (4,) m of tread meeting the water (a lorry's twin rear tyres count twice); film_depth_mm (4,);
    budget: WaterBudget over the 4 wheels (kg/s); hydroplaning_risk (4,) in [0, 1]."""

    vehicle: object
    contacts: np.ndarray
    speed_m_s: np.ndarray
    width_m: np.ndarray
    film_depth_mm: np.ndarray
    budget: WaterBudget
    hydroplaning_risk: np.ndarray


def wheel_water(vehicle, depth_fn) -> WheelWater:
    """The water model at a vehicle's wheels; depth_fn(x, z) → film depth (mm) at world points (m)."""
    contacts = np.asarray(vehicle.wheel_contacts(), dtype=np.float64)
    speeds = np.asarray(vehicle.wheel_speeds(), dtype=np.float64)
    widths = np.asarray(vehicle.wheel_widths(), dtype=np.float64).copy()
    if getattr(vehicle.spec, "kind", "car") == "truck":
        widths[2:] *= 2.0  # a lorry's rear axle runs twin tyres
    depth_mm = np.maximum(np.asarray(depth_fn(contacts[:, 0], contacts[:, 2]), dtype=np.float64), 0.0)
    budget = allocate_water(speeds, widths, depth_mm * 1e-3)
    pressure = TYRE_PRESSURE_KPA.get(getattr(vehicle.spec, "kind", "car"), TYRE_PRESSURE_KPA["car"])
    risk = hydroplaning_risk(speeds, depth_mm * 1e-3, pressure)
    return WheelWater(vehicle, contacts, speeds, widths, depth_mm, budget, risk)


MAX_VEHICLE_SPEED_M_S = 1000.0  # m/s; a vehicle (or a wind) faster than this is refused at the frame boundary
MAX_FILM_DEPTH_MM = 1000.0  # mm; a depth override deeper than this counts as this deep
MAX_POSITION_M = 1e7  # m; farther out the parcels' float32 period index (z / PERIOD_M) would lose whole periods
# |x|, |z|, |yaw|, |speed|, |yaw rate|, |y| allowed (yaw: any finite angle)
_STATE_LIMITS = np.array([MAX_POSITION_M, MAX_POSITION_M, np.finfo(np.float64).max, MAX_VEHICLE_SPEED_M_S,
                          MAX_VEHICLE_SPEED_M_S / 10.0, MAX_POSITION_M])


class WheelGeometry:
    """Per-vehicle (V) and per-wheel (W = 4·V, order FL, FR, RL, RR per vehicle) arrays for vectorised
    launches: built from per-vehicle ``WheelWater`` (the reference path) or by :func:`gather_wheels`."""

    position: np.ndarray  # (V, 3) m
    velocity: np.ndarray  # (V, 3) m/s of the body centre
    forward: np.ndarray  # (V, 3) unit
    right: np.ndarray  # (V, 3) unit
    height: np.ndarray  # (V,) m
    half_length: np.ndarray  # (V,) m
    box_index: np.ndarray  # (V,) into ``boxes``
    boxes: list  # BodyBox per distinct spec
    box_params: np.ndarray  # (V, 8) the BodyBox fields of each vehicle, in field order
    contacts: np.ndarray  # (W, 3) m
    speed: np.ndarray  # (W,) m/s, |ground speed|
    travel: np.ndarray  # (W, 3) unit, the direction the wheel rolls
    outward: np.ndarray  # (W, 3) unit, away from the vehicle's centre line
    radius: np.ndarray  # (W,) m
    width: np.ndarray  # (W,) m
    wheel_velocity: np.ndarray  # (W, 3) m/s, the body centre's velocity per wheel
    extra_depth_mm: np.ndarray  # film depth (mm) at the extra points looked up with the wheels (gather_wheels)
    buckets: np.ndarray  # (W, 6) kg/s, the water budget's buckets of every wheel
    wheel_parts: tuple  # what wheel_list makes the per-vehicle WheelWater of (gather_wheels)
    available: np.ndarray  # (W,) kg/s, M_w of every wheel
    throwing: bool  # whether any wheel throws water (gather_wheels)

    def __init__(self, wheels: list[WheelWater] | None = None):
        if wheels is None:
            return
        vehicles = [w.vehicle for w in wheels]
        self.position = np.array([v.position for v in vehicles], dtype=np.float64)
        self.velocity = np.array([v.velocity() for v in vehicles], dtype=np.float64)
        self.forward = np.array([v.forward() for v in vehicles], dtype=np.float64)
        self.right = np.array([v.right() for v in vehicles], dtype=np.float64)
        self.height = np.array([v.spec.height_m for v in vehicles])
        self.half_length = np.array([v.spec.length_m / 2.0 for v in vehicles])
        specs = []
        self.box_index = np.zeros(len(vehicles), dtype=np.int64)
        for i, v in enumerate(vehicles):
            if v.spec not in specs:
                specs.append(v.spec)
            self.box_index[i] = specs.index(v.spec)
        self.boxes = [BodyBox.of(s) for s in specs]
        self.box_params = np.array([astuple(self.boxes[k]) for k in self.box_index], dtype=np.float64).reshape(-1, 8)
        self.contacts = np.concatenate([w.contacts for w in wheels])  # (W, 3)
        self.speed = np.abs(np.concatenate([w.speed_m_s for w in wheels]))
        sign = np.concatenate([np.where(w.speed_m_s < 0, -1.0, 1.0) for w in wheels])
        self.travel = np.repeat(self.forward, 4, axis=0) * sign[:, None]  # direction the wheel rolls
        self.outward = np.repeat(self.right, 4, axis=0) * np.tile([-1.0, 1.0, -1.0, 1.0], len(wheels))[:, None]
        self.radius = np.repeat([v.spec.wheel_radius_m for v in vehicles], 4)
        self.width = np.concatenate([w.width_m for w in wheels])
        self.wheel_velocity = np.repeat(self.velocity, 4, axis=0)
        self.buckets = np.concatenate([w.budget.buckets for w in wheels]).reshape(-1, 6)
        self.available = np.concatenate([w.budget.available for w in wheels])


class _Fleet:
    """Per-spec constants of a list of vehicles, stacked (cached while the vehicles' specs stay the same)."""

    def __init__(self, specs):
        from rain_core.vehicles import wheel_contacts_local

        n = len(specs)
        kinds = [getattr(sp, "kind", "car") for sp in specs]
        self.local = np.array([wheel_contacts_local(sp) for sp in specs], dtype=np.float64).reshape(n, 4, 3)
        widths = np.array([[sp.tire_width_m] * 4 for sp in specs], dtype=np.float64).reshape(n, 4)
        widths[:, 2:] *= np.array([2.0 if k == "truck" else 1.0 for k in kinds])[:, None]  # lorries: twin rears
        self.widths = widths.reshape(-1)
        self.pressure = np.repeat([TYRE_PRESSURE_KPA.get(k, TYRE_PRESSURE_KPA["car"]) for k in kinds], 4)
        self.planing_speed = hydroplaning_speed_m_s(self.pressure)  # m/s, per wheel
        self.consts = np.array([(sp.height_m, sp.length_m / 2.0, sp.wheel_radius_m, sp.wheelbase_m / 2.0)
                                for sp in specs], dtype=np.float64).reshape(n, 4)
        self.radius = np.repeat(self.consts[:, 2], 4)
        self.outward_sign = np.tile(_SIDE, n)[:, None]
        unique = []
        self.box_index = np.zeros(n, dtype=np.int64)
        for i, sp in enumerate(specs):
            if sp not in unique:
                unique.append(sp)
            self.box_index[i] = unique.index(sp)
        self.boxes = [BodyBox.of(sp) for sp in unique]
        table = np.array([astuple(b) for b in self.boxes], dtype=np.float64).reshape(-1, 8)
        self.box_params = table[self.box_index]
        # gather_wheels' tables before the frame's columns are written: the constant ones, and 0 in the rest.
        self.vehicle_template = np.zeros((n, 20))
        self.vehicle_template[:, 12:20] = self.box_params
        self.wheel_template = np.zeros((4 * n, 15))
        self.wheel_template[:, 12] = self.radius
        self.wheel_template[:, 13] = self.widths


_FLEETS: dict[tuple, tuple[list, _Fleet]] = {}
# kernels.wheel_water's tables: per mechanism its depth band (start, width, mm) and release ramp (start, span,
# m/s); ρ_w·1e-3, the tread spray ramp, the shares, the hydroplaning onset and drained depth, the depth cap.
_WATER_BANDS = np.column_stack([water._BAND_LO_MM, water._BAND_MM, water._RAMP_LO, water._RAMP_SPAN])
_WATER_CONSTS = np.array([physics.RHO_WATER * 1e-3, water._SPRAY_LO, water._SPRAY_SPAN, water.TREAD_SPRAY_SHARE,
                          1.0 - water.MIST_SHARE, water.MIST_SHARE, water.HYDRO_LIFT_ONSET,
                          1.0 - water.HYDRO_LIFT_ONSET, water.HYDRO_DEPTH_MM[0],
                          water.HYDRO_DEPTH_MM[1] - water.HYDRO_DEPTH_MM[0], MAX_FILM_DEPTH_MM])
_XYZ = [0, 5, 1]  # check_vehicles' columns x, y, z
_SIDE = np.array([-1.0, 1.0, -1.0, 1.0])


def _fleet(vehicles) -> _Fleet:
    specs = [v.spec for v in vehicles]
    key = tuple(id(sp) for sp in specs)
    hit = _FLEETS.get(key)
    if hit is None or any(a is not b for a, b in zip(hit[0], specs, strict=True)):
        if len(_FLEETS) > 64:
            _FLEETS.clear()
        hit = (specs, _Fleet(specs))
        _FLEETS[key] = hit
    return hit[1]


def check_vehicles(vehicles) -> np.ndarray:
    """(V, 6) float64 of each vehicle's x, z (m), yaw (rad), speed (m/s), yaw rate (rad/s) and y (m): the spray's
    boundary check of what the frame feeds it. ValueError naming the vehicle and field if any is not finite,
    a coordinate is beyond ±MAX_POSITION_M, or a speed (or the speed a yaw rate gives a wheel 10 m away) is
    beyond ±MAX_VEHICLE_SPEED_M_S."""
    state = np.array([(v.position[0], v.position[2], v.yaw, v.speed_m_s, getattr(v, "yaw_rate_rad_s", 0.0),
                       v.position[1]) for v in vehicles], dtype=np.float64).reshape(-1, 6)
    ok = np.abs(state) <= _STATE_LIMITS  # NaN compares False (without a warning): caught here too
    if not ok.all():
        i, j = (int(k) for k in np.argwhere(~ok)[0])
        name = ("position[0]", "position[2]", "yaw", "speed_m_s", "yaw_rate_rad_s", "position[1]")[j]
        limit = {0: f"within ±{MAX_POSITION_M:g} m", 1: f"within ±{MAX_POSITION_M:g} m",
                 3: f"within ±{MAX_VEHICLE_SPEED_M_S:g} m/s", 4: f"within ±{MAX_VEHICLE_SPEED_M_S / 10:g} rad/s",
                 5: f"within ±{MAX_POSITION_M:g} m"}
        raise ValueError(f"spray: vehicles[{i}].{name} must be finite{' and ' + limit[j] if j in limit else ''}, "
                         f"got {state[i, j]!r}")
    return state


def gather_wheels(vehicles, depth_fn, state=None, extra_xz=None,
                  build_wheels: bool = True) -> tuple[list[WheelWater] | None, WheelGeometry]:
    """The water model at every wheel of every vehicle in one pass (one film lookup for all wheels), and the
    launch geometry: what :func:`wheel_water` and ``WheelGeometry(wheels)`` give vehicle by vehicle (the
    reference; tests compare them). The rigid-body kinematics are ``Vehicle``'s (position, yaw, speed, yaw rate
    about the rear axle), evaluated for all vehicles at once. ``state``: :func:`check_vehicles`' array, if
    already made. depth_fn(x, z) → mm; a NaN depth counts as dry, a negative one as 0. ``extra_xz`` (k, 2) m:
    more points looked up in the same call, their depths (mm, unsanitised) in ``geo.extra_depth_mm``.
    ``build_wheels=False``: the per-vehicle list is not made (None in its place); :func:`wheel_list` makes it from
    the geometry when it is asked for."""
    n = len(vehicles)
    state = check_vehicles(vehicles) if state is None else state
    fleet = _fleet(vehicles)
    geo = WheelGeometry()
    px, pz, yaw, speed, omega, py = state.T
    c, s = np.cos(yaw), np.sin(yaw)
    # The launches' per-vehicle and per-wheel tables (spawn._vehicle_table, launch.wheel_table) are written here
    # column by column, from the fleet's templates (its constant columns filled, the y components of the
    # horizontal vectors 0), and the geometry's arrays are views of their columns: no column_stack per frame.
    vt = fleet.vehicle_template.copy()  # (V, 20) position, velocity, right, forward, box params
    wt = fleet.wheel_template.copy()  # (W, 15) velocity, contact, travel, outward, radius, width, speed
    w3 = wt.reshape(n, 4, 15)
    geo.position, geo.velocity, geo.right, geo.forward = vt[:, 0:3], vt[:, 3:6], vt[:, 6:9], vt[:, 9:12]
    geo.box_params = vt[:, 12:20]
    consts = fleet.consts
    geo.height, geo.half_length = consts[:, 0], consts[:, 1]
    geo._vehicle_consts = consts  # (V, 4) height, half length, …: the compiled launches read its rows
    compiled = jit.active()
    if compiled:  # the same arithmetic in one loop (the yaw's cosine and sine stay NumPy's, as the twin's)
        signed = np.empty(4 * n)
        kernels.wheel_kinematics(state, c, s, fleet.local, consts, fleet.outward_sign.reshape(-1), vt, wt, signed)
        contacts = wt[:, 3:6]
        geo.contacts, geo.speed = contacts, wt[:, 14]
    else:
        # Forward (−sin, 0, −cos) and right (cos, 0, −sin).
        np.negative(s, out=vt[:, 9])
        np.negative(c, out=vt[:, 11])
        vt[:, 6] = c
        vt[:, 8] = vt[:, 9]
        vt[:, 0:3] = state[:, _XYZ]
        local = fleet.local
        # Vehicle.to_world: rotation about +Y by yaw, then the translation.
        contacts = w3[:, :, 3:6]
        contacts[..., 0] = c[:, None] * local[..., 0] + s[:, None] * local[..., 2] + px[:, None]
        contacts[..., 1] = local[..., 1] + py[:, None]
        contacts[..., 2] = c[:, None] * local[..., 2] - s[:, None] * local[..., 0] + pz[:, None]
        contacts = wt[:, 3:6]
        geo.contacts = contacts
        # Vehicle._point_velocity: v·forward + ω ŷ × (p − rear axle), the rear axle wheelbase/2 behind the centre;
        # ŷ × (a, 0, c) = (c, 0, −a). (Its y component, 0·v + 0, is +0: the template's.)
        ax = px + s * consts[:, 3]
        az = pz + c * consts[:, 3]
        base = geo.forward * speed[:, None]
        np.add(base[:, 0], omega * (pz - az), out=vt[:, 3])
        np.add(base[:, 2], omega * (ax - px), out=vt[:, 5])
        wv = base.repeat(4, axis=0)  # (ndarray methods: np.repeat's Python wrapper costs more than the work)
        om4 = omega.repeat(4)
        wv[:, 0] += om4 * (contacts[:, 2] - az.repeat(4))
        wv[:, 2] -= om4 * (contacts[:, 0] - ax.repeat(4))
        backwards = np.where(speed < 0.0, -1.0, 1.0)
        geo.speed = wt[:, 14]
        np.sqrt(np.einsum("wc,wc->w", wv, wv), out=geo.speed)
        signed = geo.speed * backwards.repeat(4)
        # Per wheel: its vehicle's forward × the sign of travel, its right × the side, its velocity.
        w3[:, :, 6:9] = (geo.forward * backwards[:, None])[:, None, :]
        np.multiply(geo.right[:, None, :], fleet.outward_sign.reshape(n, 4, 1), out=w3[:, :, 9:12])
        w3[:, :, 0:3] = geo.velocity[:, None, :]
    geo.travel, geo.outward, geo.wheel_velocity = wt[:, 6:9], wt[:, 9:12], wt[:, 0:3]
    geo.radius, geo.width = wt[:, 12], wt[:, 13]
    geo._wheel_table, geo._vehicle_table = wt, vt
    geo.boxes, geo.box_index = fleet.boxes, fleet.box_index
    extra = np.zeros((0, 2)) if extra_xz is None else np.asarray(extra_xz, dtype=np.float64).reshape(-1, 2)
    if n + len(extra):
        xs, zs = contacts[:, 0], contacts[:, 2]
        if len(extra):
            xs, zs = np.concatenate([xs, extra[:, 0]]), np.concatenate([zs, extra[:, 1]])
        depth = np.asarray(depth_fn(xs, zs), dtype=np.float64)
    else:
        depth = np.zeros(0)
    depth, geo.extra_depth_mm = depth[:4 * n], depth[4 * n:]
    if compiled:
        depth, available, allocated, thrown, buckets, risk, throwing = kernels.wheel_water(
            signed, wt, np.ascontiguousarray(depth), fleet.planing_speed, _WATER_BANDS, _WATER_CONSTS)
        budget = WaterBudget(available, allocated, thrown, buckets)
        geo.throwing = bool(throwing)
    else:
        # NaN → 0 (fmax drops it), below 0 → 0, +inf and beyond → MAX_FILM_DEPTH_MM.
        depth = np.minimum(np.fmax(depth, 0.0), MAX_FILM_DEPTH_MM)
        depth_m = depth * 1e-3
        budget = allocate_water_unchecked(signed, geo.width, depth_m)
        risk = hydroplaning_risk_unchecked(signed, depth_m, fleet.pressure, fleet.planing_speed)
        geo.throwing = bool((budget.thrown > 0.0).any())  # thrown ≥ 0: any wheel's total > 0
    geo.buckets, geo.available = budget.buckets, budget.available
    geo.wheel_parts = (list(vehicles), signed, depth, budget, risk)
    return (wheel_list(geo) if build_wheels else None), geo


def wheel_list(geo: WheelGeometry) -> list[WheelWater]:
    """The per-vehicle ``WheelWater`` of a geometry made by :func:`gather_wheels` (views of its arrays)."""
    vehicles, signed, depth, budget, risk = geo.wheel_parts
    wheels = []
    for i, v in enumerate(vehicles):
        k = slice(4 * i, 4 * i + 4)
        b = WaterBudget(budget.available[k], budget.allocated[k], budget.thrown[k], budget.buckets[k])
        wheels.append(WheelWater(v, geo.contacts[k], signed[k], geo.width[k], depth[k], b, risk[k]))
    return wheels
