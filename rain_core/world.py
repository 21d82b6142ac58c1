"""The procedural street: one periodic tile of road, kerbs, sidewalks, buildings, trees, lamps, a railway
underpass and a fuel station, plus the two maps the rain effects read (roof heights and the road heightmap).

Frame and units: +Y up, metres, the road along Z (see ``rain_core.layout``). The world repeats along Z with period
``PERIOD_M``; :func:`build_world` makes ONE tile covering z in [0, PERIOD_M) and the renderer draws it at
z offsets k·PERIOD_M. Objects never overlap their copies in the neighbouring tiles.

Emissive surfaces (``MAT_EMISSIVE``) store emitted radiance in W/sr/m² at 683 lm/W, i.e. luminance in cd/m²
divided by :data:`LUMINOUS_EFFICACY_LM_PER_W`. On that scale a white Lambertian surface in 100 klx sunlight is
about 47, a lamp lens is ~60, a lit window ~0.1. Lamp colours are linear RGB with Rec.709 luminance 1, so
``intensity_cd * color`` is the per-channel intensity.

The road heightmap convention: ``height01 = 0`` is the lowest point of the road surface (water collects there
first: cracks, then ruts and the gutter), ``1`` the highest (crown of dry asphalt). A water level ``f`` in [0, 1]
covers the texels with ``height01 < f``; the crack fill of DESIGN §3 reads ``min(flood_cracks, 1 - height01)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from rain_core import layout
from rain_core.mesh import (
    MAT_ASPHALT,
    MAT_CONCRETE,
    MAT_EMISSIVE,
    MAT_FOLIAGE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_PAINT,
    VERTEX_DTYPE,
    concat,
)

LUMINOUS_EFFICACY_LM_PER_W = 683.0  # lm/W: emissive albedo = luminance (cd/m²) / this
HEIGHTMAP_TEXEL_M = 0.05  # m per road heightmap texel (square texels)
HEIGHTMAP_EXTENT_M = (2.0 * layout.ROAD_HALF_WIDTH_M, 48.0)  # m (x, z); PERIOD_M is 25 × 48 m
OCCLUDER_CELL_M = 0.25  # m, fine top-down roof grid cell
OCCLUDER_HALF_X_M = 48.0  # m, the fine grid covers |x| < this (road, sidewalks, buildings)
OCCLUDER_COARSE_CELL_M = 2.0  # m, coarse grid beyond (the railway embankment out to the ground's edge)
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


@dataclass(eq=False)
class OccluderMap:
    """A top-down raster of the occluder mesh: for each cell the height (m) of the highest occluder surface at
    the cell centre, ``-inf`` where there is none. Rows follow z from 0 (cell j covers [j·cell, (j+1)·cell)),
    columns follow x from ``x0_m``; z wraps with ``PERIOD_M``."""

    grid: np.ndarray  # float32 (nz, nx), m
    x0_m: float
    cell_m: float

    def lookup(self, x, z) -> tuple[np.ndarray, np.ndarray]:
        """Nearest-cell heights (m) at x, z (m) and a mask of the points that lie inside the grid's x range."""
        nz, nx = self.grid.shape
        i = np.floor((np.asarray(x, dtype=np.float64) - self.x0_m) / self.cell_m).astype(np.int64)
        j = np.floor(np.mod(np.asarray(z, dtype=np.float64), _P) / self.cell_m).astype(np.int64) % nz
        i, j = np.broadcast_arrays(i, j)
        inside = (i >= 0) & (i < nx)
        h = self.grid[j, np.clip(i, 0, nx - 1)].astype(np.float64)
        return np.where(inside, h, -np.inf), inside


