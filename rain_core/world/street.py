"""The street's parts: road, kerbs, sidewalks, the railway underpass, the fuel station, lamps, trees and
buildings. Each part returns (vertex arrays, occluder triangle soups[, lamps])."""


from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rain_core import layout
from rain_core.mesh import (
    MAT_ASPHALT,
    MAT_CONCRETE,
    MAT_EMISSIVE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_PAINT,
)
from rain_core.world.primitives import (
    NX_,
    NY_,
    NZ_,
    PX_,
    PY_,
    PZ_,
    _blobs,
    _box_tris,
    _boxes,
    _cylinders,
    _facade_quads,
    _in_zones,
    _pack,
    _quads,
    _rects_down,
    _rects_up,
    _span,
)

LUMINOUS_EFFICACY_LM_PER_W = 683.0  # lm/W: emissive albedo = luminance (cd/m²) / this
GROUND_HALF_X_M = 200.0  # m, the grass plane ends at |x| = this

_P = layout.PERIOD_M
_HW = layout.ROAD_HALF_WIDTH_M
_KERB_OUT = _HW + layout.KERB_WIDTH_M  # m, kerb back / sidewalk start |x|
_WALK_OUT = _KERB_OUT + layout.SIDEWALK_WIDTH_M  # m, sidewalk outer edge |x|
_KH = layout.KERB_HEIGHT_M

# Railway underpass: an earth embankment crosses the street along X; the deck spans the street and rests on
# concrete wing walls that stand just outside the sidewalks.
_DECK_Z0 = layout.BRIDGE_Z_M - layout.BRIDGE_DEPTH_M / 2
_DECK_Z1 = layout.BRIDGE_Z_M + layout.BRIDGE_DEPTH_M / 2
_DECK_THICK_M = 1.0
_DECK_TOP = layout.BRIDGE_CLEARANCE_M + _DECK_THICK_M
_DECK_HALF_X = 12.5
_ABUT_X = _WALK_OUT + 0.1  # m, |x| of the wing walls' road-facing face
_EMB_BASE_HALF_Z = 15.0  # m, embankment footprint half-width along z at the ground

# Fuel station (+X side).
_CAN_Z0 = layout.CANOPY_Z_M - layout.CANOPY_LENGTH_M / 2
_CAN_Z1 = layout.CANOPY_Z_M + layout.CANOPY_LENGTH_M / 2
_CAN_X0, _CAN_X1 = layout.CANOPY_X_RANGE_M
_CAN_Y0 = layout.CANOPY_HEIGHT_M
_CAN_Y1 = _CAN_Y0 + 0.9
_STATION_Z = (layout.CANOPY_Z_M - 28.0, layout.CANOPY_Z_M + 48.0)  # m, forecourt extent along z

_LAMPS_PER_SIDE = 34  # PERIOD_M / 34 ≈ 35.3 m spacing, so the pattern tiles exactly
_LAMP_POLE_D = _KERB_OUT + 0.5  # m, |x| of the pole
_LAMP_HEAD_D = 5.9  # m, |x| of the light source: over the outer lane's outer wheel track
_LAMP_HEAD_Y = 7.9  # m
_LAMP_CD = 6000.0  # cd, a 100 W-class LED street light
_TREE_D = _KERB_OUT + 1.5  # m, |x| of tree trunks (tree pits in the sidewalk)


def _rgb_unit_luminance(rgb) -> np.ndarray:
    rgb = np.asarray(rgb, dtype=np.float64)
    return rgb / (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])


_LED_4000K = _rgb_unit_luminance((1.0, 0.84, 0.68))
_LED_5000K = _rgb_unit_luminance((1.0, 0.93, 0.85))
_WARM_WINDOW = _rgb_unit_luminance((1.0, 0.72, 0.42))


def _emissive(rgb_unit, luminance_cd_m2: float) -> np.ndarray:
    """Emissive albedo (W/sr/m² at 683 lm/W) for a colour of unit luminance and a luminance in cd/m²."""
    return np.asarray(rgb_unit, dtype=np.float64) * (luminance_cd_m2 / LUMINOUS_EFFICACY_LM_PER_W)


