"""Vehicle geometry: exterior meshes for car / van / truck, the ego car's cabin, and its curved windshield.

Everything is in the vehicle's local frame (m): forward −Z, right +X, up +Y, origin on the ground under the body
centre (as ``rain_core.vehicles``). Meshes are VERTEX_DTYPE triangle lists (rain_core.mesh); no GL here.

The body is built from convex pieces (lofts of two cross-sections, or side profiles extruded across the car with a
little tumblehome), each oriented outward, so every triangle is front-facing from outside and back-face culling is
safe. The wheels sit exactly on ``vehicles.wheel_contacts_local`` and the light lenses on
``vehicles.light_positions_local``.

The windshield is a separate curved surface (``windshield_surface``) whose edges lie on the plane of the
greenhouse's front face (``windshield_frame``); the cabin's A-pillars, roof header and dashboard cover its edges,
so what the driver sees of the outside world is through that glass.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import trimesh

from rain_core.mesh import (
    MAT_CAR_PAINT,
    MAT_EMISSIVE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_RUBBER,
    VERTEX_DTYPE,
    concat,
    from_trimesh,
)
from rain_core.vehicles import CAR_SPEC, VehicleSpec, light_positions_local, wheel_contacts_local

EGO_COLOR = (0.35, 0.02, 0.02)  # linear RGB, the ego car's default paint (a deep red)
HEADLIGHT_RADIANCE = (20.0, 20.0, 18.0)  # emissive albedo = emitted radiance (linear)
TAILLIGHT_RADIANCE = (6.0, 0.2, 0.1)

# Surface finishes: (albedo or None for the body colour, roughness, metallic, material id).
_GLASS = ((0.02, 0.025, 0.03), 0.05, 0.0, MAT_GLASS)
_TRIM = ((0.035, 0.035, 0.038), 0.6, 0.0, MAT_GENERIC)  # bumpers, black plastic
_DASH = ((0.03, 0.03, 0.032), 0.7, 0.0, MAT_GENERIC)
_PILLAR = ((0.05, 0.05, 0.055), 0.75, 0.0, MAT_GENERIC)
_HEADLINER = ((0.18, 0.18, 0.17), 0.9, 0.0, MAT_GENERIC)
_RUBBER = ((0.025, 0.025, 0.025), 0.85, 0.0, MAT_RUBBER)
_HUB = ((0.55, 0.55, 0.56), 0.35, 1.0, MAT_METAL)
_CHASSIS = ((0.03, 0.03, 0.03), 0.7, 0.5, MAT_METAL)
_PAINT_ROUGHNESS, _PAINT_METALLIC = 0.25, 0.6
_WHEEL_RIM = (0.09, 0.085, 0.08)
_MIRROR = ((0.05, 0.055, 0.06), 0.08, 0.0, MAT_GENERIC)  # the door mirror's glass (dark where no view is drawn)
_WHEEL_SPOKE = (0.16, 0.16, 0.17)  # brushed-metal-look spokes


@dataclass(frozen=True)
class _Profile:
    """Side profile of a body, m in the local frame. ``top``: (z, y, half-width factor) of the lower body's upper
    line from nose to tail; ``greenhouse``: convex (z, y) polygon cowl → glass top → roof front → roof rear →
    rear base, with per-edge finish tags; the windshield is its first edge."""

    top: tuple
    sill_y: float
    body_z: tuple  # (z front, z back) of the lower body
    belt_half_width: float  # greenhouse half width at the cowl height
    tumblehome: float  # greenhouse half width lost per m of height
    greenhouse: tuple
    greenhouse_tags: tuple  # finish per polygon edge ("glass" / "paint")
    side_glass: bool  # greenhouse sides all glass (car) or painted with cab windows (van, truck)
    cab_window_z: float  # side windows end here (m) where side_glass is False
    rake_rad: float
    cargo_box: tuple | None = None  # (z0, z1, y0, y1, half width) of a truck's box body
    glass_margin_m: float = 0.02  # the glass ends this far inside the greenhouse's side edge

    @property
    def cowl(self) -> tuple[float, float]:
        return self.greenhouse[0]

    @property
    def glass_top(self) -> tuple[float, float]:
        return self.greenhouse[1]

    def half_width(self, y: float) -> float:
        """Greenhouse half width (m) at height y (m)."""
        return self.belt_half_width - (y - self.cowl[1]) * self.tumblehome


WINDSHIELD_RAKE_RAD = math.radians(60.0)  # the car's windshield, from vertical
_RAKE_BY_KIND = {"car": WINDSHIELD_RAKE_RAD, "van": math.radians(55.0), "truck": math.radians(12.0)}


def _greenhouse(cowl, glass_top_y, rake, roof_y, roof_rear_z, rear_base) -> tuple:
    """Greenhouse polygon; the header above the glass leans back 15 % flatter than the glass, which keeps the
    polygon convex."""
    zc, yc = cowl
    zg = zc + (glass_top_y - yc) * math.tan(rake)
    roof_front = (zg + 1.15 * (roof_y - glass_top_y) * math.tan(rake), roof_y)
    return ((zc, yc), (zg, glass_top_y), roof_front, (roof_rear_z, roof_y - 0.01), rear_base)


def _profile(spec: VehicleSpec) -> _Profile:
    """Body proportions for a spec, scaled from its dimensions."""
    hl, hw, h = spec.length_m / 2.0, spec.width_m / 2.0, spec.height_m
    rake = _RAKE_BY_KIND[spec.kind]
    if spec.kind == "car":
        s = spec.length_m / 4.6  # the numbers below are for a 4.6 m saloon
        cowl = (-0.62 * s, 0.85 * h / 1.45)
        rear_base = (1.80 * s, 0.95 * h / 1.45)
        top = ((-hl, 0.70 * h / 1.45, 0.90), (-2.14 * s, 0.75 * h / 1.45, 0.95), (*cowl, 1.0), (*rear_base, 1.0),
               (2.20 * s, 0.95 * h / 1.45, 0.97), (hl, 0.90 * h / 1.45, 0.93))
        gh = _greenhouse(cowl, h - 0.05, rake, h, 1.20 * s, rear_base)
        return _Profile(top, 0.20, (-hl, hl), hw - 0.13, 0.3, gh, ("glass", "paint", "paint", "glass", "paint"),
                        True, 0.0, rake)
    if spec.kind == "van":
        cowl = (-hl + 0.9, 1.12)
        top = ((-hl, 0.98, 0.93), (-hl + 0.15, 1.04, 0.97), (*cowl, 1.0), (hl, 1.15, 1.0))
        gh = _greenhouse(cowl, h - 0.3, rake, h, hl - 0.02, (hl, 1.15))
        return _Profile(top, 0.28, (-hl, hl), hw - 0.03, 0.05, gh, ("glass", "paint", "paint", "paint", "paint"),
                        False, cowl[0] + 1.7, rake)
    cab_back = -hl + 2.25
    cowl = (-hl + 0.1, 1.45)
    top = ((-hl, 1.45, 0.97), (cab_back, 1.45, 0.97))
    gh = _greenhouse(cowl, 2.55, rake, 2.8, cab_back, (cab_back, 1.45))
    box = (cab_back + 0.15, hl, 2.0 * spec.wheel_radius_m + 0.1, h, hw)
    return _Profile(top, 0.45, (-hl, cab_back), hw - 0.05, 0.03, gh, ("glass", "paint", "paint", "paint", "paint"),
                    False, cowl[0] + 1.1, rake, cargo_box=box)


# --- primitive builders ---------------------------------------------------------------------------------------
def _paint(color) -> tuple:
    return (tuple(float(c) for c in color), _PAINT_ROUGHNESS, _PAINT_METALLIC, MAT_CAR_PAINT)


def _triangles(tris: np.ndarray, finish) -> np.ndarray:
    """(n, 3, 3) triangles → VERTEX_DTYPE with face normals, via trimesh."""
    if len(tris) == 0:
        return np.zeros(0, dtype=VERTEX_DTYPE)
    albedo, rough, metal, mat = finish
    mesh = trimesh.Trimesh(vertices=tris.reshape(-1, 3), faces=np.arange(len(tris) * 3).reshape(-1, 3),
                           process=False)
    return from_trimesh(mesh, albedo, roughness=rough, metallic=metal, material=mat)


def _oriented(tris: list, interior: np.ndarray) -> np.ndarray:
    """Drop degenerate triangles and wind the rest counter-clockwise seen from outside a convex piece."""
    t = np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    t = t[area2 > 1e-10]
    n = n[area2 > 1e-10]
    flip = np.einsum("ij,ij->i", n, t.mean(axis=1) - interior) < 0
    t[flip] = t[flip][:, [0, 2, 1]]
    return t


def _loft(sections, tags=None, cap_tags=("cap", "cap")) -> dict[str, np.ndarray]:
    """A convex solid from ≥ 2 convex cross-sections with matching vertex counts (each (k, 3), in order around).

    Returns {tag: (n, 3, 3) outward-wound triangles}; side faces take ``tags[j]`` for edge j (default "side")."""
    secs = [np.asarray(s, dtype=np.float64) for s in sections]
    k = len(secs[0])
    tags = tags or ["side"] * k
    interior = np.concatenate(secs).mean(axis=0)
    out: dict[str, list] = {}
    for a, b in zip(secs[:-1], secs[1:], strict=True):
        for j in range(k):
            j1 = (j + 1) % k
            out.setdefault(tags[j], []).extend([[a[j], a[j1], b[j1]], [a[j], b[j1], b[j]]])
    for sec, tag in ((secs[0], cap_tags[0]), (secs[-1], cap_tags[1])):
        out.setdefault(tag, []).extend([[sec[0], sec[i], sec[i + 1]] for i in range(1, k - 1)])
    return {tag: _oriented(tris, interior) for tag, tris in out.items() if tris}


def _box(lo, hi) -> np.ndarray:
    """(n, 3, 3) outward triangles of an axis-aligned box between corners lo and hi (m)."""
    mesh = trimesh.creation.box(bounds=np.array([lo, hi], dtype=np.float64))
    return np.asarray(mesh.vertices)[np.asarray(mesh.faces)]


def _extrude_profile(polygon_zy, half_width_at, x_offset=0.0):
    """Sections for a (z, y) polygon extruded across x: left and right copies at x = x_offset ± half_width_at(y)."""
    poly = np.asarray(polygon_zy, dtype=np.float64)
    hw = np.array([half_width_at(y) for y in poly[:, 1]])
    return [np.column_stack([x_offset + sgn * hw, poly[:, 1], poly[:, 0]]) for sgn in (-1.0, 1.0)]


# --- exterior ---------------------------------------------------------------------------------------------------
def _arches(spec: VehicleSpec) -> list[tuple[float, float]]:
    clear = spec.wheel_radius_m + 0.05
    return [(z - clear, z + clear) for z in (-spec.wheelbase_m / 2.0, spec.wheelbase_m / 2.0)]


def _lower_body(spec: VehicleSpec, prof: _Profile, z_max: float = math.inf) -> list[dict[str, np.ndarray]]:
    """The body below the windows as convex segments between profile stations and wheel-arch edges."""
    top = np.asarray(prof.top, dtype=np.float64)
    arches = _arches(spec)
    z0, z1 = prof.body_z
    stations = sorted({*top[:, 0], *(z for a in arches for z in a if z0 < z < z1)})
    arch_top = 2.0 * spec.wheel_radius_m + 0.04
    hw = spec.width_m / 2.0
    pieces = []
    for za, zb in zip(stations[:-1], stations[1:], strict=True):
        if za >= z_max - 1e-9:
            break
        mid = 0.5 * (za + zb)
        bottom = arch_top if any(a0 <= mid <= a1 for a0, a1 in arches) else prof.sill_y
        secs = []
        for z in (za, zb):
            yt = float(np.interp(z, top[:, 0], top[:, 1]))
            w = hw * float(np.interp(z, top[:, 0], top[:, 2]))
            c = min(0.07, (yt - bottom) / 3.0)  # chamfer of the upper and lower edges
            secs.append([(-w + c, bottom, z), (w - c, bottom, z), (w, bottom + c, z), (w, yt - c, z),
                         (w - 1.6 * c, yt, z), (-w + 1.6 * c, yt, z), (-w, yt - c, z), (-w, bottom + c, z)])
        pieces.append(_loft(secs))
    return pieces


def _wheel(center: np.ndarray, spec: VehicleSpec, outward: float, sections: int = 20) -> list[np.ndarray]:
    """Tyre (smooth tread, flat sidewalls) and a metal hub disc on the outer side. outward: ±1 along x."""
    r, w = spec.wheel_radius_m, spec.tire_width_m
    ang = np.linspace(0.0, math.tau, sections, endpoint=False)
    ring = np.column_stack([np.zeros(sections), np.cos(ang), np.sin(ang)])
    xa, xb = np.array([-w / 2, 0, 0]), np.array([w / 2, 0, 0])
    verts = np.concatenate([center + xa + r * ring, center + xb + r * ring])
    faces = []
    for i in range(sections):
        j = (i + 1) % sections
        faces += [[i, j, sections + j], [i, sections + j, sections + i]]
    # Wind every tread face to face away from the axle (the tread is not convex as a whole piece).
    faces = np.array(faces)
    tri = verts[faces]
    on_axis = center + np.outer((tri.mean(axis=1) - center)[:, 0], [1.0, 0.0, 0.0])
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    flip = np.einsum("ij,ij->i", n, tri.mean(axis=1) - on_axis) < 0
    faces[flip] = faces[flip][:, [0, 2, 1]]
    tread = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    parts = [from_trimesh(tread, _RUBBER[0], roughness=_RUBBER[1], metallic=0.0, material=MAT_RUBBER, smooth=True)]
    hub_r = 0.62 * r
    for side in (-1.0, 1.0):
        x = np.array([side * w / 2, 0, 0])
        outer, inner = center + x + r * ring, center + x + hub_r * ring
        side_tris = []
        for i in range(sections):
            j = (i + 1) % sections
            side_tris += [[outer[i], outer[j], inner[j]], [outer[i], inner[j], inner[i]]]
        parts.append(_triangles(_oriented(side_tris, center), _RUBBER))
        hub = [[center + x, inner[i], inner[(i + 1) % sections]] for i in range(sections)]
        finish = _HUB if side == outward else _RUBBER
        parts.append(_triangles(_oriented(hub, center), finish))
    return parts


def _wheels(spec: VehicleSpec) -> list[np.ndarray]:
    parts = []
    for contact in wheel_contacts_local(spec):
        center = contact + np.array([0.0, spec.wheel_radius_m, 0.0])
        parts += _wheel(center, spec, outward=math.copysign(1.0, contact[0]))
    return parts


def _lights(spec: VehicleSpec) -> list[np.ndarray]:
    head, tail = light_positions_local(spec)
    size = {"car": (0.30, 0.09), "van": (0.26, 0.14), "truck": (0.30, 0.14)}[spec.kind]
    parts = []
    for centres, radiance in ((head, HEADLIGHT_RADIANCE), (tail, TAILLIGHT_RADIANCE)):
        for c in centres:
            half = np.array([size[0] / 2, size[1] / 2, 0.015])
            parts.append(_triangles(_box(c - half, c + half), (radiance, 0.1, 0.0, MAT_EMISSIVE)))
    return parts


def _bumpers(spec: VehicleSpec, prof: _Profile) -> list[np.ndarray]:
    top = np.asarray(prof.top)
    y0 = prof.sill_y + 0.02
    parts = []
    for z_end, inward in ((prof.body_z[0], 1.0), (spec.length_m / 2.0, -1.0)):
        w = spec.width_m / 2.0 * float(np.interp(z_end, top[:, 0], top[:, 2])) - 0.02
        lo = np.array([-w, y0, min(z_end - 0.04 * inward, z_end + 0.25 * inward)])
        hi = np.array([w, y0 + 0.22, max(z_end - 0.04 * inward, z_end + 0.25 * inward)])
        parts.append(_triangles(_box(lo, hi), _TRIM))
    return parts


def _mirror_boxes(spec: VehicleSpec, prof: _Profile) -> list[tuple[tuple, tuple, tuple]]:
    """(stalk, housing, glass) boxes, each (lo, hi) car-local m, of the left then the right door mirror."""
    zc, yc = prof.cowl
    top = np.asarray(prof.top)
    sides = []
    for sgn in (-1.0, 1.0):
        z0, z1 = zc + 0.20, zc + 0.30
        y_door = float(np.interp(z0, top[:, 0], top[:, 1]))
        x_in = sgn * (spec.width_m / 2.0 - 0.04)
        x_root, x_tip = sgn * (spec.width_m / 2.0 + 0.03), sgn * (spec.width_m / 2.0 + 0.19)
        stalk = ((min(x_in, x_root), y_door - 0.04, z0 + 0.02), (max(x_in, x_root), y_door + 0.06, z1 - 0.02))
        housing = ((min(x_root, x_tip), y_door + 0.02, z0), (max(x_root, x_tip), y_door + 0.15, z1))
        glass = ((min(x_root, x_tip) + 0.01, y_door + 0.03, z1), (max(x_root, x_tip) - 0.01, y_door + 0.14, z1 + 0.005))
        sides.append((stalk, housing, glass))
    return sides


def _mirrors(spec: VehicleSpec, prof: _Profile, paint) -> list[np.ndarray]:
    """Door mirrors: a painted housing on a stalk that starts at the door's top edge beside the A-pillar base (so
    it never floats when seen through the side glass), with a mirror glass at its rear (in the driver's view it
    shows the scene behind: rain_core.gfx.mirrors)."""
    parts = []
    for stalk, housing, glass in _mirror_boxes(spec, prof):
        parts += [_triangles(_box(*stalk), paint), _triangles(_box(*housing), paint), _triangles(_box(*glass), _MIRROR)]
    return parts


def door_mirror_faces(spec: VehicleSpec = CAR_SPEC) -> np.ndarray:
    """The reflecting faces of the door mirrors, car-local m: (2, 4, 3) corners of the left and the right glass's
    rear face, counter-clockwise seen from behind; both face +z, the car's rear."""
    faces = []
    for _, _, (lo, hi) in _mirror_boxes(spec, _profile(spec)):
        z = hi[2]
        faces.append([(lo[0], lo[1], z), (hi[0], lo[1], z), (hi[0], hi[1], z), (lo[0], hi[1], z)])
    return np.array(faces, dtype=np.float64)


