"""Moving occluders: vehicles as convex pieces (a local box cut by at most two slanted planes each), which cull the
drops inside them in the vertex shader (``rain_in_vehicle`` in shaders/rainfall/drops.glsl); ``inside_vehicles``
is the NumPy twin."""

from __future__ import annotations

import math
import struct

import numpy as np

from rain_core.effects.rainfall.boxes import PERIOD_M, wrap_near
from rain_core.effects.rainfall.constants import MAX_VEHICLES


def vehicle_pieces(spec) -> list[tuple[np.ndarray, float]]:
    """Convex pieces that rain cannot pass, in the vehicle's local frame (m; forward −Z): a list of
    (side polygon (k, 2) as (z, y), half width). Slightly inside the real body, so a drop vanishes just under
    the paint (hidden by the depth test) rather than above it."""
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


PIECES_PER_VEHICLE = 2
PLANES_PER_PIECE = 2


def _ccw(poly: np.ndarray) -> np.ndarray:
    z, y = poly[:, 0], poly[:, 1]
    area = 0.5 * np.sum(z * np.roll(y, -1) - np.roll(z, -1) * y)
    return poly if area > 0 else poly[::-1]


_VOLUME_CACHE: dict = {}


def piece_volumes(spec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pieces of a vehicle as the shader tests them, in its local frame: lo, hi (PIECES, 3) boxes (m) and
    planes (PIECES, PLANES, 4) (n, d): inside ⇔ inside the box and n·p ≤ d for each plane. The box is the
    polygon's bounding box; its slanted edges (the windshield, the rear window) are the planes. Unused pieces
    are empty boxes, unused planes (0, 0, 0, 1)."""
    key = id(spec)
    if key in _VOLUME_CACHE:
        return _VOLUME_CACHE[key][1]
    lo = np.full((PIECES_PER_VEHICLE, 3), 1.0)
    hi = np.full((PIECES_PER_VEHICLE, 3), -1.0)
    planes = np.zeros((PIECES_PER_VEHICLE, PLANES_PER_PIECE, 4))
    planes[..., 3] = 1.0
    pieces = vehicle_pieces(spec)
    if len(pieces) > PIECES_PER_VEHICLE:
        raise ValueError(f"a vehicle has at most {PIECES_PER_VEHICLE} pieces, {spec.kind} has {len(pieces)}")
    for i, (poly, hw) in enumerate(pieces):
        poly = _ccw(np.asarray(poly, dtype=np.float64))
        lo[i] = (-hw, poly[:, 1].min(), poly[:, 0].min())
        hi[i] = (hw, poly[:, 1].max(), poly[:, 0].max())
        j = 0
        for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            dz, dy = b - a
            if abs(dz) < 1e-9 or abs(dy) < 1e-9:
                continue  # axis-aligned: the box has it
            if j == PLANES_PER_PIECE:
                raise ValueError(f"a piece has at most {PLANES_PER_PIECE} slanted edges ({spec.kind})")
            n = np.array([0.0, -dz, dy])  # outward in (x, y, z) for a counter-clockwise (z, y) polygon
            n /= np.linalg.norm(n)
            planes[i, j] = (*n, n[1] * a[1] + n[2] * a[0])
            j += 1
    _VOLUME_CACHE[key] = (spec, (lo, hi, planes))
    return lo, hi, planes


def cull_vehicles(vehicles, centre, reach_m: float) -> list:
    """The vehicles (at most MAX_VEHICLES, nearest first) within reach_m (m) of centre (x, z) horizontally, z
    periodic."""
    out = []
    cx, cz = float(centre[0]), float(centre[1])
    for veh in vehicles:
        # wrap_near for one vehicle in scalars (Python's round, like np.round, rounds halves to even).
        x, z = float(veh.position[0]), float(veh.position[2])
        dz = z - cz
        dz = dz - PERIOD_M * round(dz / PERIOD_M)
        dx, limit = x - cx, reach_m + 0.5 * veh.spec.length_m
        if abs(dx) > limit or abs(dz) > limit:
            continue  # hypot ≥ either leg (rounded too: each leg is a float below the exact length), so far off
        dist = float(np.hypot(dx, dz))
        if dist <= limit:
            out.append((dist, veh))
    out.sort(key=lambda item: item[0])
    return [veh for _, veh in out[:MAX_VEHICLES]]


def vehicle_uniforms(vehicles, shift_z: float, around_z: float) -> dict[str, np.ndarray | int]:
    """The shader's vehicle arrays: u_veh_pose (x, y, z in the frame shifted by shift_z and wrapped near
    around_z, yaw), u_veh_lo / u_veh_hi (local boxes), u_veh_plane, u_veh_count."""
    vehicles = vehicles[:MAX_VEHICLES]
    pose = np.zeros((MAX_VEHICLES, 4))
    for i, veh in enumerate(vehicles):
        x, y, z = (float(v) for v in veh.position)
        pose[i] = (x, y, float(wrap_near(z - float(shift_z), float(around_z))), veh.yaw)
    lo, hi, planes = _pieces(tuple(veh.spec for veh in vehicles))[0]
    return {"u_veh_pose": pose, "u_veh_lo": lo, "u_veh_hi": hi, "u_veh_plane": planes,
            "u_veh_count": len(vehicles)}


_POSE = struct.Struct(f"={4 * MAX_VEHICLES}f")


def vehicle_uniform_pairs(vehicles, shift_z: float, around_z: float) -> tuple:
    """``vehicle_uniforms`` as (name, value) pairs with the arrays as their float32 bytes, built from floats (the
    renderer's per-frame form: the pieces' bytes are kept per spec sequence, the poses packed directly)."""
    vehicles = vehicles[:MAX_VEHICLES]
    return (("u_veh_pose", _POSE.pack(*vehicle_pose_floats(vehicles, shift_z, around_z))),
            *vehicle_shape_pairs(vehicles))


def vehicle_pose_floats(vehicles, shift_z: float, around_z: float) -> list:
    """u_veh_pose of the first MAX_VEHICLES vehicles as 4·MAX_VEHICLES Python floats (unused slots 0)."""
    pose = [0.0] * (4 * MAX_VEHICLES)
    shift_z, around_z = float(shift_z), float(around_z)
    for i, veh in enumerate(vehicles[:MAX_VEHICLES]):
        x, y, z = np.asarray(veh.position, np.float64).tolist()  # float() of each, in one call
        pose[4 * i: 4 * i + 4] = (x, y, float(wrap_near(z - shift_z, around_z)), float(veh.yaw))
    return pose


def vehicle_shape_pairs(vehicles) -> tuple:
    """u_veh_lo, u_veh_hi, u_veh_plane (float32 bytes, kept per spec sequence) and u_veh_count of the first
    MAX_VEHICLES vehicles: they change only when the vehicles near the camera do."""
    vehicles = vehicles[:MAX_VEHICLES]
    lo, hi, planes = _pieces(tuple(veh.spec for veh in vehicles))[1]
    return ("u_veh_lo", lo), ("u_veh_hi", hi), ("u_veh_plane", planes), ("u_veh_count", len(vehicles))


_PIECE_ARRAYS: dict[tuple, tuple[tuple, tuple]] = {}


def _pieces(specs: tuple) -> tuple[tuple, tuple]:
    """((u_veh_lo, u_veh_hi, u_veh_plane), their float32 bytes) for vehicles of ``specs`` in this order: they
    change only when the vehicles near the camera do, so they are kept per spec sequence."""
    key = tuple(id(sp) for sp in specs)
    hit = _PIECE_ARRAYS.get(key)
    if hit is not None and all(a is b for a, b in zip(hit[0], specs, strict=True)):
        return hit[1]
    n = PIECES_PER_VEHICLE
    lo = np.zeros((MAX_VEHICLES * n, 4))
    hi = np.zeros((MAX_VEHICLES * n, 4))
    planes = np.zeros((MAX_VEHICLES * n * PLANES_PER_PIECE, 4))
    for i, spec in enumerate(specs):
        plo, phi, pp = piece_volumes(spec)
        lo[i * n: (i + 1) * n, :3] = plo
        hi[i * n: (i + 1) * n, :3] = phi
        planes[i * n * PLANES_PER_PIECE: (i + 1) * n * PLANES_PER_PIECE] = pp.reshape(-1, 4)
    for a in (lo, hi, planes):
        a.flags.writeable = False
    if len(_PIECE_ARRAYS) > 256:
        _PIECE_ARRAYS.clear()  # forgetting only costs a rebuild
    arrays = (lo, hi, planes)
    entry = (arrays, tuple(a.astype(np.float32).tobytes() for a in arrays))
    _PIECE_ARRAYS[key] = (specs, entry)
    return entry


def inside_vehicles(p: np.ndarray, vehicles) -> np.ndarray:
    """Whether points p (n, 3) (m, world) lie inside a vehicle's pieces (z periodic). Mirrors the shader."""
    inside = np.zeros(len(p), dtype=bool)
    for veh in vehicles:
        c = np.asarray(veh.position, dtype=np.float64)
        rel = p - c
        rel[:, 2] = wrap_near(rel[:, 2], 0.0)
        cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
        local = np.stack([cy * rel[:, 0] - sy * rel[:, 2], rel[:, 1], sy * rel[:, 0] + cy * rel[:, 2]], axis=1)
        plo, phi, pp = piece_volumes(veh.spec)
        for i in range(PIECES_PER_VEHICLE):
            k = np.all((local >= plo[i]) & (local <= phi[i]), axis=1)
            for j in range(PLANES_PER_PIECE):
                k &= local @ pp[i, j, :3] <= pp[i, j, 3]
            inside |= k
    return inside