@dataclass(eq=False)
class World:
    """One tile of the street. See the module docstring for frames, units and conventions."""

    seed: int
    vertices: np.ndarray  # VERTEX_DTYPE triangles: all static lit geometry of the tile
    lamps: list[StreetLamp]
    occluders: trimesh.Trimesh  # roofs rain cannot pass: bridge deck + embankment, canopy, roofs, awnings, kiosk
    road_heightmap: np.ndarray  # float32 (H, W) in [0, 1]; rows along z, columns along x; 0 = lowest
    heightmap_extent_m: tuple[float, float]  # (size_x_m, size_z_m) of the whole heightmap
    occluder_map: OccluderMap  # 0.25 m cells over |x| < OCCLUDER_HALF_X_M
    occluder_map_coarse: OccluderMap  # 2 m cells over |x| < GROUND_HALF_X_M + margin

    def occluder_height(self, x, z) -> np.ndarray:
        """Height (m) at which a raindrop falling straight down at (x, z) (m) first meets a roof; ``-inf`` where
        it reaches the road or the ground. z is periodic. Resolution: 0.25 m cells (nearest cell centre) for
        |x| < 48 m, 2 m cells beyond; so roof edges are exact to half a cell."""
        fine, inside = self.occluder_map.lookup(x, z)
        coarse, _ = self.occluder_map_coarse.lookup(x, z)
        return np.where(inside, fine, coarse)

    def road_height01(self, x, z) -> np.ndarray:
        """Bilinear sample of ``road_heightmap`` at x, z (m), exactly as a GL texture with LINEAR filtering,
        CLAMP_TO_EDGE across x and REPEAT along z, sampled at u = (x + ROAD_HALF_WIDTH_M) / size_x,
        v = z / size_z, with the array uploaded row 0 first (row j ↔ v, column i ↔ u)."""
        return sample_heightmap(self.road_heightmap, self.heightmap_extent_m, x, z)


def sample_heightmap(hmap: np.ndarray, extent_m: tuple[float, float], x, z) -> np.ndarray:
    """Bilinear, GL-texture-compatible sample of a road heightmap (see :meth:`World.road_height01`); x, z in m."""
    nz, nx = hmap.shape
    fx = (np.asarray(x, dtype=np.float64) + extent_m[0] / 2) / extent_m[0] * nx - 0.5
    fz = np.asarray(z, dtype=np.float64) / extent_m[1] * nz - 0.5
    fx, fz = np.broadcast_arrays(fx, fz)
    i0 = np.floor(fx)
    j0 = np.floor(fz)
    tx = fx - i0
    tz = fz - j0
    i0 = i0.astype(np.int64)
    j0 = j0.astype(np.int64)
    ia = np.clip(i0, 0, nx - 1)
    ib = np.clip(i0 + 1, 0, nx - 1)
    ja = np.mod(j0, nz)
    jb = np.mod(j0 + 1, nz)
    h = hmap.astype(np.float64)
    top = h[ja, ia] * (1 - tx) + h[ja, ib] * tx
    bot = h[jb, ia] * (1 - tx) + h[jb, ib] * tx
    return top * (1 - tz) + bot * tz


# ----------------------------------------------------------------------------------------------------------------
# Road heightmap


def _periodic_noise(rng: np.random.Generator, shape, sigma_texels: float) -> np.ndarray:
    """Gaussian-filtered white noise, periodic on both axes (filtered in the Fourier domain), unit std."""
    white = rng.standard_normal(shape)
    kz = np.fft.fftfreq(shape[0])[:, None]
    kx = np.fft.rfftfreq(shape[1])[None, :]
    filt = np.exp(-2.0 * (np.pi * sigma_texels) ** 2 * (kz**2 + kx**2))
    out = np.fft.irfft2(np.fft.rfft2(white) * filt, s=shape)
    return out / (out.std() + 1e-12)


