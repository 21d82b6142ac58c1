"""The wheels: the water model at each contact patch (film depth, the budget it makes, the hydroplaning risk) and
the per-wheel geometry the launches use."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rain_core.effects.spray.body import BodyBox
from rain_core.effects.spray.water import TYRE_PRESSURE_KPA, WaterBudget, allocate_water, hydroplaning_risk
from rain_core.water_film import film_depth_mm


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

    def depth(x, z):
        x, z = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64))
        return np.asarray(film_depth_mm(x, z, cracks, puddles, puddle_amount=amount, seed=seed, world=world,
                                        wetness=wetness), dtype=np.float64)

    return depth


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


class WheelGeometry:
    """Per-vehicle and per-wheel arrays gathered for vectorised launches."""

    def __init__(self, wheels: list[WheelWater]):
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
        self.contacts = np.concatenate([w.contacts for w in wheels])  # (W, 3)
        self.speed = np.abs(np.concatenate([w.speed_m_s for w in wheels]))
        sign = np.concatenate([np.where(w.speed_m_s < 0, -1.0, 1.0) for w in wheels])
        self.travel = np.repeat(self.forward, 4, axis=0) * sign[:, None]  # direction the wheel rolls
        self.outward = np.repeat(self.right, 4, axis=0) * np.tile([-1.0, 1.0, -1.0, 1.0], len(wheels))[:, None]
        self.radius = np.repeat([v.spec.wheel_radius_m for v in vehicles], 4)
        self.width = np.concatenate([w.width_m for w in wheels])
        self.wheel_velocity = np.repeat(self.velocity, 4, axis=0)
