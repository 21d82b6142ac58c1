"""Moving occluders: vehicles as convex pieces, tested analytically against a drop's path relative to each one."""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.rainfall.boxes import Boxes, wrap_near
from rain_core.effects.rainfall.constants import VEHICLE_WAKE_S


def near_boxes(vehicle, boxes: Boxes, margin_m: float = 10.0) -> bool:
    """Whether a vehicle is within margin_m (m) of the outer box horizontally (z periodic)."""
    c = np.asarray(vehicle.position, dtype=np.float64)
    lo, hi = boxes.lo[-1], boxes.hi[-1]
    z = wrap_near(c[2], 0.5 * (lo[2] + hi[2]))
    reach = margin_m + 0.5 * vehicle.spec.length_m
    return bool(lo[0] - reach <= c[0] <= hi[0] + reach and lo[2] - reach <= z <= hi[2] + reach)


def vehicle_pieces(spec) -> list[tuple[np.ndarray, float]]:
    """Convex pieces that rain cannot pass, in the vehicle's local frame (m; forward −Z): a list of
    (side polygon (k, 2) as (z, y) counter-clockwise seen from +X, half width). Slightly inside the real body,
    so a drop ends just under the paint (hidden by the depth test) rather than above it."""
    hl, hw, h = spec.length_m / 2.0, spec.width_m / 2.0, spec.height_m
    if spec.kind == "car":
        s, k = spec.length_m / 4.6, h / 1.45
        belt = 0.70 * k
        rake = math.tan(math.radians(60.0))
        cowl_z, cowl_y = -0.62 * s, 0.85 * k
        body = np.array([[-hl, -1.0], [hl, -1.0], [hl, belt], [-hl, belt]])
        cabin = np.array([[cowl_z - (cowl_y - belt) * rake, belt], [1.8 * s, belt], [1.8 * s, 0.95 * k],
                          [1.2 * s, h - 0.02], [cowl_z + (h - 0.02 - cowl_y) * rake, h - 0.02]])
        return [(body, hw - 0.02), (cabin, hw - 0.15)]
    if spec.kind == "van":
        belt, cowl_z, cowl_y = 0.98, -hl + 0.9, 1.12
        rake = math.tan(math.radians(55.0))
        body = np.array([[-hl, -1.0], [hl, -1.0], [hl, belt], [-hl, belt]])
        cabin = np.array([[cowl_z - (cowl_y - belt) * rake, belt], [hl, belt], [hl, h - 0.02],
                          [cowl_z + (h - 0.02 - cowl_y) * rake, h - 0.02]])
        return [(body, hw - 0.02), (cabin, hw - 0.05)]
    if spec.kind == "truck":
        cab_back = -hl + 2.25
        cab = np.array([[-hl, -1.0], [cab_back, -1.0], [cab_back, 2.78], [-hl, 2.78]])
        cargo = np.array([[cab_back, -1.0], [hl, -1.0], [hl, h - 0.02], [cab_back, h - 0.02]])
        return [(cab, hw - 0.05), (cargo, hw - 0.02)]
    return [(np.array([[-hl, -1.0], [hl, -1.0], [hl, h], [-hl, h]]), hw)]