def _crack_mask(rng: np.random.Generator, nz: int, nx: int, dx: float) -> np.ndarray:
    """Thin random-walk cracks (1 texel core, soft shoulders), wrapping along z; float32 in [0, 1]."""
    n = 44
    kind = rng.choice(3, size=n, p=(0.5, 0.25, 0.25))  # 0 longitudinal in wheel paths, 1 transverse, 2 random
    lengths = np.where(kind == 0, rng.uniform(1.5, 6.0, n), np.where(kind == 1, rng.uniform(1.0, 4.0, n),
                                                                      rng.uniform(0.5, 2.5, n)))
    ruts = np.array([c + o for c in layout.LANE_CENTRES_X for o in (-0.9, 0.9)])
    x0 = np.where(kind == 0, rng.choice(ruts, n) + rng.normal(0, 0.12, n), rng.uniform(-_HW + 0.3, _HW - 0.3, n))
    z0 = rng.uniform(0, HEIGHTMAP_EXTENT_M[1], n)
    # Heading measured from +z towards +x.
    theta0 = np.where(kind == 0, rng.normal(0, 0.08, n) + np.pi * rng.integers(0, 2, n),
                      np.where(kind == 1, np.pi / 2 + rng.normal(0, 0.15, n), rng.uniform(0, 2 * np.pi, n)))
    wiggle = np.where(kind == 2, 0.1, 0.04)  # rad per step: random cracks meander, the others run straight
    step = dx * 0.5  # half a texel per step so the line has no gaps
    n_steps = int(np.ceil(lengths.max() / step))
    theta = theta0[:, None] + np.cumsum(rng.normal(0, 1, (n, n_steps)) * wiggle[:, None], axis=1)
    px = x0[:, None] + np.cumsum(np.sin(theta) * step, axis=1)
    pz = z0[:, None] + np.cumsum(np.cos(theta) * step, axis=1)
    alive = (np.arange(n_steps)[None, :] * step) < lengths[:, None]
    i = np.floor((px + _HW) / dx).astype(np.int64)
    j = np.floor(pz / dx).astype(np.int64) % nz
    ok = alive & (i >= 0) & (i < nx)
    core = np.zeros((nz, nx), dtype=np.float32)
    core[j[ok], i[ok]] = 1.0
    # Soft shoulders: half depth on the 4-neighbours (z wraps, x does not).
    side = np.maximum(np.roll(core, 1, axis=0), np.roll(core, -1, axis=0))
    side[:, 1:] = np.maximum(side[:, 1:], core[:, :-1])
    side[:, :-1] = np.maximum(side[:, :-1], core[:, 1:])
    return np.maximum(core, 0.45 * side)