def mirror_glass_mask(vertices: np.ndarray) -> np.ndarray:
    """Which vertices of a car or cabin mesh (VERTEX_DTYPE) belong to a door mirror's glass."""
    albedo, rough, metal, mat = _MIRROR
    return (np.all(np.abs(vertices["albedo"] - np.asarray(albedo, np.float32)) < 1e-6, axis=1)
            & (np.round(vertices["params"][:, 2]) == mat) & (np.abs(vertices["params"][:, 0] - rough) < 1e-6))


def _greenhouse_parts(spec: VehicleSpec, prof: _Profile, paint) -> list[np.ndarray]:
    secs = _extrude_profile(prof.greenhouse, prof.half_width)
    # A section's vertices run around the (z, y) polygon; lofting left→right makes edge j the face between
    # polygon vertices j and j+1.
    tags = list(prof.greenhouse_tags)
    pieces = _loft(secs, tags=tags, cap_tags=("sides", "sides"))
    finishes = {"glass": _GLASS, "paint": paint, "sides": _GLASS if prof.side_glass else paint}
    parts = [_triangles(tris, finishes[tag]) for tag, tris in pieces.items()]
    if not prof.side_glass:
        parts += _cab_windows(prof)
    return parts


def _clip_polygon_z(poly: np.ndarray, z_max: float) -> np.ndarray:
    """Sutherland–Hodgman clip of a (z, y) polygon to z ≤ z_max."""
    out = []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        a_in, b_in = a[0] <= z_max, b[0] <= z_max
        if a_in:
            out.append(a)
        if a_in != b_in:
            t = (z_max - a[0]) / (b[0] - a[0])
            out.append(a + t * (b - a))
    return np.array(out)