@dataclass
class StreetLamp:
    """One light source. position: m (the lens centre); direction: unit vector of the beam axis (mostly down);
    intensity_cd: peak luminous intensity along the axis (cd); color: linear RGB with luminance 1."""

    position: np.ndarray
    direction: np.ndarray
    intensity_cd: float
    color: np.ndarray



# ----------------------------------------------------------------------------------------------------------------
# Scene parts. Each returns (vertex arrays, occluder triangle soups).

_ASPHALT = (0.075, 0.075, 0.078)
_PAINT_WHITE = (0.65, 0.65, 0.62)
_PAINT_YELLOW = (0.62, 0.42, 0.05)
_KERB = (0.38, 0.37, 0.35)
_SIDEWALK = (0.30, 0.29, 0.27)
_GRASS = (0.06, 0.10, 0.035)
_CONCRETE = (0.33, 0.32, 0.30)
_DARK_METAL = (0.08, 0.085, 0.09)
_POLE = (0.22, 0.23, 0.24)
_GLASS = (0.03, 0.035, 0.04)

_WALL_PALETTE = np.array([
    (0.30, 0.12, 0.08),  # red brick
    (0.22, 0.10, 0.07),  # dark brick
    (0.45, 0.38, 0.27),  # sandstone
    (0.35, 0.34, 0.32),  # grey concrete
    (0.58, 0.56, 0.52),  # white plaster
    (0.50, 0.42, 0.30),  # ochre render
    (0.28, 0.33, 0.35),  # blue-grey panels
    (0.14, 0.14, 0.15),  # dark cladding
    (0.42, 0.30, 0.24),  # terracotta render
])
_AWNING_PALETTE = np.array([(0.35, 0.03, 0.03), (0.03, 0.15, 0.06), (0.03, 0.06, 0.25), (0.45, 0.38, 0.05),
                            (0.25, 0.25, 0.25)])


def _road_and_streetside(rng: np.random.Generator) -> list[np.ndarray]:
    parts = []
    seg = 40.0  # m, long strips are cut into segments so no triangle is a kilometre long
    z0 = np.arange(0.0, _P, seg)
    z1 = z0 + seg
    parts.append(_rects_up(-_HW, _HW, z0, z1, 0.0, _ASPHALT, 0.9, MAT_ASPHALT))
    # Markings, 4 mm proud of the asphalt to stay out of its depth range.
    y = 0.004
    for xc in (-0.12, 0.12):  # double yellow centre line
        parts.append(_rects_up(xc - 0.05, xc + 0.05, z0, z1, y, _PAINT_YELLOW, 0.6, MAT_PAINT))
    for xc in (-(_HW - 0.25), _HW - 0.25):  # solid edge lines
        parts.append(_rects_up(xc - 0.075, xc + 0.075, z0, z1, y, _PAINT_WHITE, 0.6, MAT_PAINT))
    dz = np.arange(0.0, _P, 12.0)  # 3 m dash, 9 m gap between lanes of one direction
    for xc in (-layout.LANE_WIDTH_M, layout.LANE_WIDTH_M):
        parts.append(_rects_up(xc - 0.06, xc + 0.06, dz, dz + 3.0, y, _PAINT_WHITE, 0.6, MAT_PAINT))
    # Kerbs, sidewalk slabs (2 m, slightly varied), ground.
    slab0 = np.arange(0.0, _P, 2.0)
    for side in (-1.0, 1.0):
        lo_x, hi_x = _span(side, _HW, _KERB_OUT)
        n = len(z0)
        parts.append(_boxes(np.stack([np.full(n, lo_x), np.full(n, -0.1), z0], 1),
                            np.stack([np.full(n, hi_x), np.full(n, _KH), z1], 1), _KERB, 0.7, 0.0, MAT_CONCRETE,
                            faces=(PY_, NX_ if side > 0 else PX_)))
        lo_x, hi_x = _span(side, _KERB_OUT, _WALK_OUT)
        shade = rng.uniform(0.9, 1.08, len(slab0))[:, None] * np.asarray(_SIDEWALK)
        parts.append(_rects_up(lo_x, hi_x, slab0, slab0 + 2.0, _KH, shade, 0.75, MAT_CONCRETE))
        m = len(z0)
        parts.append(_boxes(np.stack([np.full(m, lo_x), np.full(m, -0.1), z0], 1),
                            np.stack([np.full(m, hi_x), np.full(m, _KH), z1], 1), _SIDEWALK, 0.75, 0.0,
                            MAT_CONCRETE, faces=(PX_ if side > 0 else NX_,)))
        lo_x, hi_x = _span(side, _WALK_OUT, GROUND_HALF_X_M)
        parts.append(_rects_up(lo_x, hi_x, z0, z1, 0.0, _GRASS, 0.95, MAT_GENERIC))
    return parts