def make_road_heightmap(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The road's relative height as a texture: (height01, crack_mask), both float32 (H, W) = (960, 280), rows
    along z (0.05 m texels over 48 m, seamless), columns along x over the road width (14 m). height01 = 0 is the
    lowest point. Components: crown (2 % cross slope to the kerb gutters), two rutted wheel tracks per lane at
    ±0.9 m from the lane centre (0.7 m wide), shallow depressions, fine aggregate noise, and cracks (crack_mask
    = 1 on a crack's centre line, ~0.45 on its shoulders). The amplitudes are chosen for how water should
    collect, not to metric scale: cracks < ruts and gutters < lane centres < crown."""
    dx = HEIGHTMAP_TEXEL_M
    nx = int(round(HEIGHTMAP_EXTENT_M[0] / dx))
    nz = int(round(HEIGHTMAP_EXTENT_M[1] / dx))
    x = -_HW + (np.arange(nx) + 0.5) * dx
    z = (np.arange(nz) + 0.5) * dx
    ax = np.abs(x)[None, :]
    crown = -0.30 * ax / _HW
    gutter = -0.10 * np.clip(1.0 - (_HW - ax) / 0.4, 0.0, 1.0) ** 2
    # Ruts: raised-cosine grooves whose depth and lateral position wander slowly (whole cycles per tile).
    ruts = np.zeros((nz, nx))
    depth_noise = _periodic_noise(rng, (nz, 8), sigma_texels=60.0)
    for k, c in enumerate(layout.LANE_CENTRES_X):
        for m, off in enumerate((-0.9, 0.9)):
            cycles = rng.integers(1, 4)
            wander = 0.06 * np.sin(2 * np.pi * cycles * z / HEIGHTMAP_EXTENT_M[1] + rng.uniform(0, 2 * np.pi))
            d = (x[None, :] - (c + off) - wander[:, None]) / 0.35
            groove = np.where(np.abs(d) < 1.0, 0.5 * (1.0 + np.cos(np.pi * d)), 0.0)
            depth = 0.26 * (1.0 + 0.3 * depth_noise[:, (2 * k + m) % 8])
            ruts += groove * depth[:, None]
    low = 0.07 * _periodic_noise(rng, (nz, nx), sigma_texels=25.0)
    fine = 0.025 * _periodic_noise(rng, (nz, nx), sigma_texels=0.8)
    h = 0.9 + crown + gutter - ruts + low + fine
    cracks = _crack_mask(rng, nz, nx, dx)
    h = h - cracks * (0.55 + 0.25 * np.clip(h, 0.0, 1.0))
    h = (h - h.min()) / (h.max() - h.min())
    return h.astype(np.float32), cracks


# ----------------------------------------------------------------------------------------------------------------
# Mesh primitives (vectorised over instances; all emit VERTEX_DTYPE triangle lists)

NX_, PX_, NY_, PY_, NZ_, PZ_ = range(6)  # box face indices: -x, +x, -y, +y, -z, +z
_ALL_FACES = (0, 1, 2, 3, 4, 5)


def _box_template() -> tuple[np.ndarray, np.ndarray]:
    tris, normals = [], []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, 1):
            quad = np.zeros((4, 3))
            quad[:, axis] = side
            quad[:, u] = (0, 1, 1, 0)
            quad[:, v] = (0, 0, 1, 1)
            if side == 0:  # e_u × e_v = +e_axis; reverse the winding for the −axis face
                quad = quad[::-1]
            tris.append(quad[[0, 1, 2, 0, 2, 3]])
            n = np.zeros(3)
            n[axis] = 1.0 if side else -1.0
            normals.append(n)
    return np.array(tris), np.array(normals)


_BOX_TRIS, _BOX_NORMALS = _box_template()


def _pack(pos: np.ndarray, nrm: np.ndarray, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """pos, nrm: (N, k, 3) for N instances of k vertices; albedo (3,) or (N, 3); rough/metal scalar or (N,)."""
    n_inst, k = pos.shape[:2]
    out = np.empty(n_inst * k, dtype=VERTEX_DTYPE)
    out["position"] = pos.reshape(-1, 3)
    out["normal"] = np.broadcast_to(nrm, pos.shape).reshape(-1, 3)
    alb = np.asarray(albedo, dtype=np.float32)
    out["albedo"] = np.repeat(alb, k, axis=0) if alb.ndim == 2 else alb
    params = np.empty((n_inst, 3), dtype=np.float32)
    params[:, 0] = rough
    params[:, 1] = metal
    params[:, 2] = float(mat)
    out["params"] = np.repeat(params, k, axis=0)
    return out


def _box_positions(lo, hi, faces=_ALL_FACES) -> tuple[np.ndarray, np.ndarray]:
    lo = np.atleast_2d(np.asarray(lo, dtype=np.float64))
    hi = np.atleast_2d(np.asarray(hi, dtype=np.float64))
    faces = list(faces)
    t = _BOX_TRIS[faces].reshape(-1, 3)
    pos = lo[:, None, :] + t[None] * (hi - lo)[:, None, :]
    nrm = np.repeat(_BOX_NORMALS[faces], 6, axis=0)[None]
    return pos, nrm


def _boxes(lo, hi, albedo, rough=0.8, metal=0.0, mat=MAT_CONCRETE, faces=_ALL_FACES) -> np.ndarray:
    """Axis-aligned boxes from corners lo, hi (N, 3) m; faces picks which sides to emit."""
    pos, nrm = _box_positions(lo, hi, faces)
    return _pack(pos, nrm, albedo, rough, metal, mat)


def _box_tris(lo, hi) -> np.ndarray:
    """Closed boxes as a triangle soup (N·12, 3, 3) for the occluder mesh."""
    pos, _ = _box_positions(lo, hi)
    return pos.reshape(-1, 3, 3)


def _quads(p0, u, v, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """Parallelograms p0, p0+u, p0+u+v, p0+v (N, 3) m, facing u × v."""
    p0, u, v = (np.atleast_2d(np.asarray(a, dtype=np.float64)) for a in (p0, u, v))
    p0, u, v = np.broadcast_arrays(p0, u, v)
    pos = np.stack([p0, p0 + u, p0 + u + v, p0, p0 + u + v, p0 + v], axis=1)
    n = np.cross(u, v)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return _pack(pos, n[:, None, :], albedo, rough, metal, mat)


def _rects_up(x0, x1, z0, z1, y, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Up-facing horizontal rectangles [x0, x1] × [z0, z1] at height y (m), arrays of N."""
    x0, x1, z0, z1, y = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                              for a in (x0, x1, z0, z1, y)))
    zeros = np.zeros_like(x0)
    p0 = np.stack([x0, y, z0], axis=1)
    u = np.stack([zeros, zeros, z1 - z0], axis=1)
    v = np.stack([x1 - x0, zeros, zeros], axis=1)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _rects_down(x0, x1, z0, z1, y, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Down-facing horizontal rectangles (lamp lenses, canopy lights), arrays of N, m."""
    x0, x1, z0, z1, y = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                              for a in (x0, x1, z0, z1, y)))
    zeros = np.zeros_like(x0)
    p0 = np.stack([x0, y, z0], axis=1)
    u = np.stack([x1 - x0, zeros, zeros], axis=1)
    v = np.stack([zeros, zeros, z1 - z0], axis=1)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _facade_quads(x, facing, y0, y1, z0, z1, albedo, rough=0.8, mat=MAT_GENERIC) -> np.ndarray:
    """Vertical rectangles in the plane x = const (m) facing ``facing`` = ±1 along x; arrays of N."""
    x, facing, y0, y1, z0, z1 = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=np.float64))
                                                      for a in (x, facing, y0, y1, z0, z1)))
    zeros = np.zeros_like(x)
    p0 = np.stack([x, y0, z0], axis=1)
    along_z = np.stack([zeros, zeros, z1 - z0], axis=1)
    along_y = np.stack([zeros, y1 - y0, zeros], axis=1)
    pos_face = (facing > 0)[:, None]  # +x: e_y × e_z; −x: e_z × e_y
    u = np.where(pos_face, along_y, along_z)
    v = np.where(pos_face, along_z, along_y)
    return _quads(p0, u, v, albedo, rough, 0.0, mat)


def _cylinders(base, radius, height, segments: int, albedo, rough=0.8, metal=0.0, mat=MAT_GENERIC) -> np.ndarray:
    """Vertical capped cylinders (smooth sides) standing on base (N, 3) m; radius, height (N,) m."""
    base = np.atleast_2d(np.asarray(base, dtype=np.float64))
    n = len(base)
    radius = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
    height = np.broadcast_to(np.asarray(height, dtype=np.float64), (n,))
    th = 2 * np.pi * np.arange(segments) / segments
    ring = np.stack([np.cos(th), np.zeros(segments), np.sin(th)], axis=1)
    nxt = np.roll(ring, -1, axis=0)
    zero = np.zeros_like(ring)
    up_n = np.tile((0.0, 1.0, 0.0), (segments, 1))
    # Side: b_k, t_k, t_k1, b_k, t_k1, b_k1 (outward); cap: c, t_k1, t_k (up).
    radial = np.stack([ring, ring, nxt, ring, nxt, nxt, zero, nxt, ring], axis=1).reshape(-1, 3)
    up = np.tile(np.array([0, 1, 1, 0, 1, 0, 1, 1, 1], dtype=np.float64), segments)
    normals = np.stack([ring, ring, nxt, ring, nxt, nxt, up_n, up_n, up_n], axis=1).reshape(-1, 3)
    pos = (base[:, None, :] + radial[None] * radius[:, None, None]
           + (up[None, :, None] * height[:, None, None]) * np.array([0.0, 1.0, 0.0]))
    return _pack(pos, normals[None], albedo, rough, metal, mat)


def _blobs(centre, radii, template: trimesh.Trimesh, jitter: np.ndarray, albedo, rough=0.9,
           mat=MAT_FOLIAGE) -> np.ndarray:
    """Lumpy ellipsoids: the unit template scaled by radii (N, 3) m with per-vertex radial jitter (N, nv)."""
    verts = np.asarray(template.vertices)
    faces = np.asarray(template.faces)
    pts = centre[:, None, :] + verts[None] * radii[:, None, :] * (1.0 + jitter[:, :, None])
    tri = pts[:, faces]  # (N, nf, 3, 3)
    fn = np.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0])
    incidence = np.zeros((len(verts), len(faces)))
    incidence[faces.ravel(), np.repeat(np.arange(len(faces)), 3)] = 1.0
    vn = np.einsum("vf,nfc->nvc", incidence, fn)
    vn /= np.linalg.norm(vn, axis=2, keepdims=True)
    return _pack(tri.reshape(len(centre), -1, 3), vn[:, faces].reshape(len(centre), -1, 3), albedo, rough, 0.0,
                 mat)


def _span(side: float, d0, d1) -> tuple[np.ndarray, np.ndarray]:
    """x interval (lo, hi) for the distances d0..d1 from the centre line on side ±1."""
    a = side * np.asarray(d0, dtype=np.float64)
    b = side * np.asarray(d1, dtype=np.float64)
    return np.minimum(a, b), np.maximum(a, b)


def _in_zones(z0, z1, zones) -> np.ndarray:
    z0 = np.asarray(z0, dtype=np.float64)
    z1 = np.asarray(z1, dtype=np.float64)
    hit = np.zeros(np.broadcast(z0, z1).shape, dtype=bool)
    for a, b in zones:
        hit |= (z1 > a) & (z0 < b)
    return hit


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
    px = np.array([_KERB_OUT + 1.5, 14.6])
    pz = np.array([_CAN_Z0 + 4.0, _CAN_Z1 - 4.0])
    gx, gz = (a.ravel() for a in np.meshgrid(px, pz))
    base_y = np.where(gx < _WALK_OUT, _KH, _KH + 0.15)
    parts.append(_boxes(np.stack([gx - 0.25, base_y, gz - 0.25], 1), np.stack([gx + 0.25, np.full(4, _CAN_Y0),
                                                                               gz + 0.25], 1),
                        (0.6, 0.6, 0.6), 0.5, 0.3, MAT_METAL, faces=(NX_, PX_, NZ_, PZ_)))
    # Pump islands (raised concrete) with pumps between the pillars.
    parts.append(_boxes((14.0, 0.0, _CAN_Z0 + 2.0), (15.2, _KH + 0.15, _CAN_Z1 - 2.0), (0.5, 0.5, 0.48), 0.7,
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
    kx0, kx1, kz0, kz1 = 22.0, 30.0, layout.CANOPY_Z_M + 14.0, layout.CANOPY_Z_M + 32.0
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


def _trees(rng: np.random.Generator, detail_segments: int, subdiv: int) -> list[np.ndarray]:
    parts = []
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
        parts.append(_cylinders(np.stack([x, np.full(n, _KH), z], 1), rng.uniform(0.12, 0.18, n), trunk_h + r_y,
                                max(4, detail_segments - 2), (0.08, 0.055, 0.035), 0.9, 0.0, MAT_GENERIC))
        centre = np.stack([x + side * rng.uniform(0.0, 0.3, n), _KH + trunk_h + 0.8 * r_y, z], 1)
        radii = np.stack([r_x, r_y, rng.uniform(1.8, 2.6, n)], 1)
        jitter = rng.uniform(-0.12, 0.12, (n, len(template.vertices)))
        green = np.stack([rng.uniform(0.04, 0.08, n), rng.uniform(0.09, 0.15, n), rng.uniform(0.025, 0.05, n)], 1)
        parts.append(_blobs(centre, radii, template, jitter, green))
    return parts


def _buildings(rng: np.random.Generator, detail: float) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Blocks along both sides, lot by lot, leaving out the underpass and the fuel station."""
    walls_lo, walls_hi, walls_col, roofs_col = [], [], [], []
    slab_lo, slab_hi = [], []
    glass, lit, doors = [], [], []  # rows: (x, facing, y0, y1, z0, z1)
    awn_lo, awn_hi, awn_col = [], [], []
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
            if rng.random() < 0.55:
                segs = [(z0 + 0.8, door_z - 0.3), (door_z + 1.4, z1 - 0.8)]
                for a, b in segs:
                    if b - a > 0.8:
                        (lit if rng.random() < 0.25 else glass).append((xf, facing, 0.5, 3.0, a, b))
                if rng.random() < 0.5:
                    ax0, ax1 = _span(side, d0 - 1.6, d0)
                    awn_lo.append((ax0, 3.1, z0 + 0.5))
                    awn_hi.append((ax1, 3.25, z1 - 0.5))
                    awn_col.append(_AWNING_PALETTE[rng.integers(len(_AWNING_PALETTE))])
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
    return parts, occ


# ----------------------------------------------------------------------------------------------------------------
# Occluder rasterisation


def _rasterise_top(tris: np.ndarray, x0: float, cell: float, nx: int) -> np.ndarray:
    """Max-height raster (m) of a triangle soup (T, 3, 3) on cells of ``cell`` m: rows z in [0, PERIOD_M) (the
    soup wraps), columns x from x0. A cell takes a triangle if its centre lies inside the triangle's xz shadow."""
    nz = int(round(_P / cell))
    grid = np.full((nz, nx), -np.inf, dtype=np.float32)
    a = tris[:, 1] - tris[:, 0]
    b = tris[:, 2] - tris[:, 0]
    tris = tris[np.abs(a[:, 0] * b[:, 2] - a[:, 2] * b[:, 0]) > 1e-9]  # vertical faces cast no shadow
    zmin, zmax = tris[:, :, 2].min(1), tris[:, :, 2].max(1)
    shift = np.array([0.0, 0.0, _P])
    tris = np.concatenate([tris, tris[zmin < 0] + shift, tris[zmax > _P] - shift])
    lo = np.floor((tris[:, :, [0, 2]].min(1) - (x0, 0.0)) / cell - 0.5).astype(np.int64) + 1
    hi = np.floor((tris[:, :, [0, 2]].max(1) - (x0, 0.0)) / cell - 0.5).astype(np.int64)
    lo = np.maximum(lo, 0)
    hi = np.minimum(hi, (nx - 1, nz - 1))
    eps = 1e-7
    for t in np.nonzero((lo <= hi).all(1))[0]:
        (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = tris[t]
        i0, j0 = lo[t]
        i1, j1 = hi[t]
        cx = x0 + (np.arange(i0, i1 + 1) + 0.5) * cell
        cz = ((np.arange(j0, j1 + 1) + 0.5) * cell)[:, None]
        det = (z2 - z3) * (x1 - x3) + (x3 - x2) * (z1 - z3)
        l1 = ((z2 - z3) * (cx - x3) + (x3 - x2) * (cz - z3)) / det
        l2 = ((z3 - z1) * (cx - x3) + (x1 - x3) * (cz - z3)) / det
        l3 = 1.0 - l1 - l2
        inside = (l1 >= -eps) & (l2 >= -eps) & (l3 >= -eps)
        if not inside.any():
            continue
        y = l1 * y1 + l2 * y2 + l3 * y3
        sub = grid[j0:j1 + 1, i0:i1 + 1]
        np.maximum(sub, np.where(inside, y, -np.inf), out=sub)
    return grid


# ----------------------------------------------------------------------------------------------------------------


def build_world(seed: int = 1, detail: float = 1.0) -> World:
    """Build one tile (z in [0, PERIOD_M) m) of the street, deterministically for ``seed``.

    detail in [0.25, 4] scales tessellation: cylinder segments (8 at 1), foliage sphere subdivisions (1 at 1,
    2 from 2), window granularity (ribbons only below 0.5). The road heightmap does not depend on detail.
    """
    if not (0.25 <= detail <= 4.0):
        raise ValueError(f"detail must be in [0.25, 4], got {detail}")
    rng = np.random.default_rng(seed)
    # Independent streams per part, so changing one part's draws does not reshuffle the others.
    r_road, r_hmap, r_build, r_trees = (np.random.default_rng(s) for s in rng.bit_generator.seed_seq.spawn(4))
    segments = max(4, int(round(8 * detail)))
    subdiv = 0 if detail < 0.5 else (1 if detail < 2.0 else 2)

    parts = _road_and_streetside(r_road)
    occ = []
    p, o, bridge_lamps = _bridge()
    parts += p
    occ += o
    p, o, station_lamps = _station()
    parts += p
    occ += o
    p, lamps = _street_lamps(segments)
    parts += p
    parts += _trees(r_trees, segments, subdiv)
    p, o = _buildings(r_build, detail)
    parts += p
    occ += o
    vertices = concat(parts)

    occ_tris = np.concatenate(occ)
    occluders = trimesh.Trimesh(vertices=occ_tris.reshape(-1, 3), faces=np.arange(3 * len(occ_tris)).reshape(-1, 3),
                                process=False)
    fine_nx = int(round(2 * OCCLUDER_HALF_X_M / OCCLUDER_CELL_M))
    fine = OccluderMap(_rasterise_top(occ_tris, -OCCLUDER_HALF_X_M, OCCLUDER_CELL_M, fine_nx), -OCCLUDER_HALF_X_M,
                       OCCLUDER_CELL_M)
    half = GROUND_HALF_X_M + 8.0
    coarse_nx = int(round(2 * half / OCCLUDER_COARSE_CELL_M))
    coarse = OccluderMap(_rasterise_top(occ_tris, -half, OCCLUDER_COARSE_CELL_M, coarse_nx), -half,
                         OCCLUDER_COARSE_CELL_M)

    hmap, _ = make_road_heightmap(r_hmap)
    return World(seed=seed, vertices=vertices, lamps=lamps + bridge_lamps + station_lamps, occluders=occluders,
                 road_heightmap=hmap, heightmap_extent_m=HEIGHTMAP_EXTENT_M, occluder_map=fine,
                 occluder_map_coarse=coarse)