def _cab_windows(prof: _Profile) -> list[np.ndarray]:
    """Glass panes a few mm proud of the painted cab sides (vans and trucks)."""
    poly = _clip_polygon_z(np.asarray(prof.greenhouse, dtype=np.float64), prof.cab_window_z)
    centre = poly.mean(axis=0)
    poly = centre + (poly - centre) * 0.82  # leave a painted frame
    parts = []
    for sgn in (-1.0, 1.0):
        pts = np.column_stack([[sgn * (prof.half_width(y) + 0.004) for y in poly[:, 1]], poly[:, 1], poly[:, 0]])
        fan = [[pts[0], pts[i], pts[i + 1]] for i in range(1, len(pts) - 1)]
        across = np.array([-sgn * 10.0, float(centre[1]), float(centre[0])])  # a point on the other side
        parts.append(_triangles(_oriented(fan, across), _GLASS))
    return parts


def _cargo_box(prof: _Profile, paint) -> list[np.ndarray]:
    if prof.cargo_box is None:
        return []
    z0, z1, y0, y1, hw = prof.cargo_box
    box = _triangles(_box((-hw, y0, z0), (hw, y1, z1)), paint)
    chassis = _triangles(_box((-0.5, 0.55, prof.body_z[1] - 0.2), (0.5, y0, z1 - 0.1)), _CHASSIS)
    light_bar = _triangles(_box((-hw + 0.05, 0.62, z1 - 0.12), (hw - 0.05, 0.95, z1 - 0.01)), _TRIM)
    return [box, chassis, light_bar]