def _bridge() -> tuple[list[np.ndarray], list[np.ndarray], list[StreetLamp]]:
    parts, occ, lamps = [], [], []
    lo = (-_DECK_HALF_X, layout.BRIDGE_CLEARANCE_M, _DECK_Z0)
    hi = (_DECK_HALF_X, _DECK_TOP, _DECK_Z1)
    parts.append(_boxes(lo, hi, _CONCRETE, 0.8, 0.0, MAT_CONCRETE))
    occ.append(_box_tris(lo, hi))
    # Embankment: a trapezoid in (z, y) extruded along x from the wing wall out to the ground's edge.
    zc = layout.BRIDGE_Z_M
    prof = np.array([(zc - _EMB_BASE_HALF_Z, 0.0), (zc + _EMB_BASE_HALF_Z, 0.0), (_DECK_Z1, _DECK_TOP),
                     (_DECK_Z0, _DECK_TOP)])  # (z, y), counter-clockwise seen from +x
    for side in (-1.0, 1.0):
        xa, xb = _ABUT_X * side, GROUND_HALF_X_M * side
        near = np.column_stack([np.full(4, xa), prof[:, 1], prof[:, 0]])
        far = np.column_stack([np.full(4, xb), prof[:, 1], prof[:, 0]])
        # Slopes and top: quads between consecutive profile corners (the base lies on the ground, skipped).
        tris = []
        for a, b in ((1, 2), (2, 3), (3, 0)):
            q = np.array([near[a], far[a], far[b], near[b]])
            tris.append(q[[0, 1, 2, 0, 2, 3]].reshape(2, 3, 3))
        tris = np.concatenate(tris)
        if side < 0:  # mirrored in x: reverse the winding so the faces still point outwards
            tris = tris[:, ::-1]
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        parts.append(_pack(tris.reshape(1, -1, 3), np.repeat(n, 3, axis=0)[None], _GRASS, 0.95, 0.0,
                           MAT_GENERIC))
        # The road-facing end is the concrete wing wall (trapezoid = two triangles).
        cap = near[[0, 1, 2, 0, 2, 3]] if side > 0 else near[[0, 2, 1, 0, 3, 2]]
        cap_n = np.array([-side, 0.0, 0.0])
        parts.append(_pack(cap[None], cap_n[None, None], (0.28, 0.27, 0.25), 0.85, 0.0, MAT_CONCRETE))
        occ.append(np.concatenate([tris, cap.reshape(2, 3, 3)]))
    # Railings along both deck edges: posts every 1.5 m, a top and a mid rail.
    xs = np.arange(-_DECK_HALF_X - 4.0, _DECK_HALF_X + 4.0 + 1e-6, 1.5)
    for ze in (_DECK_Z0 + 0.15, _DECK_Z1 - 0.15):
        n = len(xs)
        parts.append(_boxes(np.stack([xs - 0.04, np.full(n, _DECK_TOP), np.full(n, ze - 0.04)], 1),
                            np.stack([xs + 0.04, np.full(n, _DECK_TOP + 1.1), np.full(n, ze + 0.04)], 1),
                            _POLE, 0.5, 0.8, MAT_METAL, faces=(NX_, PX_, NZ_, PZ_)))
        for yr, t in ((_DECK_TOP + 1.1, 0.06), (_DECK_TOP + 0.55, 0.04)):
            parts.append(_boxes((xs[0], yr - t, ze - t), (xs[-1], yr + t, ze + t), _POLE, 0.5, 0.8, MAT_METAL))
    # Lights on the deck underside above each carriageway.
    for xl in (-3.5, 3.5):
        y = layout.BRIDGE_CLEARANCE_M - 0.06
        parts.append(_boxes((xl - 0.4, y, zc - 0.2), (xl + 0.4, layout.BRIDGE_CLEARANCE_M, zc + 0.2), _DARK_METAL,
                            0.5, 0.6, MAT_METAL, faces=(NX_, PX_, NZ_, PZ_)))
        cd = 2000.0
        parts.append(_rects_down(xl - 0.35, xl + 0.35, zc - 0.15, zc + 0.15, y - 0.002,
                                 _emissive(_LED_5000K, cd / 0.21), 0.3, MAT_EMISSIVE))
        lamps.append(StreetLamp(np.array([xl, y - 0.01, zc]), np.array([0.0, -1.0, 0.0]), cd, _LED_5000K.copy()))
    return parts, occ, lamps


