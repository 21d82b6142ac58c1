"""Street furniture at the kerb, placed from the seed: cars parked half on the sidewalk, road signs on posts and
zebra crossings.

Parking. There is no parking lane (two traffic lanes each way), so cars park "on the pavement": the wheels on
the kerb side stand on the sidewalk, the body rolls by the kerb height (asin(0.15 m / track) ≈ 5°), and the
body's inner edge stays at |x| ≥ ``PARKED_INNER_X_M`` so the outer lane (centre ±5.25 m, cars ~1.8 m wide)
stays free. Cars stand in runs with gaps, clear of lamp posts, sign posts, tree trunks (vans also of the crowns
above them), doors, zebra crossings (10 m each way), the underpass and the fuel station's forecourt. The meshes
are ``rain_core.car_mesh.vehicle_mesh`` with the lights off, the door mirrors folded (left out), the body's inner
end caps dropped and lighter wheels, baked in world space (~1100 vertices a car). Each car is solid (an
axis-aligned box, ``World.solid_boxes``) and roofs the rain (its lower body and its greenhouse as two rolled boxes
in the occluder mesh).

Signs. Flat plates on 60 mm posts at the sidewalk's road edge, facing the traffic on their side, painted
(``MAT_PAINT``, which ``shaders/core/materials.glsl`` makes retroreflective above the road: signs light up in
headlights): a speed limit (white disc, red ring, black digits), pavement parking allowed (blue square, white "P", and a
white supplementary plate with a car half up the kerb), a pedestrian crossing (blue square, white triangle) at
each zebra crossing, no stopping (blue disc, red ring and cross) at the underpass, and a blue direction sign
(white text bars and an arrow) on two posts. Posts are solid circles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import layout
from rain_core.mesh import (
    MAT_CAR_PAINT,
    MAT_EMISSIVE,
    MAT_GENERIC,
    MAT_METAL,
    MAT_PAINT,
    MAT_RUBBER,
    concat,
    transform,
)
from rain_core.world.primitives import _box_tris, _cylinders, _in_zones, _pack, _rects_up

_P = layout.PERIOD_M
_HW = layout.ROAD_HALF_WIDTH_M
_KH = layout.KERB_HEIGHT_M
_KERB_OUT = _HW + layout.KERB_WIDTH_M

PARKED_INNER_X_M = 6.6  # m, no parked body comes nearer the centre line than this (traffic: |x| ≤ ~6.2 m)
SIGN_POST_X_M = _KERB_OUT + 0.25  # m, |x| of sign posts: at the sidewalk's road edge
SIGN_POST_R_M = 0.03  # m, post radius (60 mm tube)
SIGN_SOLID_R_M = 0.05  # m, the post's radius for collisions (a little margin)

_BRIDGE_ZONE = (layout.BRIDGE_Z_M - 22.0, layout.BRIDGE_Z_M + 22.0)  # m, embankment and approaches
_STATION_ZONE = (layout.CANOPY_Z_M - 34.0, layout.CANOPY_Z_M + 52.0)  # m, forecourt and its driveways (+x)

# Body colours of parked cars (linear RGB): traffic's palette plus a few more.
_PALETTE = np.array([[0.80, 0.80, 0.78], [0.02, 0.02, 0.022], [0.45, 0.46, 0.48], [0.10, 0.10, 0.11],
                     [0.03, 0.07, 0.25], [0.40, 0.02, 0.02], [0.12, 0.16, 0.13], [0.55, 0.45, 0.30],
                     [0.25, 0.25, 0.27], [0.02, 0.03, 0.08], [0.60, 0.38, 0.03], [0.05, 0.12, 0.22],
                     [0.18, 0.03, 0.05], [0.62, 0.62, 0.60]])
_BELT = {"car": 0.62, "van": 0.49}  # belt line / height: the top of the lower body's occluder box
PARKING_EMPTY_M = (20.0, 70.0)  # m, the empty stretch before each run of parked cars
PARKING_RUN_CARS = (1, 7)  # cars in a run (the upper bound excluded)
PARKING_SIGNS_PER_SIDE = 3  # "pavement parking" signs, each at the start of a run of three or more cars


@dataclass(frozen=True)
class Kerbside:
    """What ``kerbside`` builds. ``groups``: (label class name, vertex arrays) in build order; ``occ``: occluder
    triangle soups; ``circles`` (N, 3) x, z, radius (m) of the sign posts; ``boxes`` (M, 4) x0, x1, z0, z1 (m)
    of the parked cars' footprints; ``signs``: (kind, side ±1, z m) of each sign; ``crossings``: z (m) of the
    zebra crossings."""

    groups: list
    occ: list
    circles: np.ndarray
    boxes: np.ndarray
    signs: list
    crossings: np.ndarray


# ----------------------------------------------------------------------------------------------------------------
# Small mesh helpers (local frames; every face wound counter-clockwise around its normal)


def _tris(pos: np.ndarray, nrm: np.ndarray, albedo, rough, metal, mat) -> np.ndarray:
    """Triangles (n, 3, 3) with per-vertex normals (n, 3, 3), wound counter-clockwise around the normal."""
    pos = np.array(pos, dtype=np.float64).reshape(-1, 3, 3)
    nrm = np.broadcast_to(np.asarray(nrm, dtype=np.float64), pos.shape).copy()
    cross = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    flip = np.einsum("ij,ij->i", cross, nrm.mean(axis=1)) < 0
    pos[flip] = pos[flip][:, ::-1]
    nrm[flip] = nrm[flip][:, ::-1]
    return _pack(pos[None].reshape(1, -1, 3), nrm.reshape(1, -1, 3), albedo, rough, metal, mat)


# ----------------------------------------------------------------------------------------------------------------
# Parked cars


def _light_wheels(spec, road: float, sections: int = 8) -> np.ndarray:
    """Wheels of a parked car in its local frame: an 8-sided tyre; on the road side a tyre wall and a metal hub,
    on the kerb side (hidden behind the body but for the tyre's foot) a plain dark face. No inner faces (they
    face the car's underside). road: the local x side (±1) that faces the road."""
    from rain_core.vehicles import wheel_contacts_local

    r, w = spec.wheel_radius_m, spec.tire_width_m
    ang = 2 * np.pi * (np.arange(sections) + 0.5) / sections
    ring = np.stack([np.zeros(sections), np.cos(ang), np.sin(ang)], axis=1)
    nxt = np.roll(ring, -1, axis=0)
    rubber = (0.025, 0.025, 0.025)
    parts = []
    for contact in wheel_contacts_local(spec):
        c = contact + np.array([0.0, r, 0.0])
        out = math.copysign(1.0, contact[0])
        xo, xi = np.array([out * w / 2, 0, 0]), np.array([-out * w / 2, 0, 0])
        a, b = c + xi + r * ring, c + xo + r * ring
        an, bn = c + xi + r * nxt, c + xo + r * nxt
        tread = np.stack([np.stack([a, b, bn], 1), np.stack([a, bn, an], 1)], 1).reshape(-1, 3, 3)
        tn = np.stack([np.stack([ring, ring, nxt], 1), np.stack([ring, nxt, nxt], 1)], 1).reshape(-1, 3, 3)
        parts.append(_tris(tread, tn, rubber, 0.85, 0.0, MAT_RUBBER))
        face_o = np.array([out, 0.0, 0.0])
        centre = np.broadcast_to(c + xo, ring.shape)
        if out == road:
            hub_r = 0.62 * r
            hi, hin = c + xo + hub_r * ring, c + xo + hub_r * nxt
            rim = np.stack([np.stack([b, bn, hin], 1), np.stack([b, hin, hi], 1)], 1).reshape(-1, 3, 3)
            parts.append(_tris(rim, face_o, rubber, 0.85, 0.0, MAT_RUBBER))
            parts.append(_tris(np.stack([centre, hi, hin], 1), face_o, (0.55, 0.55, 0.56), 0.35, 1.0, MAT_METAL))
        else:
            parts.append(_tris(np.stack([centre, b, bn], 1), face_o, rubber, 0.85, 0.0, MAT_RUBBER))
    return concat(parts)


_TEMPLATES: dict[tuple[str, float], tuple[np.ndarray, np.ndarray]] = {}


def _parked_template(kind: str, road: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, paint mask) of a parked vehicle of ``kind`` in its local frame: ``vehicle_mesh`` with unlit
    lenses, mirrors folded away and the light wheels, hubs on the local x side ``road`` (±1). Built once."""
    hit = _TEMPLATES.get((kind, road))
    if hit is not None:
        return hit
    from rain_core.car_mesh import vehicle_mesh
    from rain_core.vehicles import SPECS, wheel_contacts_local

    spec = SPECS[kind]
    v = vehicle_mesh(spec, (0.5, 0.5, 0.5))
    tri = v["position"].reshape(-1, 3, 3).astype(np.float64)
    mat = np.rint(v["params"][::3, 2]).astype(int)
    centres = wheel_contacts_local(spec) + np.array([0.0, spec.wheel_radius_m, 0.0])
    reach = math.hypot(spec.wheel_radius_m, spec.tire_width_m / 2) + 0.01
    d = np.linalg.norm(tri[:, :, None, :] - centres[None, None], axis=3).max(axis=1)  # (n, 4)
    at_wheel = (d <= reach).any(axis=1)
    mirror = np.abs(tri[:, :, 0]).max(axis=1) > spec.width_m / 2 + 0.01
    keep = ~((mat == MAT_RUBBER) | ((mat == MAT_METAL) & at_wheel) | mirror | _hidden_caps(tri))
    # Lenses: only the face that looks out of the body's end (the others are 15 mm strips).
    n = v["normal"][::3].astype(np.float64)
    end = np.sign(tri[:, :, 2].mean(axis=1))
    keep &= ~((mat == MAT_EMISSIVE) & (n[:, 2] * end < 0.9))
    body = v.reshape(-1, 3)[keep].reshape(-1).copy()
    lens = np.rint(body["params"][:, 2]) == MAT_EMISSIVE
    red = lens & (body["albedo"][:, 0] > 2.0 * body["albedo"][:, 1])
    body["albedo"][lens & ~red] = (0.45, 0.45, 0.43)  # a headlight lens, off
    body["albedo"][red] = (0.30, 0.015, 0.01)  # a tail-light lens, off
    body["params"][lens] = (0.12, 0.0, float(MAT_GENERIC))
    out = concat([body, _light_wheels(spec, road)])
    paint = np.rint(out["params"][:, 2]) == MAT_CAR_PAINT
    _TEMPLATES[(kind, road)] = (out, paint)
    return out, paint


def _hidden_caps(tri: np.ndarray, tol: float = 1e-5) -> np.ndarray:
    """Mask of the triangles (n, 3, 3) that lie in a plane z = const and are covered by triangles in the same
    plane facing the other way: the inner end caps of the body's convex segments, shut inside the body. A
    triangle is covered when all its corners lie inside one of the opposite triangles (the caps are convex
    fans, so inside the cap)."""
    z = tri[:, :, 2]
    flat = np.ptp(z, axis=1) < tol
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1)
    facing = np.where(flat & (area > 1e-9), np.sign(cross[:, 2]), 0.0)
    hidden = np.zeros(len(tri), dtype=bool)
    cand = np.nonzero(facing != 0)[0]
    keys = np.round(z[cand, 0] / tol).astype(np.int64)
    for key in np.unique(keys):
        idx = cand[keys == key]
        for sgn in (-1.0, 1.0):
            mine, other = idx[facing[idx] == sgn], idx[facing[idx] == -sgn]
            if len(mine) == 0 or len(other) == 0:
                continue
            o = tri[other][:, :, :2]  # (m, 3, 2) x, y
            p = tri[mine][:, :, :2].reshape(-1, 2)  # corners (k·3, 2)
            a, b, c = o[:, 0], o[:, 1], o[:, 2]

            def side(u, v, q):
                return (v[None, :, 0] - u[None, :, 0]) * (q[:, None, 1] - u[None, :, 1]) - \
                    (v[None, :, 1] - u[None, :, 1]) * (q[:, None, 0] - u[None, :, 0])

            s1, s2, s3 = side(a, b, p), side(b, c, p), side(c, a, p)
            inside = (((s1 >= -1e-6) & (s2 >= -1e-6) & (s3 >= -1e-6))
                      | ((s1 <= 1e-6) & (s2 <= 1e-6) & (s3 <= 1e-6))).any(axis=1)
            hidden[mine] = inside.reshape(-1, 3).all(axis=1)
    return hidden


def _occluder_boxes_local(kind: str, verts: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Two local boxes that roof the rain: the lower body to the belt line and the greenhouse to the roof."""
    from rain_core.vehicles import SPECS

    spec = SPECS[kind]
    p = verts["position"].astype(np.float64)
    hl, hw, h = spec.length_m / 2, spec.width_m / 2, spec.height_m
    belt = _BELT[kind] * h
    roof = p[p[:, 1] > 0.85 * h]
    gz0, gz1 = roof[:, 2].min(), roof[:, 2].max()
    gw = np.abs(roof[:, 0]).max()
    return [(np.array([-hw, 0.25, -hl]), np.array([hw, belt, hl])),
            (np.array([-gw, belt, gz0]), np.array([gw, h, gz1]))]


def _rot_y(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _free(z0: float, z1: float, keepout: np.ndarray) -> float | None:
    """None if [z0, z1] misses every keep-out interval (K, 2), else the end of the first one it hits."""
    if len(keepout) == 0:
        return None
    hit = (keepout[:, 1] > z0) & (keepout[:, 0] < z1)
    return float(keepout[hit, 1].max()) if hit.any() else None


def _parked_cars(rng: np.random.Generator, keepout: dict, tree_keepout: dict):
    """Vertex arrays, occluder soups, footprints (N, 4) and runs [side, z0, z1, cars] of the parked cars.
    keepout[side]: (K, 2) z intervals no car may cover; tree_keepout[side]: more intervals vans avoid."""
    from rain_core.vehicles import SPECS

    parts, occ, boxes, runs = [], [], [], []
    for side in (1.0, -1.0):
        z = float(rng.uniform(0.0, 20.0))
        base = np.asarray(keepout[side], dtype=np.float64).reshape(-1, 2)
        vans = np.concatenate([base, np.asarray(tree_keepout[side], dtype=np.float64).reshape(-1, 2)])
        run = 0  # cars left in this run
        while True:
            if run == 0:  # an empty stretch, then a run of a few cars nose to tail
                z += float(rng.uniform(*PARKING_EMPTY_M))
                run = int(rng.integers(*PARKING_RUN_CARS))
                runs.append([side, math.inf, -math.inf, 0])
            kind = "van" if rng.random() < 0.12 else "car"
            spec = SPECS[kind]
            length = spec.length_m
            gap = float(rng.uniform(0.6, 1.8))
            colour = _PALETTE[rng.integers(len(_PALETTE))] * rng.uniform(0.85, 1.0)
            if kind == "van" and rng.random() < 0.6:
                colour = np.array([0.78, 0.78, 0.76]) * rng.uniform(0.9, 1.0)  # most vans are white
            reverse = rng.random() < 0.1
            inset = float(rng.uniform(0.02, 0.15))
            if z + length > _P - 0.5:
                break
            blocked = _free(z - 0.4, z + length + 0.4, vans if kind == "van" else base)
            if blocked is not None:
                z = blocked + 0.4 + float(rng.uniform(0.0, 1.0))
                continue
            run -= 1
            yaw = (0.0 if side > 0 else math.pi) + (math.pi if reverse else 0.0)
            outer_local = side * math.cos(yaw)  # the local x side that stands on the kerb
            verts, paint = _parked_template(kind, -round(outer_local))
            roll = math.asin(_KH / spec.track_m) * outer_local
            lift = spec.track_m / 2 * math.sin(abs(roll))
            rot = _rot_y(yaw) @ _rot_z(roll)
            m = np.eye(4)
            m[:3, :3] = rot
            m[:3, 3] = (0.0, lift, z + length / 2)
            car = transform(verts, m)
            px = car["position"][:, 0].astype(np.float64)
            inner = px.min() if side > 0 else -px.max()  # nearest |x| to the centre line
            dx = side * (PARKED_INNER_X_M + inset - inner)
            car["position"][:, 0] += dx
            m[0, 3] += dx
            car["albedo"][paint] = colour
            parts.append(car)
            x0, x1 = float(car["position"][:, 0].min()), float(car["position"][:, 0].max())
            z0, z1 = float(car["position"][:, 2].min()), float(car["position"][:, 2].max())
            boxes.append((x0, x1, z0, z1))
            runs[-1][1:] = [min(runs[-1][1], z0), max(runs[-1][2], z1), runs[-1][3] + 1]
            for lo, hi in _occluder_boxes_local(kind, verts):
                t = _box_tris(lo, hi).reshape(-1, 3)
                occ.append((t @ m[:3, :3].T + m[:3, 3]).reshape(-1, 3, 3))
            z += length + gap
    return parts, occ, np.array(boxes, dtype=np.float64).reshape(-1, 4), [r for r in runs if r[3] > 0]


# ----------------------------------------------------------------------------------------------------------------
# Signs: plates in a local frame (x right, y up, facing +z), instanced onto posts

_WHITE = (0.78, 0.78, 0.76)
_RED = (0.50, 0.015, 0.015)
_BLUE = (0.01, 0.07, 0.32)
_BLACK = (0.02, 0.02, 0.02)
_BACK = (0.30, 0.31, 0.32)  # galvanised back of a plate
_POST = (0.40, 0.41, 0.42)
_PLATE_T = 0.012  # m, plate thickness
_LAYER = 0.0025  # m, each paint layer stands this far in front of the one below


def _face(pts: np.ndarray, layer: int, albedo, rough=0.45) -> np.ndarray:
    """Front-facing (+z) triangles (n, 3, 2) of x, y (m) at paint layer ``layer``."""
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 3, 2)
    pos = np.concatenate([pts, np.full(pts.shape[:2] + (1,), _PLATE_T / 2 + layer * _LAYER)], axis=2)
    return _tris(pos, np.array([0.0, 0.0, 1.0]), albedo, rough, 0.0, MAT_PAINT)


def _quad2(x0, y0, x1, y1) -> np.ndarray:
    return np.array([[(x0, y0), (x1, y0), (x1, y1)], [(x0, y0), (x1, y1), (x0, y1)]])


def _poly2(p) -> np.ndarray:
    """A convex polygon (k, 2) as a fan."""
    p = np.asarray(p, dtype=np.float64)
    return np.stack([np.broadcast_to(p[0], p[1:-1].shape), p[1:-1], p[2:]], axis=1)


def _disc2(cx, cy, r, n=20) -> np.ndarray:
    a = 2 * np.pi * np.arange(n) / n
    return _poly2(np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], 1))