def vehicle_mesh(spec: VehicleSpec, color=EGO_COLOR) -> np.ndarray:
    """Exterior mesh of a vehicle in its local frame (VERTEX_DTYPE triangles).

    color: linear RGB body paint (3,). Body in MAT_CAR_PAINT, windows MAT_GLASS, tyres MAT_RUBBER on the wheel
    contacts, head and tail lenses MAT_EMISSIVE (albedo = radiance), black bumpers."""
    color = np.asarray(color, dtype=np.float64).reshape(3)
    if not np.all(np.isfinite(color)) or np.any(color < 0):
        raise ValueError(f"color must be finite linear RGB ≥ 0, got {color}")
    return _vehicle_mesh(spec, tuple(float(c) for c in color))


@lru_cache(maxsize=16)  # ~0.15 MB each; the traffic of one seed is a handful of cars
def _vehicle_mesh(spec: VehicleSpec, color: tuple[float, float, float]) -> np.ndarray:
    """vehicle_mesh, built once per (spec, colour) and read-only: every scene and every car that enters the
    traffic with a colour seen before reuses it (a car is ~40 ms of NumPy)."""
    prof = _profile(spec)
    paint = _paint(np.asarray(color))
    parts = [_triangles(tris, paint) for piece in _lower_body(spec, prof) for tris in piece.values()]
    parts += _greenhouse_parts(spec, prof, paint)
    parts += _cargo_box(prof, paint)
    parts += _wheels(spec) + _lights(spec) + _bumpers(spec, prof) + _mirrors(spec, prof, paint)
    mesh = concat(parts)
    mesh.setflags(write=False)
    return mesh