_PILLAR_X = np.array([_KERB_OUT + 1.5, 14.6])  # m, the canopy's four pillars (0.5 m square)
_PILLAR_Z = np.array([_CAN_Z0 + 4.0, _CAN_Z1 - 4.0])
_PUMP_ISLAND = (14.0, 15.2, _CAN_Z0 + 2.0, _CAN_Z1 - 2.0)  # x0, x1, z0, z1 (m)
_KIOSK = (22.0, 30.0, layout.CANOPY_Z_M + 14.0, layout.CANOPY_Z_M + 32.0)


def station_solid_boxes() -> np.ndarray:
    """(N, 4) x0, x1, z0, z1 (m) of the fuel station's solid parts a car cannot drive through: the canopy's
    pillars, the pump island, the kiosk."""
    gx, gz = (a.ravel() for a in np.meshgrid(_PILLAR_X, _PILLAR_Z))
    pillars = np.stack([gx - 0.25, gx + 0.25, gz - 0.25, gz + 0.25], axis=1)
    return np.concatenate([pillars, [_PUMP_ISLAND, _KIOSK]])


def _station() -> tuple[list[np.ndarray], list[np.ndarray], list[StreetLamp]]:
    parts, occ, lamps = [], [], []
    za, zb = _STATION_Z
    parts.append(_boxes((_WALK_OUT, -0.1, za), (34.0, _KH, zb), (0.27, 0.27, 0.26), 0.8, 0.0, MAT_CONCRETE,
                        faces=(PY_, PX_, NZ_, PZ_)))
    # Canopy: white underside, red fascia, grey top; it cantilevers over the outer lane from its pillars.
    lo, hi = (_CAN_X0, _CAN_Y0, _CAN_Z0), (_CAN_X1, _CAN_Y1, _CAN_Z1)
    parts.append(_boxes(lo, hi, (0.75, 0.75, 0.74), 0.6, 0.0, MAT_GENERIC, faces=(NY_,)))
    parts.append(_boxes(lo, hi, (0.45, 0.02, 0.02), 0.5, 0.0, MAT_GENERIC, faces=(NX_, PX_, NZ_, PZ_)))
    parts.append(_boxes(lo, hi, (0.30, 0.30, 0.30), 0.7, 0.0, MAT_METAL, faces=(PY_,)))
    occ.append(_box_tris(lo, hi))
    gx, gz = (a.ravel() for a in np.meshgrid(_PILLAR_X, _PILLAR_Z))
    base_y = np.where(gx < _WALK_OUT, _KH, _KH + 0.15)
    parts.append(_boxes(np.stack([gx - 0.25, base_y, gz - 0.25], 1), np.stack([gx + 0.25, np.full(4, _CAN_Y0),
                                                                               gz + 0.25], 1),
                        (0.6, 0.6, 0.6), 0.5, 0.3, MAT_METAL, faces=(NX_, PX_, NZ_, PZ_)))
    # Pump islands (raised concrete) with pumps between the pillars.
    ix0, ix1, iz0, iz1 = _PUMP_ISLAND
    parts.append(_boxes((ix0, 0.0, iz0), (ix1, _KH + 0.15, iz1), (0.5, 0.5, 0.48), 0.7,
                        0.0, MAT_CONCRETE, faces=(NX_, PX_, PY_, NZ_, PZ_)))
    pump_z = np.array([layout.CANOPY_Z_M - 4.0, layout.CANOPY_Z_M, layout.CANOPY_Z_M + 4.0])
    n = len(pump_z)
    y0 = _KH + 0.15
    lo = np.stack([np.full(n, 14.35), np.full(n, y0), pump_z - 0.5], 1)
    hi = np.stack([np.full(n, 14.85), np.full(n, y0 + 1.5), pump_z + 0.5], 1)
    parts.append(_boxes(lo, hi, (0.45, 0.03, 0.03), 0.4, 0.0, MAT_GENERIC, faces=(NX_, PX_, NZ_, PZ_)))
    lo2 = lo.copy()
    lo2[:, 1] = y0 + 1.5
    hi2 = hi.copy()
    hi2[:, 1] = y0 + 1.9
    parts.append(_boxes(lo2, hi2, (0.7, 0.7, 0.68), 0.4, 0.0, MAT_GENERIC))
    parts.append(_facade_quads(np.full(n, 14.34), -1.0, y0 + 1.0, y0 + 1.35, pump_z - 0.3, pump_z + 0.3,
                               _emissive(_LED_5000K, 150.0), 0.2, MAT_EMISSIVE))
    # Canopy lights: 3 × 2 recessed panels, each also a light source.
    lx = np.array([5.5, 9.5, 13.5])
    lz = np.array([_CAN_Z0 + 6.0, _CAN_Z1 - 6.0])
    gx, gz = (a.ravel() for a in np.meshgrid(lx, lz))
    cd = 3000.0
    parts.append(_rects_down(gx - 0.3, gx + 0.3, gz - 0.3, gz + 0.3, _CAN_Y0 - 0.002,
                             _emissive(_LED_5000K, cd / 0.36), 0.3, MAT_EMISSIVE))
    for x, z in zip(gx, gz, strict=True):
        lamps.append(StreetLamp(np.array([x, _CAN_Y0 - 0.01, z]), np.array([0.0, -1.0, 0.0]), cd,
                                _LED_5000K.copy()))
    # Kiosk: white box, glass shop front facing the road, roof slab overhanging the entrance.
    kx0, kx1, kz0, kz1 = _KIOSK
    parts.append(_boxes((kx0, _KH, kz0), (kx1, 3.6, kz1), (0.6, 0.6, 0.58), 0.7, 0.0, MAT_CONCRETE,
                        faces=(NX_, PX_, NZ_, PZ_)))
    parts.append(_facade_quads(kx0 - 0.02, -1.0, 0.45, 2.8, kz0 + 1.0, kz1 - 1.0, _emissive(_LED_5000K, 250.0),
                               0.1, MAT_EMISSIVE))
    roof_lo, roof_hi = (kx0 - 1.5, 3.6, kz0 - 0.3), (kx1 + 0.3, 3.9, kz1 + 0.3)
    parts.append(_boxes(roof_lo, roof_hi, (0.45, 0.02, 0.02), 0.6, 0.0, MAT_GENERIC))
    occ.append(_box_tris(roof_lo, roof_hi))
    # Price pylon at the forecourt entrance, lit panels facing both directions of traffic.
    sx0, sx1, sz0, sz1 = _WALK_OUT + 0.5, _WALK_OUT + 1.1, za + 2.0, za + 4.0
    parts.append(_boxes((sx0, 0.0, sz0), (sx1, 6.5, sz1), (0.45, 0.02, 0.02), 0.5, 0.0, MAT_GENERIC))
    for zf, sgn in ((sz0 - 0.02, -1.0), (sz1 + 0.02, 1.0)):
        p0 = np.array([[sx0 + 0.05, 2.5, zf]])
        u = np.array([[sx1 - sx0 - 0.1, 0.0, 0.0]])
        v = np.array([[0.0, 3.5, 0.0]])
        if sgn < 0:
            u, v = v, u
        parts.append(_quads(p0, u, v, _emissive((1.0, 1.0, 1.0), 400.0), 0.2, 0.0, MAT_EMISSIVE))
    return parts, occ, lamps