def _ring2(cx, cy, r0, r1, n=20) -> np.ndarray:
    a = 2 * np.pi * np.arange(n) / n
    o = np.stack([cx + r1 * np.cos(a), cy + r1 * np.sin(a)], 1)
    i = np.stack([cx + r0 * np.cos(a), cy + r0 * np.sin(a)], 1)
    on, inn = np.roll(o, -1, 0), np.roll(i, -1, 0)
    return np.concatenate([np.stack([o, on, inn], 1), np.stack([o, inn, i], 1)])


def _bar2(p0, p1, width) -> np.ndarray:
    """A straight stroke of ``width`` (m) from p0 to p1 (x, y)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    d = p1 - p0
    n = np.array([-d[1], d[0]]) / np.linalg.norm(d) * width / 2
    return _poly2([p0 - n, p1 - n, p1 + n, p0 + n])


_SEGMENTS = {"0": "abcdef", "3": "abcdg", "5": "acdfg", "P": "abefg"}


def _glyph(ch: str, cx: float, cy: float, h: float, stroke: float) -> np.ndarray:
    """A seven-segment glyph of height h (m) centred at cx, cy."""
    w = 0.55 * h
    x0, x1, y0, ym, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy, cy + h / 2
    s = stroke / 2
    seg = {"a": ((x0, y1 - s), (x1, y1 - s)), "b": ((x1 - s, ym), (x1 - s, y1)), "c": ((x1 - s, y0), (x1 - s, ym)),
           "d": ((x0, y0 + s), (x1, y0 + s)), "e": ((x0 + s, y0), (x0 + s, ym)), "f": ((x0 + s, ym), (x0 + s, y1)),
           "g": ((x0, ym), (x1, ym))}
    return np.concatenate([_bar2(*seg[k], stroke) for k in _SEGMENTS[ch]])


def _round_plate(r: float, n: int = 20) -> list[np.ndarray]:
    """The bare round plate: its back (−z) and its rim."""
    a = 2 * np.pi * np.arange(n) / n
    ring = np.stack([r * np.cos(a), r * np.sin(a)], 1)
    back = _poly2(ring)
    back_pos = np.concatenate([back, np.full(back.shape[:2] + (1,), -_PLATE_T / 2)], 2)
    parts = [_tris(back_pos, np.array([0.0, 0.0, -1.0]), _BACK, 0.6, 0.5, MAT_METAL)]
    nxt = np.roll(ring, -1, 0)
    zf, zb = _PLATE_T / 2, -_PLATE_T / 2
    q = np.stack([np.column_stack([ring, np.full(n, zb)]), np.column_stack([nxt, np.full(n, zb)]),
                  np.column_stack([nxt, np.full(n, zf)]), np.column_stack([ring, np.full(n, zf)])], 1)
    rim = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    rn = rim.copy()
    rn[:, :, 2] = 0.0
    rn /= np.linalg.norm(rn, axis=2, keepdims=True)
    parts.append(_tris(rim, rn, _BACK, 0.6, 0.5, MAT_METAL))
    return parts


def _rect_plate(x0, y0, x1, y1) -> list[np.ndarray]:
    """The bare rectangular plate: back and four edges."""
    from rain_core.world.primitives import NX_, NY_, NZ_, PX_, PY_, _boxes

    return [_boxes((x0, y0, -_PLATE_T / 2), (x1, y1, _PLATE_T / 2), _BACK, 0.6, 0.5, MAT_METAL,
                   faces=(NX_, PX_, NY_, PY_, NZ_))]


def _sign_templates() -> dict[str, tuple[np.ndarray, float, tuple]]:
    """kind → (plate vertices in the local frame with the plate's centre at the origin, post top above the
    ground (m), post x offsets (m))."""
    t = {}
    r = 0.32
    for limit in ("30", "50"):
        p = _round_plate(r) + [_face(_disc2(0, 0, r), 0, _RED), _face(_disc2(0, 0, 0.76 * r), 1, _WHITE)]
        p += [_face(_glyph(ch, dx, 0.0, 0.24, 0.042), 2, _BLACK) for ch, dx in zip(limit, (-0.085, 0.085),
                                                                                     strict=True)]
        t["limit" + limit] = (concat(p), 2.35, (0.0,))
    # Pavement parking: blue square with a white P, and under it a white plate with a car half up the kerb.
    s = 0.30
    p = _rect_plate(-s, -s, s, s) + [_face(_quad2(-s, -s, s, s), 0, _BLUE),
                                     _face(_glyph("P", 0.0, 0.0, 0.40, 0.075), 1, _WHITE)]
    y0, y1 = -s - 0.30, -s - 0.04
    p += _rect_plate(-s, y0, s, y1) + [_face(_quad2(-s + 0.01, y0 + 0.01, s - 0.01, y1 - 0.01), 0, _WHITE)]
    body = _poly2([(-0.17, y0 + 0.09), (0.17, y0 + 0.12), (0.16, y0 + 0.18), (-0.16, y0 + 0.15)])
    kerb = _quad2(0.0, y0 + 0.04, 0.24, y0 + 0.08)
    p += [_face(body, 1, _BLACK), _face(kerb, 1, _BLACK), _face(_quad2(-0.24, y0 + 0.035, 0.0, y0 + 0.05), 1, _BLACK)]
    t["parking"] = (concat(p), 2.45, (0.0,))
    # Pedestrian crossing: blue square, white triangle, a black walker.
    p = _rect_plate(-s, -s, s, s) + [_face(_quad2(-s, -s, s, s), 0, _BLUE),
                                     _face(_poly2([(-0.25, -0.2), (0.25, -0.2), (0.0, 0.25)]), 1, _WHITE)]
    walker = np.concatenate([_disc2(0.0, 0.06, 0.03, 8), _bar2((0.0, 0.03), (-0.01, -0.06), 0.04),
                             _bar2((-0.01, -0.06), (-0.06, -0.16), 0.025), _bar2((-0.01, -0.06), (0.05, -0.16), 0.025),
                             _bar2((0.0, 0.02), (-0.06, -0.04), 0.02), _bar2((0.0, 0.02), (0.06, -0.03), 0.02)])
    p += [_face(walker, 2, _BLACK)]
    t["crossing"] = (concat(p), 2.45, (0.0,))
    # No stopping: blue disc, red ring, red cross.
    p = _round_plate(r) + [_face(_disc2(0, 0, r), 0, _RED), _face(_disc2(0, 0, 0.8 * r), 1, _BLUE)]
    p += [_face(np.concatenate([_bar2((-0.2, -0.2), (0.2, 0.2), 0.07), _bar2((-0.2, 0.2), (0.2, -0.2), 0.07)]), 2,
                _RED)]
    t["nostop"] = (concat(p), 2.35, (0.0,))
    # Direction sign: a blue board with three lines of white "text" and an arrow, on two posts.
    w, h = 0.85, 0.45
    p = _rect_plate(-w, -h, w, h) + [_face(_quad2(-w, -h, w, h), 0, _BLUE),
                                     _face(np.concatenate([_ring_rect(-w + 0.03, -h + 0.03, w - 0.03, h - 0.03, 0.02)]),
                                           1, _WHITE)]
    rows = []
    for k, length in enumerate((0.95, 0.7, 1.1)):
        yc = h - 0.13 - k * 0.26
        rows.append(_quad2(-w + 0.12, yc - 0.05, -w + 0.12 + length, yc + 0.05))
    arrow = np.concatenate([_bar2((w - 0.40, -0.05), (w - 0.20, -0.05), 0.08),
                            _poly2([(w - 0.20, -0.16), (w - 0.08, -0.05), (w - 0.20, 0.06)])])
    p += [_face(np.concatenate(rows + [arrow]), 1, _WHITE)]
    t["direction"] = (concat(p), 3.2, (-0.6, 0.6))
    return t


def _ring_rect(x0, y0, x1, y1, wdt) -> np.ndarray:
    """A rectangular border of width wdt (m) inside [x0, x1] × [y0, y1]."""
    return np.concatenate([_quad2(x0, y0, x1, y0 + wdt), _quad2(x0, y1 - wdt, x1, y1), _quad2(x0, y0 + wdt, x0 + wdt,
                                                                                              y1 - wdt),
                           _quad2(x1 - wdt, y0 + wdt, x1, y1 - wdt)])


_SIGNS: dict | None = None


def _place_signs(rng: np.random.Generator, blocked: dict, crossings: np.ndarray):
    """[(kind, side, z)]: signs for each side, clear of ``blocked[side]`` (K, 2) z intervals: the crossings',
    no stopping before the underpass, speed limits and a direction sign (parking signs come with the cars)."""
    out = []
    for side in (1.0, -1.0):
        ahead = side  # a sign stands before the place it refers to, as its traffic comes (−z on +x)
        taken = [np.asarray(blocked[side], dtype=np.float64).reshape(-1, 2)]

        def put(kind, z, side=side, taken=taken, tries=12):
            for k in range(tries):  # nearest free spot: z, z ∓ 1.7 m, …
                zz = float(np.mod(z + (k % 2 * 2 - 1) * (k // 2) * 1.7, _P))
                if not (1.0 < zz < _P - 1.0):
                    continue
                if _free(zz - 1.0, zz + 1.0, np.concatenate(taken)) is None:
                    taken.append(np.array([[zz - 1.0, zz + 1.0]]))
                    out.append((kind, side, zz))
                    return True
            return False

        for zc in crossings:
            put("crossing", zc + ahead * 4.0)
        # No stopping on the approaches to the underpass.
        put("nostop", layout.BRIDGE_Z_M + ahead * (_BRIDGE_ZONE[1] - layout.BRIDGE_Z_M + 3.0))
        for z in rng.uniform(0.0, _P, 2):
            put("limit" + ("30" if rng.random() < 0.3 else "50"), z)
        put("direction", float(rng.uniform(0.0, _P)))
    return out


def _signs(placements) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
    """(post vertex arrays, plate vertex arrays, post circles (N, 3) x, z, r)."""
    global _SIGNS
    if _SIGNS is None:
        _SIGNS = _sign_templates()
    posts, plates, circles = [], [], []
    for kind, side, z in placements:
        verts, top, offsets = _SIGNS[kind]
        yaw = 0.0 if side > 0 else math.pi  # +x side faces +z (its traffic comes from +z)
        m = np.eye(4)
        m[:3, :3] = _rot_y(yaw)
        plate_y = top - (0.45 if kind == "direction" else 0.32)
        x = side * (SIGN_POST_X_M + (1.05 if kind == "direction" else 0.0))
        m[:3, 3] = (x, plate_y, z)
        plates.append(transform(verts, m))
        for off in offsets:
            px = x + (off if side > 0 else -off)
            pz = z - side * (_PLATE_T / 2 + SIGN_POST_R_M + 0.002)  # behind the plate
            posts.append(_cylinders(np.array([[px, _KH, pz]]), SIGN_POST_R_M, top - _KH, 6, _POST, 0.5, 0.8,
                                    MAT_METAL))
            circles.append((px, pz, SIGN_SOLID_R_M))
    return posts, plates, np.array(circles, dtype=np.float64).reshape(-1, 3)


# ----------------------------------------------------------------------------------------------------------------
# Zebra crossings


def _crossing_positions(rng: np.random.Generator) -> np.ndarray:
    """z (m) of the tile's zebra crossings: two, away from the underpass, the station and each other."""
    zs = []
    while len(zs) < 2:
        z = float(rng.uniform(40.0, _P - 40.0))
        if _in_zones(z - 30.0, z + 30.0, [_BRIDGE_ZONE, _STATION_ZONE]) or any(abs(z - o) < 200.0 for o in zs):
            continue
        zs.append(z)
    return np.array(sorted(zs))