# --- windshield -------------------------------------------------------------------------------------------------
def windshield_frame(spec: VehicleSpec = CAR_SPEC) -> dict:
    """The plane and size of the windshield, local frame (m).

    bottom_center: middle of the glass's lower edge; up_along_glass: unit vector up the glass (rises and runs
    backwards, +Z); right: unit +X; normal: unit outward normal (forward and up); width_m: glass width at the
    bottom edge, top_width_m at the top; height_m: length along the glass bottom→top; rake_rad: angle from
    vertical; sag_m: how far the curved glass bulges outward of this plane at its centre."""
    prof = _profile(spec)
    rake = prof.rake_rad
    (zc, yc), (_, yg) = prof.cowl, prof.glass_top
    m = prof.glass_margin_m
    return {
        "bottom_center": np.array([0.0, yc, zc]),
        "up_along_glass": np.array([0.0, math.cos(rake), math.sin(rake)]),
        "right": np.array([1.0, 0.0, 0.0]),
        "normal": np.array([0.0, math.sin(rake), -math.cos(rake)]),
        "width_m": 2.0 * (prof.half_width(yc) - m),
        "top_width_m": 2.0 * (prof.half_width(yg) - m),
        "height_m": (yg - yc) / math.cos(rake),
        "rake_rad": rake,
        "sag_m": 0.05 if spec.kind == "car" else 0.02,
    }