def _street_lamps(detail_segments: int) -> tuple[list[np.ndarray], list[StreetLamp]]:
    parts, lamps = [], []
    s = _P / _LAMPS_PER_SIDE
    skip = [(layout.BRIDGE_Z_M - 13.0, layout.BRIDGE_Z_M + 13.0)]
    for side, phase in ((1.0, 0.25), (-1.0, 0.75)):
        z = (np.arange(_LAMPS_PER_SIDE) + phase) * s
        zones = skip + ([(_CAN_Z0 - 2.0, _CAN_Z1 + 2.0)] if side > 0 else [])
        z = z[~_in_zones(z - 0.5, z + 0.5, zones)]
        n = len(z)
        parts.append(_cylinders(np.stack([np.full(n, side * _LAMP_POLE_D), np.full(n, _KH), z], 1), 0.09,
                                _LAMP_HEAD_Y + 0.15 - _KH, detail_segments, _POLE, 0.5, 0.7, MAT_METAL))
        ax0, ax1 = _span(side, _LAMP_HEAD_D + 0.3, _LAMP_POLE_D)
        parts.append(_boxes(np.stack([np.full(n, ax0), np.full(n, _LAMP_HEAD_Y + 0.02), z - 0.04], 1),
                            np.stack([np.full(n, ax1), np.full(n, _LAMP_HEAD_Y + 0.1), z + 0.04], 1),
                            _POLE, 0.5, 0.7, MAT_METAL))
        hx0, hx1 = _span(side, _LAMP_HEAD_D - 0.35, _LAMP_HEAD_D + 0.35)
        y0 = _LAMP_HEAD_Y - 0.02
        parts.append(_boxes(np.stack([np.full(n, hx0), np.full(n, y0), z - 0.17], 1),
                            np.stack([np.full(n, hx1), np.full(n, y0 + 0.16), z + 0.17], 1),
                            _DARK_METAL, 0.5, 0.6, MAT_METAL, faces=(NX_, PX_, PY_, NZ_, PZ_)))
        lens_area = 0.6 * 0.26
        parts.append(_rects_down(hx0 + 0.05, hx1 - 0.05, z - 0.13, z + 0.13, y0 - 0.002,
                                 _emissive(_LED_4000K, _LAMP_CD / lens_area), 0.2, MAT_EMISSIVE))
        # Aimed slightly toward the road's centre line.
        d = np.array([-side * 0.15, -1.0, 0.0])
        d /= np.linalg.norm(d)
        for zz in z:
            lamps.append(StreetLamp(np.array([side * _LAMP_HEAD_D, y0 - 0.01, zz]), d.copy(), _LAMP_CD,
                                    _LED_4000K.copy()))
    return parts, lamps