def _zebra(crossings: np.ndarray) -> list[np.ndarray]:
    """White bars along the road, 0.5 m wide with 0.5 m gaps, 3 m long; 6 mm proud (above the lane lines)."""
    xs = np.arange(-_HW + 0.6, _HW - 0.6 + 1e-6, 1.0)
    x0 = np.concatenate([xs - 0.25 for _ in crossings])
    z0 = np.repeat(crossings - 1.5, len(xs))
    return [_rects_up(x0, x0 + 0.5, z0, z0 + 3.0, 0.006, (0.68, 0.68, 0.65), 0.6, MAT_PAINT)]


# ----------------------------------------------------------------------------------------------------------------


def kerbside(r_signs: np.random.Generator, r_park: np.random.Generator, lamp_posts: np.ndarray,
             trunks: np.ndarray, doors: np.ndarray) -> Kerbside:
    """Zebra crossings, signs and parked cars for one tile. lamp_posts, trunks: (N, 3) x, z, radius (m);
    doors: (M, 3) side (±1), z0, z1 (m) of the buildings' doors."""
    crossings = _crossing_positions(r_signs)
    blocked, park_out, van_out = {}, {}, {}
    for side in (1.0, -1.0):
        posts = np.asarray(lamp_posts, dtype=np.float64).reshape(-1, 3)
        posts = posts[np.sign(posts[:, 0]) == side]
        tr = np.asarray(trunks, dtype=np.float64).reshape(-1, 3)
        tr = tr[np.sign(tr[:, 0]) == side]
        zones = [_BRIDGE_ZONE] + ([_STATION_ZONE] if side > 0 else [])
        fixed = [np.array(zones), np.stack([posts[:, 1] - 1.5, posts[:, 1] + 1.5], 1),
                 np.stack([tr[:, 1] - 1.0, tr[:, 1] + 1.0], 1), np.stack([crossings - 3.0, crossings + 3.0], 1)]
        blocked[side] = np.concatenate(fixed)
        d = np.asarray(doors, dtype=np.float64).reshape(-1, 3)
        d = d[d[:, 0] == side]
        park_out[side] = np.concatenate([np.array(zones), np.stack([posts[:, 1] - 0.5, posts[:, 1] + 0.5], 1),
                                         np.stack([d[:, 1] - 0.4, d[:, 2] + 0.4], 1),
                                         np.stack([tr[:, 1] - 0.4, tr[:, 1] + 0.4], 1),
                                         np.stack([crossings - 10.0, crossings + 10.0], 1)])
        van_out[side] = np.stack([tr[:, 1] - 2.8, tr[:, 1] + 2.8], 1)
    placements = _place_signs(r_signs, blocked, crossings)
    for side in (1.0, -1.0):
        zs = np.array([z for _, s, z in placements if s == side])
        if len(zs):
            park_out[side] = np.concatenate([park_out[side], np.stack([zs - 0.6, zs + 0.6], 1)])
    cars, occ, boxes, runs = _parked_cars(r_park, park_out, van_out)
    # Pavement-parking signs where a run of three or more cars begins, as its traffic comes (−z on the +x side).
    for side in (1.0, -1.0):
        taken = np.concatenate([blocked[side]] + [np.array([[z - 1.0, z + 1.0]]) for _, s, z in placements
                                                  if s == side])
        cands = [r for r in runs if r[0] == side and r[3] >= 3]
        for k in r_signs.permutation(len(cands))[:PARKING_SIGNS_PER_SIDE]:
            _, z0, z1, _ = cands[k]
            z = z1 + 0.45 if side > 0 else z0 - 0.45
            near_car = np.any((boxes[:, 2] < z + 0.35) & (boxes[:, 3] > z - 0.35))
            if not near_car and _free(z - 0.5, z + 0.5, taken) is None and 1.0 < z < _P - 1.0:
                placements.append(("parking", side, z))
                taken = np.concatenate([taken, [[z - 1.0, z + 1.0]]])
    posts, plates, circles = _signs(placements)
    groups = [("marking", _zebra(crossings)), ("pole", posts), ("traffic_sign", plates), ("vehicle", cars)]
    return Kerbside(groups, occ, circles, boxes, placements, crossings)


__all__ = ["PARKED_INNER_X_M", "SIGN_POST_X_M", "Kerbside", "kerbside"]