def windshield_surface(spec: VehicleSpec = CAR_SPEC, n_u: int = 24, n_v: int = 12):
    """The curved windshield as an (n_u × n_v) grid in the local frame.

    Returns (positions (n, 3) m, unit outward normals (n, 3), uv (n, 2) in [0, 1]², triangles (m, 3) int32),
    n = n_u·n_v, vertex index = j·n_u + i for u = i/(n_u−1) (left → right) and v = j/(n_v−1) (bottom → top).
    The glass bulges outward like a pillow: offset sag·(1−(2u−1)²)·(1−(2v−1)²) along the frame normal, so its
    edges lie on the frame plane under the pillars, header and cowl. Triangles wind counter-clockwise seen from
    outside (along the normals)."""
    if int(n_u) < 2 or int(n_v) < 2:
        raise ValueError(f"n_u and n_v must be ≥ 2, got {n_u}, {n_v}")
    n_u, n_v = int(n_u), int(n_v)
    f = windshield_frame(spec)
    b, up, right, nrm = f["bottom_center"], f["up_along_glass"], f["right"], f["normal"]
    w0, w1, h, sag = f["width_m"], f["top_width_m"], f["height_m"], f["sag_m"]
    u, v = np.meshgrid(np.linspace(0.0, 1.0, n_u), np.linspace(0.0, 1.0, n_v))
    u, v = u.ravel(), v.ravel()
    width = w0 + (w1 - w0) * v
    bu, bv = 1.0 - (2.0 * u - 1.0) ** 2, 1.0 - (2.0 * v - 1.0) ** 2
    pos = (b + np.outer(v * h, up) + np.outer((u - 0.5) * width, right) + np.outer(sag * bu * bv, nrm))
    # Analytic tangents of the surface, then n = ∂P/∂v × ∂P/∂u (points along +normal for this frame).
    d_u = np.outer(width, right) + np.outer(sag * (-4.0 * (2.0 * u - 1.0)) * bv, nrm)
    d_v = (np.outer(np.full_like(v, h), up) + np.outer((u - 0.5) * (w1 - w0), right)
           + np.outer(sag * bu * (-4.0 * (2.0 * v - 1.0)), nrm))
    normals = np.cross(d_v, d_u)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    uv = np.column_stack([u, v])
    i, j = np.meshgrid(np.arange(n_u - 1), np.arange(n_v - 1))
    k = (j * n_u + i).ravel()
    tris = np.concatenate([np.column_stack([k, k + n_u, k + 1]), np.column_stack([k + 1, k + n_u, k + n_u + 1])])
    return pos, normals, uv, tris.astype(np.int32)