def _trees(rng: np.random.Generator, detail_segments: int, subdiv: int) -> tuple[list[np.ndarray], np.ndarray]:
    """The street trees' meshes and their trunks, (N, 3) x, z, radius (m)."""
    parts, trunks = [], []
    s = _P / _LAMPS_PER_SIDE
    template = trimesh.creation.icosphere(subdivisions=subdiv)
    for side, phase in ((1.0, 0.25), (-1.0, 0.75)):
        lamp_z = (np.arange(_LAMPS_PER_SIDE) + phase) * s
        z = (lamp_z[:, None] + s * np.array([1 / 3, 2 / 3])[None]).ravel()
        z = z + rng.uniform(-1.0, 1.0, len(z))
        keep = rng.random(len(z)) > 0.2
        zones = [(layout.BRIDGE_Z_M - 18.0, layout.BRIDGE_Z_M + 18.0)]
        if side > 0:
            zones.append((_STATION_Z[0] - 3.0, _CAN_Z1 + 4.0))
        z = np.mod(z[keep & ~_in_zones(z - 3.0, z + 3.0, zones)], _P)
        n = len(z)
        x = np.full(n, side * _TREE_D)
        # Street trees are pruned to keep ~4.5 m clear over the carriageway: tall trunks, crowns narrow across x.
        trunk_h = rng.uniform(3.0, 3.8, n)
        r_x = rng.uniform(1.5, 1.9, n)
        r_y = rng.uniform(1.8, 2.6, n)
        trunk_r = rng.uniform(0.12, 0.18, n)
        trunks.append(np.stack([x, z, trunk_r], axis=1))
        parts.append(_cylinders(np.stack([x, np.full(n, _KH), z], 1), trunk_r, trunk_h + r_y,
                                max(4, detail_segments - 2), (0.08, 0.055, 0.035), 0.9, 0.0, MAT_GENERIC))
        centre = np.stack([x + side * rng.uniform(0.0, 0.3, n), _KH + trunk_h + 0.8 * r_y, z], 1)
        radii = np.stack([r_x, r_y, rng.uniform(1.8, 2.6, n)], 1)
        jitter = rng.uniform(-0.12, 0.12, (n, len(template.vertices)))
        green = np.stack([rng.uniform(0.04, 0.08, n), rng.uniform(0.09, 0.15, n), rng.uniform(0.025, 0.05, n)], 1)
        parts.append(_blobs(centre, radii, template, jitter, green))
    return parts, np.concatenate(trunks)