def _piece_planes(poly: np.ndarray, half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """Outward normals (m, 3) and offsets (m,) of a side polygon extruded ±half_width along x: n·p ≤ d inside."""
    normals, offsets = [np.array([1.0, 0.0, 0.0]), np.array([-1.0, 0.0, 0.0])], [half_width, half_width]
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        dz, dy = b - a
        # Counter-clockwise in (z, y): the outward normal of edge a→b is (dy, −dz) in (z, y).
        n = np.array([0.0, -dz, dy])
        n /= np.linalg.norm(n)
        normals.append(n)
        offsets.append(float(n[1] * a[1] + n[2] * a[0]))
    return np.array(normals), np.array(offsets)


def _ccw(poly: np.ndarray) -> np.ndarray:
    z, y = poly[:, 0], poly[:, 1]
    area = 0.5 * np.sum(z * np.roll(y, -1) - np.roll(z, -1) * y)
    return poly if area > 0 else poly[::-1]


_PIECE_CACHE: dict = {}


def _vehicle_planes(spec):
    key = id(spec)
    if key not in _PIECE_CACHE:
        _PIECE_CACHE[key] = (spec, [_piece_planes(_ccw(poly), hw) for poly, hw in vehicle_pieces(spec)])
    return _PIECE_CACHE[key][1]


def vehicle_fate(p0: np.ndarray, u: np.ndarray, life: np.ndarray, vehicles) -> tuple[np.ndarray, np.ndarray]:
    """Cut drops' lives (s) where their paths p0 + u·τ (m, m/s) enter a vehicle moving at its current velocity;
    keep is False for drops inside a vehicle or that left one less than VEHICLE_WAKE_S ago. (A ballistic wake
    would be tens of metres long for slow small drops at driving speed; in fact they ride the airflow around
    the body, so only drops that would emerge from the body itself are refused.) vehicles: objects with
    ``spec``, ``position``, ``yaw``, ``velocity()`` (rain_core.vehicles.Vehicle)."""
    n = len(p0)
    keep = np.ones(n, dtype=bool)
    life = life.copy()
    for veh in vehicles:
        c = np.asarray(veh.position, dtype=np.float64)
        v = np.asarray(veh.velocity(), dtype=np.float64)
        cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
        rel = p0 - c
        rel[:, 2] = wrap_near(rel[:, 2], 0.0)
        w = u - v
        # Local frame: world = R·local with R = [[c, 0, s], [0, 1, 0], [−s, 0, c]] (vehicles.model_matrix).
        pl = np.stack([cy * rel[:, 0] - sy * rel[:, 2], rel[:, 1], sy * rel[:, 0] + cy * rel[:, 2]], axis=1)
        wl = np.stack([cy * w[:, 0] - sy * w[:, 2], w[:, 1], sy * w[:, 0] + cy * w[:, 2]], axis=1)
        # Prefilter: horizontal closest approach, while the drop is below the vehicle's top.
        spec = veh.spec
        radius = 0.5 * math.hypot(spec.length_m, spec.width_m) + 0.2
        fall = np.maximum(-wl[:, 1], 1e-6)
        t_lo = (pl[:, 1] - (spec.height_m + 0.1)) / fall
        t_hi = (pl[:, 1] + 1.0) / fall
        speed2 = np.maximum(wl[:, 0] ** 2 + wl[:, 2] ** 2, 1e-12)
        t_close = np.clip(-(pl[:, 0] * wl[:, 0] + pl[:, 2] * wl[:, 2]) / speed2, t_lo, t_hi)
        dx = pl[:, 0] + wl[:, 0] * t_close
        dz = pl[:, 2] + wl[:, 2] * t_close
        near = np.flatnonzero(dx * dx + dz * dz < radius * radius)
        if near.size == 0:
            continue
        pn, wn = pl[near], wl[near]
        for normals, offsets in _vehicle_planes(spec):
            num = offsets[None, :] - pn @ normals.T  # n·p ≤ d ⇔ n·w·τ ≤ num
            den = wn @ normals.T
            with np.errstate(divide="ignore", invalid="ignore"):
                t_cross = num / den
            t_enter = np.max(np.where(den < 0, t_cross, -np.inf), axis=1)
            t_exit = np.min(np.where(den > 0, t_cross, np.inf), axis=1)
            parallel_out = np.any((den == 0) & (num < 0), axis=1)
            hits = (t_enter < t_exit) & ~parallel_out
            past = hits & (t_enter < 0.0) & (t_exit > -VEHICLE_WAKE_S)
            keep[near[past]] = False
            future = hits & (t_enter >= 0.0)
            idx = near[future]
            life[idx] = np.minimum(life[idx], t_enter[future])
    return keep, life