# --- cabin ------------------------------------------------------------------------------------------------------
def driver_eye_local(spec: VehicleSpec = CAR_SPEC) -> np.ndarray:
    """Driver's eye (m, local frame) for a vehicle type: left-hand drive, so x < 0."""
    zc, yc = _profile(spec).cowl
    return np.array([-0.2 * spec.width_m, yc + 0.38, zc + 1.05])


DRIVER_EYE_LOCAL = driver_eye_local(CAR_SPEC)  # m, the ego car's driver


def cabin_mesh(spec: VehicleSpec = CAR_SPEC, color=EGO_COLOR) -> np.ndarray:
    """What the driver sees of the car (VERTEX_DTYPE, local frame): the hood and front wings (paint, ``color``),
    dashboard with instrument binnacle, A-pillars, roof header and headliner, door tops, steering wheel and
    mirrors. The glass is not included (``windshield_surface`` is drawn by the windshield effect)."""
    color = np.asarray(color, dtype=np.float64).reshape(3)
    prof = _profile(spec)
    paint = _paint(color)
    f = windshield_frame(spec)
    eye = driver_eye_local(spec)
    zc, yc = prof.cowl
    zg, yg = prof.glass_top
    rake = prof.rake_rad
    up2 = np.array([math.sin(rake), math.cos(rake)])  # (z, y) up along the glass
    n2 = np.array([-math.cos(rake), math.sin(rake)])  # (z, y) outward normal
    parts = [_triangles(tris, paint) for piece in _lower_body(spec, prof, z_max=zc) for tris in piece.values()]
    parts += _mirrors(spec, prof, paint)
    inner_hw = prof.belt_half_width
    # Dashboard: a slab under the glass whose top stays below the eye's sight line to the glass's lower edge.
    z_rear = eye[2] - 0.62
    sight = (eye[1] - yc) / (eye[2] - zc)  # rise per m of the line eye → lower glass edge
    y_rear = yc + sight * (z_rear - zc) - 0.09
    # Its front edge rises just above that sight line (but stays under the glass) to hide the glass's lower edge.
    z_lip = zc + 0.03
    y_lip = yc + 0.03 * 0.5 * (sight + 1.0 / math.tan(rake))
    dash = [(z_lip, y_lip), (z_rear, y_rear), (z_rear + 0.03, y_rear - 0.08), (z_rear, yc - 0.35),
            (z_lip, yc - 0.35)]
    parts += [_triangles(t, _DASH) for t in _loft(_extrude_profile(dash, lambda y: inner_hw)).values()]
    # Instrument binnacle in front of the driver.
    zb0, zb1 = z_rear - 0.28, z_rear - 0.01
    yb = yc + sight * (zb1 - zc) - 0.025
    binnacle = [(zb0, yc + sight * (zb0 - zc) - 0.06), (zb1 - 0.06, yb), (zb1, yb - 0.015), (zb1, y_rear - 0.02)]
    parts += [_triangles(t, _DASH) for t in
              _loft(_extrude_profile(binnacle, lambda y: 0.17, x_offset=float(eye[0]))).values()]
    # A-pillars: wedges inside the glass plane covering its side edges, from below the cowl to the header.
    b, up, nrm, h = f["bottom_center"], f["up_along_glass"], f["normal"], f["height_m"]
    for sgn in (-1.0, 1.0):
        secs = []
        for t in (-0.05, 1.05):
            p = b + up * (t * h)
            hw = prof.half_width(float(p[1]))
            outer = p + np.array([sgn * (hw + 0.01), 0.0, 0.0])
            inner = p + np.array([sgn * (hw - 0.065), 0.0, 0.0])
            secs.append([outer, inner, inner - nrm * 0.035, outer - nrm * 0.05])
        parts += [_triangles(t, _PILLAR) for t in _loft(secs).values()]
    # Roof header (covers the glass's top edge) running back into the headliner.
    a1 = np.array([zg, yg]) - 0.06 * up2
    bp = a1 - 0.04 * n2
    header = [tuple(a1), (zg, yg), (zg + 0.9, spec.height_m - 0.01), (zg + 0.9, yg - 0.03), tuple(bp)]
    hw_top = prof.half_width(yg) + 0.01
    parts += [_triangles(t, _HEADLINER) for t in _loft(_extrude_profile(header, lambda y: hw_top)).values()]
    # Door tops beside the driver and the passenger.
    top = np.asarray(prof.top)
    for sgn in (-1.0, 1.0):
        secs = []
        for z in (zc + 0.05, eye[2] + 0.6):
            yt = float(np.interp(z, top[:, 0], top[:, 1])) + 0.02
            x0, x1 = sgn * (spec.width_m / 2.0 - 0.05), sgn * (inner_hw - 0.05)
            secs.append([(x0, yc - 0.4, z), (x1, yc - 0.4, z), (x1, yt - 0.03, z), (x0, yt, z)])
        parts += [_triangles(t, _PILLAR) for t in _loft(secs).values()]
    parts += _steering_wheel(eye, z_rear, y_rear)
    return concat(parts)