@dataclass
class Frontage:
    """What later parts need to know of the buildings' street fronts (m). doors: (N, 3) side (±1), z0, z1;
    shops: (M, 5) side, façade |x|, z0, z1 of the shop front, 1 if it has an awning else 0."""

    doors: np.ndarray
    shops: np.ndarray


def _buildings(rng: np.random.Generator, detail: float) -> tuple[list[np.ndarray], list[np.ndarray], Frontage]:
    """Blocks along both sides, lot by lot, leaving out the underpass and the fuel station."""
    walls_lo, walls_hi, walls_col, roofs_col = [], [], [], []
    slab_lo, slab_hi = [], []
    glass, lit, doors = [], [], []  # rows: (x, facing, y0, y1, z0, z1)
    awn_lo, awn_hi, awn_col = [], [], []
    door_rows, shop_rows = [], []
    for side in (-1.0, 1.0):
        zones = [(layout.BRIDGE_Z_M - _EMB_BASE_HALF_Z - 3.0, layout.BRIDGE_Z_M + _EMB_BASE_HALF_Z + 3.0)]
        if side > 0:
            zones.append((_STATION_Z[0] - 2.0, _STATION_Z[1] + 2.0))
        facing = -side
        z = 0.0
        while True:
            z += rng.choice([0.0, 0.0, 0.3, 1.5, 3.0])
            width = rng.uniform(9.0, 28.0)
            if z + width > _P - 0.5:
                width = _P - 0.5 - z
                if width < 7.0:
                    break
            hit = [b for a, b in zones if z + width > a and z < b]
            if hit:
                z = hit[0] + rng.uniform(0.0, 2.0)
                continue
            z0, z1 = z, z + width
            z = z1
            floors = int(rng.choice(np.arange(1, 8), p=[0.12, 0.16, 0.2, 0.18, 0.14, 0.1, 0.1]))
            height = 4.0 + 3.2 * (floors - 1) + 0.6
            d0 = layout.BUILDING_SETBACK_M + rng.choice([0.0, 0.0, 0.5, 1.5])
            d1 = d0 + rng.uniform(10.0, 22.0)
            x0, x1 = _span(side, d0, d1)
            walls_lo.append((x0, 0.0, z0))
            walls_hi.append((x1, height, z1))
            col = _WALL_PALETTE[rng.integers(len(_WALL_PALETTE))] * rng.uniform(0.85, 1.15, 3)
            walls_col.append(col)
            roofs_col.append(np.full(3, rng.uniform(0.08, 0.16)))
            if floors >= 3 and rng.random() < 0.6:  # plant rooms and stair houses break up the skyline
                for _ in range(rng.integers(1, 4)):
                    sx, sz, sy = rng.uniform(1.5, 4.0), rng.uniform(1.5, 4.0), rng.uniform(1.0, 2.8)
                    dc = rng.uniform(d0 + 2.0 + sx / 2, d1 - 1.0 - sx / 2)
                    zc = rng.uniform(z0 + 1.0 + sz / 2, z1 - 1.0 - sz / 2)
                    rx0, rx1 = _span(side, dc - sx / 2, dc + sx / 2)
                    slab_lo.append((rx0, height, zc - sz / 2))
                    slab_hi.append((rx1, height + sy, zc + sz / 2))
            if rng.random() < 0.3:  # cornice overhanging the façade
                cx0, cx1 = _span(side, d0 - 0.4, d1)
                slab_lo.append((cx0, height - 0.35, z0 - 0.2))
                slab_hi.append((cx1, height + 0.05, z1 + 0.2))
            xf = side * (d0 - 0.03)  # glass sits 3 cm proud of the wall
            # Upper floors: ribbon windows or punched windows.
            ribbon = rng.random() < 0.35 or detail < 0.5
            pitch = rng.choice([2.4, 3.0, 3.6])
            ratio = rng.uniform(0.45, 0.7)
            n_win = max(1, int((width - 2.0) // pitch))
            zc = (z0 + z1) / 2 + (np.arange(n_win) - (n_win - 1) / 2) * pitch
            p_lit = rng.uniform(0.02, 0.15)
            for f in range(1, floors):
                y0 = 4.0 + 3.2 * (f - 1) + 0.9
                y1 = y0 + (1.6 if ribbon else 1.5)
                if ribbon:
                    rows = [(xf, facing, y0, y1, z0 + 0.8, z1 - 0.8)]
                else:
                    rows = [(xf, facing, y0, y1, c - pitch * ratio / 2, c + pitch * ratio / 2) for c in zc]
                for r in rows:
                    (lit if rng.random() < p_lit else glass).append(r)
            # Ground floor: a shop front (sometimes under an awning) or windows and a door.
            door_z = rng.uniform(z0 + 1.0, z1 - 2.2)
            doors.append((xf, facing, 0.0, 2.2, door_z, door_z + 1.1))
            door_rows.append((side, door_z, door_z + 1.1))
            if rng.random() < 0.55:
                shop_rows.append([side, d0, z0 + 0.5, z1 - 0.5, 0.0])
                segs = [(z0 + 0.8, door_z - 0.3), (door_z + 1.4, z1 - 0.8)]
                for a, b in segs:
                    if b - a > 0.8:
                        (lit if rng.random() < 0.25 else glass).append((xf, facing, 0.5, 3.0, a, b))
                if rng.random() < 0.5:
                    ax0, ax1 = _span(side, d0 - 1.6, d0)
                    awn_lo.append((ax0, 3.1, z0 + 0.5))
                    awn_hi.append((ax1, 3.25, z1 - 0.5))
                    awn_col.append(_AWNING_PALETTE[rng.integers(len(_AWNING_PALETTE))])
                    shop_rows[-1][4] = 1.0
            else:
                for c in zc:
                    a, b = c - pitch * ratio / 2, c + pitch * ratio / 2
                    if b < door_z - 0.2 or a > door_z + 1.3:
                        glass.append((xf, facing, 1.0, 2.5, a, b))
    parts, occ = [], []
    lo, hi = np.array(walls_lo), np.array(walls_hi)
    cols, roof_cols = np.array(walls_col), np.array(roofs_col)
    parts.append(_boxes(lo, hi, cols, 0.85, 0.0, MAT_CONCRETE, faces=(NX_, PX_, NZ_, PZ_)))
    parts.append(_boxes(lo, hi, roof_cols, 0.9, 0.0, MAT_CONCRETE, faces=(PY_,)))
    occ.append(_box_tris(lo, hi))
    if slab_lo:
        parts.append(_boxes(np.array(slab_lo), np.array(slab_hi), (0.3, 0.3, 0.29), 0.8, 0.0, MAT_CONCRETE))
        occ.append(_box_tris(np.array(slab_lo), np.array(slab_hi)))
    if awn_lo:
        parts.append(_boxes(np.array(awn_lo), np.array(awn_hi), np.array(awn_col), 0.9, 0.0, MAT_GENERIC))
        occ.append(_box_tris(np.array(awn_lo), np.array(awn_hi)))
    for rows, alb, rough, mat in ((glass, _GLASS, 0.05, MAT_GLASS), (doors, (0.06, 0.04, 0.03), 0.6, MAT_GENERIC)):
        r = np.array(rows)
        parts.append(_facade_quads(r[:, 0], r[:, 1], r[:, 2], r[:, 3], r[:, 4], r[:, 5], alb, rough, mat))
    if lit:
        r = np.array(lit)
        lum = rng.uniform(30.0, 150.0, len(r))[:, None]
        tint = _WARM_WINDOW[None] * rng.uniform(0.9, 1.1, (len(r), 3))
        parts.append(_facade_quads(r[:, 0], r[:, 1], r[:, 2], r[:, 3], r[:, 4], r[:, 5],
                                   tint * lum / LUMINOUS_EFFICACY_LM_PER_W, 0.1, MAT_EMISSIVE))
    frontage = Frontage(np.array(door_rows, dtype=np.float64).reshape(-1, 3),
                        np.array(shop_rows, dtype=np.float64).reshape(-1, 5))
    return parts, occ, frontage