def _steering_wheel(eye: np.ndarray, z_dash: float, y_dash: float) -> list[np.ndarray]:
    """A 38 cm wheel tilted 25° back from vertical, its top rim below the dashboard's line of sight."""
    tilt = math.radians(25.0)
    centre = np.array([eye[0], y_dash - 0.12, z_dash + 0.22])
    rot = trimesh.transformations.rotation_matrix(-tilt, [1.0, 0.0, 0.0])
    xf = trimesh.transformations.translation_matrix(centre) @ rot
    rim = trimesh.creation.torus(0.19, 0.017, major_sections=32, minor_sections=8, transform=xf)
    # Leather-grey rather than black, so the rim and spokes read against the dark dashboard.
    parts = [from_trimesh(rim, _WHEEL_RIM, roughness=0.55, material=MAT_GENERIC, smooth=True)]
    hub = trimesh.creation.cylinder(radius=0.06, height=0.06, sections=12, transform=xf)
    parts.append(from_trimesh(hub, (0.025, 0.025, 0.025), roughness=0.6, material=MAT_GENERIC))
    for offset, extents in (((0.095, 0.0, 0.0), (0.19, 0.03, 0.02)), ((-0.095, 0.0, 0.0), (0.19, 0.03, 0.02)),
                            ((0.0, -0.095, 0.0), (0.03, 0.19, 0.02))):  # spokes: right, left, down
        spoke = trimesh.creation.box(extents=extents)
        spoke.apply_transform(xf @ trimesh.transformations.translation_matrix(offset))
        parts.append(from_trimesh(spoke, _WHEEL_SPOKE, roughness=0.5, material=MAT_GENERIC))
    column = trimesh.creation.cylinder(radius=0.035, segment=[centre, centre + rot[:3, :3] @ [0, 0, -0.35]],
                                       sections=10)
    parts.append(from_trimesh(column, (0.02, 0.02, 0.02), roughness=0.6, material=MAT_GENERIC))
    return parts
