"""Water on the road (DESIGN §3 "Wet road"): standing water in cracks and puddles and the thin wet film.

The one model of the water the road holds, shared by the road effect (which draws it), the spray (what the
wheels throw) and the ripples (where drops land in water). NumPy float64, the reference; the GLSL twin is
``shaders/road/film.glsl`` (tests/effects/road/test_film.py checks the constants and the values agree).
GL-free: it imports no ``moderngl``.

Standing water comes from the road heightmap h (0 lowest: cracks ≈ 0–0.35, ruts ≈ 0.5–0.65, lane centres
0.7–0.85), the same map smoothed over PUDDLE_GROUND_SIGMA_M (h_s, without the cracks), and a seeded noise map
n ∈ [0, 1] (uniform; periodic in 1200 m so it never tiles visibly). Cracks hold
``CRACK_MAX_MM · clamp((cracks · CRACK_LEVEL − h) / CRACK_DEPTH_SPAN, 0, 1)`` mm (they fill and dry with the fast
level). Puddles lie where the blended ground ``g = (1 − K)·h_s + K·n`` is below the slow level
``L = PUDDLE_LEVEL_MAX · (puddles · puddle_amount)^PUDDLE_LEVEL_EXPONENT`` and hold
``PUDDLE_MAX_MM · clamp((L − g) / PUDDLE_DEPTH_SPAN, 0, 1)`` mm: they follow the ruts and low spots, and the noise
decides which stretch of rut floods. The wet film itself is ``WET_FILM_MM · wetness`` mm. No water off the
asphalt (|x| > 7 m) nor under roofs higher than SHELTER_MIN_HEIGHT_M (the bridge deck, the fuel-station canopy).

Frames: x across the road (m), z along it (m, any world z: every map here is periodic in ``layout.PERIOD_M``, so
world z and the renderer's wrapped z give the same values).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from rain_core import checks, jit, layout
from rain_core.gutter import gutter_depth_mm, upstream_length_m
from rain_core.world import HEIGHTMAP_TEXEL_M, sample_heightmap

# shaders/road/film.glsl holds the same numbers.
WET_FILM_MM = 0.2  # mm, water film on a fully wet road (between the macrotexture peaks)
CRACK_MAX_MM = 3.0  # mm, deepest water in a crack
CRACK_LEVEL = 0.42  # height01 reached by the crack level at cracks = 1 (just above the cracks, below the ruts)
CRACK_DEPTH_SPAN = 0.2  # height01 below the crack level where a crack holds CRACK_MAX_MM
PUDDLE_MAX_MM = 10.0  # mm, puddles are shallow (DESIGN §3)
PUDDLE_NOISE_WEIGHT = 0.45  # K: share of the noise map in the puddle ground g = (1 − K)·h + K·n
PUDDLE_LEVEL_MAX = 0.56  # the puddle level at puddles = puddle_amount = 1 (about half the road under water)
PUDDLE_LEVEL_EXPONENT = 0.25  # level = MAX·(puddles·amount)^this: the low ground is a thin tail, so a
#                               linear level would flood almost nothing until the end, then everything
PUDDLE_DEPTH_SPAN = 0.35  # ground units below the level where a puddle is PUDDLE_MAX_MM deep
PUDDLE_GROUND_SIGMA_M = 0.15  # m: puddles see the road's shape, not its cracks (the crack level fills those)
ROAD_HALF_WIDTH_M = layout.ROAD_HALF_WIDTH_M
PUDDLE_MAP_CELL_M = 0.25  # m, noise and shelter map texels (x over the road width, z over a period)
SHELTER_MIN_HEIGHT_M = 0.5  # m, a roof higher than this above the road keeps the rain off it


# --- maps ------------------------------------------------------------------------------------------------

def _road_map_shape() -> tuple[int, int]:
    """(rows along z over a period, columns across the road) of the puddle-map grid."""
    return (int(round(layout.PERIOD_M / PUDDLE_MAP_CELL_M)), int(round(2 * ROAD_HALF_WIDTH_M / PUDDLE_MAP_CELL_M)))


def _periodic_smooth_noise(rng: np.random.Generator, shape, sigma_cells: float) -> np.ndarray:
    """Gaussian-filtered white noise, periodic on both axes (Fourier filter), zero mean, unit std."""
    white = rng.standard_normal(shape)
    kz = np.fft.fftfreq(shape[0])[:, None]
    kx = np.fft.rfftfreq(shape[1])[None, :]
    out = np.fft.irfft2(np.fft.rfft2(white) * np.exp(-2.0 * (np.pi * sigma_cells) ** 2 * (kz**2 + kx**2)), s=shape)
    out -= out.mean()
    return out / (out.std() + 1e-12)


@lru_cache(maxsize=8)
def puddle_noise(seed: int = 0) -> np.ndarray:
    """The seeded puddle noise map, float32 (rows along z over PERIOD_M, columns across the road), values
    uniformly distributed in (0, 1) (a rank transform of smooth Gaussian noise: puddle_amount then maps to
    coverage predictably). Blobs of a few metres with a finer octave for ragged outlines."""
    nz, nx = _road_map_shape()
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x70AD]))
    field = _periodic_smooth_noise(rng, (nz, nx), 6.0) + 0.35 * _periodic_smooth_noise(rng, (nz, nx), 1.5)
    ranks = np.empty(field.size)
    ranks[np.argsort(field, axis=None, kind="stable")] = (np.arange(field.size) + 0.5) / field.size
    return ranks.reshape(nz, nx).astype(np.float32)


def shelter_map(world) -> np.ndarray:
    """Where roofs keep the rain off the road, float32 in [0, 1] on the puddle-map grid (1 = fully under a
    roof higher than SHELTER_MIN_HEIGHT_M; edges softened over ~0.5 m as blown rain reaches a little under)."""
    nz, nx = _road_map_shape()
    occ = getattr(world, "occluder_map", None)
    if occ is None:
        return np.zeros((nz, nx), dtype=np.float32)
    x = -ROAD_HALF_WIDTH_M + (np.arange(nx) + 0.5) * PUDDLE_MAP_CELL_M
    z = (np.arange(nz) + 0.5) * PUDDLE_MAP_CELL_M
    heights = np.asarray(world.occluder_height(x[None, :], z[:, None]), dtype=np.float64)
    roof = (np.isfinite(heights) & (heights > SHELTER_MIN_HEIGHT_M)).astype(np.float64)
    for _ in range(2):  # [1 2 1]/4 twice along both axes (z wraps, x clamps)
        roof = 0.25 * np.roll(roof, 1, axis=0) + 0.5 * roof + 0.25 * np.roll(roof, -1, axis=0)
        padded = np.pad(roof, ((0, 0), (1, 1)), mode="edge")
        roof = 0.25 * padded[:, :-2] + 0.5 * padded[:, 1:-1] + 0.25 * padded[:, 2:]
    return roof.astype(np.float32)


def sample_road_map(grid, x, z):
    """Bilinear sample of a puddle-map grid (rows z over PERIOD_M, columns x over the road) at x, z (m),
    exactly as a GL LINEAR texture clamped across x and repeated along z (u = (x + 7)/14, v = z/PERIOD_M).
    A tuple of grids gives a tuple of samples (one set of indices, as ``sample_heightmap``)."""
    return sample_heightmap(grid, (2 * ROAD_HALF_WIDTH_M, layout.PERIOD_M), x, z)


def smooth_heightmap(hmap: np.ndarray, sigma_m: float = PUDDLE_GROUND_SIGMA_M) -> np.ndarray:
    """The road heightmap blurred by a Gaussian of sigma_m (m): wraps along z, clamps across x (like its
    texture). The puddles' ground: a 5 cm crack does not cut a puddle's soft margin into a hard edge."""
    sigma = sigma_m / HEIGHTMAP_TEXEL_M
    radius = int(math.ceil(3 * sigma))
    k = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    k /= k.sum()
    h = np.asarray(hmap, dtype=np.float64)
    out = sum(w * np.roll(h, s, axis=0) for s, w in zip(range(-radius, radius + 1), k, strict=True))
    padded = np.pad(out, ((0, 0), (radius, radius)), mode="edge")
    out = sum(w * padded[:, i:i + h.shape[1]] for i, w in enumerate(k))
    return out.astype(np.float32)


@lru_cache(maxsize=4)
def smooth_heightmap_for(world) -> np.ndarray:
    """:func:`smooth_heightmap` of ``world.road_heightmap``, cached per world."""
    return smooth_heightmap(world.road_heightmap)


@lru_cache(maxsize=4)
def shelter_map_for(world) -> np.ndarray:
    """:func:`shelter_map` of ``world``, cached per world."""
    return shelter_map(world)


def default_world():
    """The default street, ``shared_world(seed=1)`` (what the film functions use when given no world)."""
    from rain_core.world import shared_world

    return shared_world(seed=1)


# --- standing water and film (NumPy twin of shaders/road/film.glsl) ----------------------------------------

def crack_level(cracks: float) -> float:
    """The crack flood level in height01 units (what the shader's u_road_levels.y holds)."""
    return float(cracks) * CRACK_LEVEL


def puddle_level(puddles: float, puddle_amount: float) -> float:
    """The puddle water level in ground units (u_road_levels.z): PUDDLE_LEVEL_MAX·(puddles·amount)^exponent."""
    return PUDDLE_LEVEL_MAX * (float(puddles) * float(puddle_amount)) ** PUDDLE_LEVEL_EXPONENT


def _standing_water_mm(h, h_smooth, n, shelter, cracks, puddles, puddle_amount):
    crack = CRACK_MAX_MM * np.clip((cracks * CRACK_LEVEL - h) / CRACK_DEPTH_SPAN, 0.0, 1.0)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * h_smooth + PUDDLE_NOISE_WEIGHT * n
    level = PUDDLE_LEVEL_MAX * (puddles * puddle_amount) ** PUDDLE_LEVEL_EXPONENT
    puddle = PUDDLE_MAX_MM * np.clip((level - ground) / PUDDLE_DEPTH_SPAN, 0.0, 1.0)
    return np.maximum(crack, puddle) * (1.0 - shelter)


def _pack(maps: tuple) -> np.ndarray:
    """Maps on one (nz, nx) grid packed for one-gather bilinear sampling: row j·(nx + 1) + c holds, for the cell
    whose lower-left texel column is i = c − 1 (−1 … nx − 1) and row j, the four texels a GL LINEAR, clamp-x,
    repeat-z sample reads — (j, i), (j, i + 1), (j + 1, i), (j + 1, i + 1), columns clamped, rows wrapped — of
    every map in turn: (nz·(nx + 1), 4·len(maps)) float32, the maps' own values."""
    nz, nx = maps[0].shape
    out = np.empty((nz, nx + 1, 4 * len(maps)), dtype=np.float32)
    for k, m in enumerate(maps):
        m = np.asarray(m, dtype=np.float32)
        # Columns i (clamped: cell −1 reads column 0) and i + 1 (clamped: cell nx − 1 reads column nx − 1).
        left = np.concatenate([m[:, :1], m], axis=1)
        right = np.concatenate([m, m[:, -1:]], axis=1)
        for q, tap in enumerate((left, right, np.roll(left, -1, axis=0), np.roll(right, -1, axis=0))):
            out[:, :, 4 * k + q] = tap
    return out.reshape(nz * (nx + 1), 4 * len(maps))


class _PackedGrids:
    """The four maps of the water model — road heightmap and its smoothed twin (heightmap grid), puddle noise and
    shelter (puddle-map grid) — packed (``_pack``) into one table, with each grid's constants as (2, 1) columns,
    so both grids' samples take one pass of NumPy calls and one gather."""

    def __init__(self, seed: int, world):
        grids = ((world.road_heightmap, smooth_heightmap_for(world)), (puddle_noise(seed), shelter_map_for(world)))
        tables = [_pack(g) for g in grids]
        extents = (tuple(world.heightmap_extent_m), (2 * ROAD_HALF_WIDTH_M, layout.PERIOD_M))
        shapes = [g[0].shape for g in grids]
        col = lambda values: np.array(values, dtype=np.float64)[:, None]  # noqa: E731
        # sample_heightmap's scalars, as arrays: the same IEEE operations element by element.
        self.half_x = col([e[0] / 2 for e in extents])
        self.ext_x = col([e[0] for e in extents])
        self.ext_z = col([e[1] for e in extents])
        self.nx = col([s[1] for s in shapes])
        self.nz = col([s[0] for s in shapes])
        self.top_col = col([s[1] - 1 for s in shapes])
        self.nz_int = self.nz.astype(np.int64)
        self.row_len_int = col([s[1] + 1 for s in shapes]).astype(np.int64)
        # Row of cell (i = −1, j = 0) of each grid in the one table.
        self.offset = col([1.0, 1.0 + len(tables[0])])
        self.table = np.concatenate(tables)
        # The same constants for the compiled sampler (_sample_kernel): one row per grid.
        self.kernel_constants = np.ascontiguousarray(np.concatenate(
            [self.half_x, self.ext_x, self.ext_z, self.nx, self.nz, self.top_col, self.offset], axis=1))
        self.kernel_ints = np.ascontiguousarray(np.concatenate([self.nz_int, self.row_len_int], axis=1))
        self._kernel_scratch = (np.zeros(0), np.empty((2, 0), np.int64))
        self._maps = (*grids[0], grids[1][0], extents[0])  # for dry_floors, built on first use
        self._floors = None

    def sample(self, x, z):
        """(2, 2, k): [grid][map] bilinear samples at x, z (float64 (k,) m), each bit for bit what
        ``sample_heightmap`` gives for that map alone."""
        fx = (x + self.half_x) / self.ext_x * self.nx - 0.5
        fz = z / self.ext_z * self.nz - 0.5
        i0 = np.floor(fx)
        j0 = np.floor(fz)
        tx = fx - i0
        tz = fz - j0
        # Clamping the column to −1 … nx − 1 picks the texels sample_heightmap's clamped taps pick (small integers:
        # exact in float64); the row wraps as there, in int64 (a float64 np.mod costs several times more).
        column = (np.minimum(np.maximum(i0, -1.0), self.top_col) + self.offset).astype(np.int64)
        cell = j0.astype(np.int64) % self.nz_int * self.row_len_int + column
        texels = self.table.take(cell, axis=0)  # (2, k, 8): 4 taps of 2 maps
        # As float64 (exact), tap-major and contiguous: the products below then run on plain rows (float32 rows
        # 32 bytes apart made NumPy buffer and cast every operand).
        texels = texels.transpose(0, 2, 1).astype(np.float64, order="C").reshape(2, 2, 4, -1)  # (grid, map, tap, k)
        ux, uz = 1 - tx, 1 - tz
        ux, tx, uz, tz = ux[:, None], tx[:, None], uz[:, None], tz[:, None]
        top = texels[:, :, 0] * ux + texels[:, :, 1] * tx
        bot = texels[:, :, 2] * ux + texels[:, :, 3] * tx
        return top * uz + bot * tz

    def kernel_scratch(self, size: int) -> tuple[np.ndarray, np.ndarray]:
        """(float64 (≥ size,), int64 (2, ≥ size)) scratch of the compiled sampler, grown by doubling and kept (the
        ripples ask for strips of ~10⁴ points every frame: no fresh pages each time)."""
        if self._kernel_scratch[0].size < size:
            size = max(size, 2 * self._kernel_scratch[0].size)
            self._kernel_scratch = (np.zeros(size), np.empty((2, size), np.int64))
        return self._kernel_scratch

    def dry_floors(self) -> np.ndarray | None:
        """(2, nz·nx) float64 on the puddle-map grid (row-major, cell (j, i) covers z ∈ [j, j + 1)·cell,
        x + ROAD_HALF_WIDTH_M ∈ [i, i + 1)·cell): lower bounds of the sampled height h and of the puddle ground g
        at every point of each cell (see ``_standing_where_wet``). Built on first use; None when the heightmap's
        texels do not tile the puddle-map cells (then nothing is ruled out)."""
        if self._floors is None:
            self._floors = _dry_floors(self._maps) if self._maps is not None else False
            self._maps = None
        return self._floors if self._floors is not False else None


# Lower bounds of the dry-cell table sit this far (height01 and ground units, both O(1)) below the texels' minima:
# a bilinear sample is never below its taps' minimum by more than a few ulps (~1e-15).
DRY_FLOOR_MARGIN = 1e-9
# The dry-cell test trusts its cell only within this many cells of z = 0, where the samplers' row arithmetic is
# exact to far below a texel (here 2.5e8 m: their coordinates' rounding stays below 1e-5 texel).
DRY_TEST_MAX_ROWS = 1e9
# Queries smaller than this skip the dry-cell test (its dozen NumPy calls cost more than they save); the compiled
# test (one loop) is worth it at any size, so with the kernels on every query takes it.
DRY_TEST_MIN_POINTS = 512
# Queries smaller than this compute the kerb streams everywhere rather than in their band alone (the NumPy path;
# the compiled one always takes the band, which its loop finds).
KERB_BAND_MIN_POINTS = 256


def _window_min(a: np.ndarray, lo: int, hi: int, axis: int, wrap: bool) -> np.ndarray:
    """Minimum over offsets lo … hi along ``axis`` (wrapped, or clamped to the edge)."""
    size = a.shape[axis]
    out = None
    for o in range(lo, hi + 1):
        index = np.mod(np.arange(size) + o, size) if wrap else np.clip(np.arange(size) + o, 0, size - 1)
        shifted = a.take(index, axis=axis)
        out = shifted if out is None else np.minimum(out, shifted)
    return out


def _dry_floors(maps) -> np.ndarray | None:
    """The table of ``_PackedGrids.dry_floors`` from (h, h_smooth, noise): per puddle-map cell, the minima of
    every texel a bilinear sample of a point in it can read — one texel more on each side than the exact footprint,
    for the rounding of the cell's and the samplers' coordinates — less DRY_FLOOR_MARGIN."""
    h, h_smooth, noise = (np.asarray(m, dtype=np.float64) for m in maps[:3])
    extent_x, extent_z = maps[3]
    nz, nx = noise.shape
    hz, hx = h.shape
    # Heightmap texels per puddle-map cell across (rx) and along (rz) the road, and heightmap periods per PERIOD_M.
    periods = layout.PERIOD_M / extent_z
    rx, rz = hx // nx, hz * round(periods) // nz
    if extent_x != 2 * ROAD_HALF_WIDTH_M or periods != round(periods) or rx * nx != hx or rz * nz != hz * periods \
            or hz % rz:
        return None

    def heightmap_floor(m):
        # A cell's points read texels r·c − 1 … r·c + r (bilinear taps); one more either side for rounding.
        # Rows wrap with the heightmap's own period, tiled over the puddle map's.
        m = _window_min(m, -2, rx + 1, 1, wrap=False)[:, ::rx]
        m = _window_min(m, -2, rz + 1, 0, wrap=True)[::rz]
        return np.tile(m, (nz // len(m), 1))

    # The puddle map's points read texels c − 1 … c + 1; one more either side.
    n_floor = _window_min(_window_min(noise, -2, 2, 1, wrap=False), -2, 2, 0, wrap=True)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * heightmap_floor(h_smooth) + PUDDLE_NOISE_WEIGHT * n_floor
    return np.stack([heightmap_floor(h), ground]).reshape(2, -1) - DRY_FLOOR_MARGIN


@lru_cache(maxsize=16)
def _kerb_band_start(gutter_k: float) -> float:
    """|x| (m) beyond which the kerb streams may hold water for spread coefficient gutter_k (> 0): the spread
    k·L^(3/8) is largest at the full inlet spacing L = 50 m (with a margin for the rounding of the power). Cached:
    every film query asks it, and gutter_k changes only with the weather."""
    from rain_core.gutter import INLET_SPACING_M

    widest = gutter_k * INLET_SPACING_M ** 0.375 * (1.0 + 1e-9) + 1e-12
    return ROAD_HALF_WIDTH_M - widest


@lru_cache(maxsize=2)
def _packed_grids(seed: int, world) -> _PackedGrids:
    return _PackedGrids(seed, world)


def _road_depths(grids: _PackedGrids, x, z, crack_at, puddle_at, gutter_k):
    """Standing water (mm) and the shelter at on-road points x, z (float64 (k,) m): ``_standing_water_mm`` and
    the gutter streams as ``water_depths_mm`` computes them. crack_at = cracks·CRACK_LEVEL, puddle_at = the
    puddle level (Python floats). The NumPy twins' path (with the kernels on, _depths_compiled does this)."""
    (h, h_smooth), (n, shelter) = grids.sample(x, z)
    # np.clip's values, without its Python-level wrapper (two ufuncs: the same numbers, NaN included).
    crack = CRACK_MAX_MM * np.minimum(np.maximum((crack_at - h) / CRACK_DEPTH_SPAN, 0.0), 1.0)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * h_smooth + PUDDLE_NOISE_WEIGHT * n
    puddle = PUDDLE_MAX_MM * np.minimum(np.maximum((puddle_at - ground) / PUDDLE_DEPTH_SPAN, 0.0), 1.0)
    standing = np.maximum(crack, puddle) * (1.0 - shelter)
    if gutter_k > 0.0:
        if x.size < KERB_BAND_MIN_POINTS:
            return np.maximum(standing, gutter_depth_mm(x, z, gutter_k)), shelter
        # The stream is +0 short of its widest spread from the kerb, and max(standing, +0) is standing (≥ +0, as
        # the shelter ≤ 1): it is computed in the kerb band alone.
        near = (np.abs(x) > _kerb_band_start(gutter_k)).nonzero()[0]
        if near.size:
            standing[near] = np.maximum(standing.take(near), gutter_depth_mm(x.take(near), z.take(near), gutter_k))
    return standing, shelter


def _checked_levels(cracks, puddles, puddle_amount, wetness) -> tuple[float, float, float]:
    """(crack level, puddle level, wet film mm) of the weather's levels, each checked in [0, 1]."""
    cracks, puddles, puddle_amount, wetness = (
        checks.number(name, v, 0.0, 1.0) for name, v in (("cracks", cracks), ("puddles", puddles),
                                                        ("puddle_amount", puddle_amount), ("wetness", wetness)))
    return (cracks * CRACK_LEVEL, PUDDLE_LEVEL_MAX * (puddles * puddle_amount) ** PUDDLE_LEVEL_EXPONENT,
            WET_FILM_MM * wetness)


def _depths(grids, x, z, crack_at: float, puddle_at: float, wet: float, gutter_k: float):
    """(standing, film) mm at float64 x, z (m) of one shape. Only the asphalt holds water: the maps are sampled
    there alone (callers such as the ripples ask for whole strips of cells, about half over the pavements)."""
    if jit.active():
        return _depths_compiled(grids, x, z, crack_at, puddle_at, wet, gutter_k)
    on_road = np.abs(x) <= ROAD_HALF_WIDTH_M
    if on_road.all():  # e.g. the wheels' points: no gather and scatter
        road, shelter = _road_depths(grids, x.reshape(-1), z.reshape(-1), crack_at, puddle_at, gutter_k)
        return road.reshape(x.shape), (wet * (1.0 - shelter)).reshape(x.shape)
    standing, film = np.zeros(x.shape), np.zeros(x.shape)
    if on_road.any():
        road, shelter = _road_depths(grids, x[on_road], z[on_road], crack_at, puddle_at, gutter_k)
        standing[on_road] = road
        film[on_road] = wet * (1.0 - shelter)
    return standing, film


def _depths_compiled(grids, x, z, crack_at: float, puddle_at: float, wet: float, gutter_k: float):
    """``_depths`` with the kernels on: the on-road test, the samples, the film and the kerb band in one loop
    (``film_points``); the kerb streams (a power law) stay NumPy's, in the kerb band alone (the loop gives its
    points for free; short of it the stream is +0 and max(standing, +0) is standing, so a query of any size gives
    ``_road_depths``' values, and one without a point in the band makes no NumPy call for them)."""
    flat_x, flat_z = np.ascontiguousarray(x).reshape(-1), np.ascontiguousarray(z).reshape(-1)
    standing, film = np.empty(x.shape), np.empty(x.shape)
    shelter, index = grids.kernel_scratch(flat_x.size)
    kerb = _kerb_band_start(gutter_k) if gutter_k > 0.0 else math.inf
    flat = standing.reshape(-1)
    _, near = _kernels.film_points(grids.table, grids.kernel_constants, grids.kernel_ints, flat_x, flat_z, crack_at,
                                   puddle_at, wet, kerb, flat, film.reshape(-1), shelter, index)
    if gutter_k > 0.0 and near:
        at = index[1, :near]
        flat[at] = np.maximum(flat.take(at), gutter_depth_mm(flat_x.take(at), flat_z.take(at), gutter_k))
    return standing, film


def water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, world=None, wetness=0.0, gutter_k=0.0):
    """(standing water, film) depths in mm at road points x, z (m; arrays broadcast): standing water in cracks,
    puddles and the kerb streams (``gutter_k``: the spread coefficient of rain_core.gutter, 0 without), and the
    wet film WET_FILM_MM·wetness. Both 0 off the asphalt (|x| > 7 m); cracks, puddles and film 0 under roofs
    (the gutter stream runs on under them)."""
    crack_at, puddle_at, wet = _checked_levels(cracks, puddles, puddle_amount, wetness)
    world = world if world is not None else default_world()
    x = np.asarray(x_m, dtype=np.float64)
    z = np.asarray(z_m, dtype=np.float64)
    if x.shape != z.shape:
        x, z = np.broadcast_arrays(x, z)
    return _depths(_packed_grids(int(seed), world), x, z, crack_at, puddle_at, wet, float(gutter_k))


def film_depth_sampler(cracks, puddles, puddle_amount=0.5, seed=0, world=None, wetness=0.0, gutter_k=0.0):
    """:func:`film_depth_mm` with these arguments fixed (checked here, once): returns ``depth(x, z)`` → mm for
    float64 arrays x, z (m) of one shape, the same values bit for bit, for a caller that asks every frame (the
    spray's wheels and landings, the road's film function). Arguments and units as :func:`film_depth_mm`."""
    crack_at, puddle_at, wet = _checked_levels(cracks, puddles, puddle_amount, wetness)
    grids = _packed_grids(int(seed), world if world is not None else default_world())
    gutter_k = float(gutter_k)
    floors = grids.dry_floors() if wet == 0.0 else None

    def depth(x, z):
        return np.maximum(*_depths(grids, x, z, crack_at, puddle_at, wet, gutter_k))

    if floors is None:
        return depth
    # Without the wet film the depth is the standing water alone (max(s, ±0) is s, bit for bit), and that is +0
    # wherever the dry-cell table rules out cracks, puddles and kerb streams: only the other points are sampled.
    levels = np.array([[crack_at], [puddle_at]])
    kerb = _kerb_band_start(gutter_k) if gutter_k > 0.0 else math.inf
    nz, nx = _road_map_shape()
    # Puddle-map cells per m along z and across x, its columns, its cells.
    scale = (nz / layout.PERIOD_M, nx / (2 * ROAD_HALF_WIDTH_M), float(nx), nz * nx)

    def standing_depth(x, z):
        if x.size < DRY_TEST_MIN_POINTS and not jit.active():
            return depth(x, z)
        return _standing_where_wet(grids, floors, levels, kerb, scale, x, z, crack_at, puddle_at, gutter_k, depth)

    return standing_depth


def _standing_where_wet(grids, floors, levels, kerb, scale, x, z, crack_at, puddle_at, gutter_k, fallback):
    """Standing water (mm) at float64 x, z (m) of one shape, sampled only on the asphalt where the dry-cell table
    (``_PackedGrids.dry_floors``) allows a crack or a puddle (h or g below its level) or near the kerbs where the
    gutter may run (|x| > kerb); +0 elsewhere, which is what sampling gives there (the maps' bilinear samples stay
    within their taps' range to a few ulps, so the clamps give +0 crack and puddle, and the gutter is +0)."""
    if jit.active() and _is_grid(x, z):
        return _standing_on_grid(grids, floors, levels, kerb, scale, x, z, gutter_k, fallback)
    if jit.active():  # one loop over the points; the kerb streams (a power law) stay in NumPy
        flat_x, flat_z = np.ascontiguousarray(x).reshape(-1), np.ascontiguousarray(z).reshape(-1)
        out = np.zeros(x.shape)
        shelter, scratch = grids.kernel_scratch(flat_x.size)
        m = _kernels._standing_where_wet_kernel(grids.table, grids.kernel_constants, grids.kernel_ints, floors,
                                       levels[0, 0], levels[1, 0], kerb, *scale, DRY_TEST_MAX_ROWS, flat_x, flat_z,
                                       out.reshape(-1), shelter, scratch)
        if m < 0:
            return fallback(x, z)
        if m and gutter_k > 0.0:
            index, flat = scratch[1, :m], out.reshape(-1)
            flat[index] = np.maximum(flat.take(index), gutter_depth_mm(flat_x.take(index), flat_z.take(index),
                                                                      gutter_k))
        return out
    flat_x, flat_z = x.reshape(-1), z.reshape(-1)
    ax = np.abs(flat_x)
    on = (ax <= ROAD_HALF_WIDTH_M).nonzero()[0]
    xs, zs = flat_x.take(on), flat_z.take(on)
    rows = zs * scale[0]
    if rows.size and not (-DRY_TEST_MAX_ROWS < rows.min() and rows.max() < DRY_TEST_MAX_ROWS):
        return fallback(x, z)  # far or non-finite z: sample everything, as before
    # Puddle-map cell (row wrapped, column clamped; x + 7 ≥ 0 on the road): small integers, exact.
    cols = np.minimum(np.floor((xs + ROAD_HALF_WIDTH_M) * scale[1]), scale[2] - 1.0)
    cell = (np.floor(rows) * scale[2] + cols).astype(np.int64) % scale[3]
    maybe = np.less(floors.take(cell, axis=1), levels)
    maybe = maybe[0] | maybe[1]
    if kerb < ROAD_HALF_WIDTH_M:
        maybe |= ax.take(on) > kerb
    index = maybe.nonzero()[0]
    out = np.zeros(x.shape)
    if index.size:
        out.reshape(-1)[on.take(index)] = _road_depths(grids, xs.take(index), zs.take(index), crack_at, puddle_at,
                                                       gutter_k)[0]
    return out


def _is_grid(x, z) -> bool:
    """Whether x, z (float64, one 2-D shape) are a grid: x the same down every column and z along every row, as
    views (strides 0) give them, e.g. ``np.broadcast_to`` of a row of x and a column of z (the ripples' strips)."""
    return x.ndim == 2 and x.strides[0] == 0 and z.strides[1] == 0 and x.size > 0


def _standing_on_grid(grids, floors, levels, kerb, scale, x, z, gutter_k, fallback):
    """``_standing_where_wet`` on a grid (``_is_grid``), compiled: each row's and each column's share of the
    sampling done once (``_standing_grid_kernel``), and the kerb streams' power law once per row and kerb (the
    stream's spread depends on z and the kerb alone) — the same operations on the same values: the same bits."""
    xc, zr = np.ascontiguousarray(x[0]), np.ascontiguousarray(z[:, 0])
    spread = _EMPTY_SPREAD
    if kerb < ROAD_HALF_WIDTH_M:
        # gutter_depth_mm's T = k·L^(3/8) at the −x then the +x kerb, on contiguous arrays as it computes them
        sides = np.repeat(_KERB_SIDES, zr.size)
        with np.errstate(invalid="ignore"):  # a non-finite z: the kernel sends it to the fallback
            spread = (gutter_k * upstream_length_m(sides, np.concatenate((zr, zr))) ** 0.375).reshape(2, -1)
    out = np.zeros(x.shape)
    if _kernels._standing_grid_kernel(grids.table, grids.kernel_constants, grids.kernel_ints, floors, levels[0, 0],
                                      levels[1, 0], kerb, *scale, DRY_TEST_MAX_ROWS, xc, zr, spread, out) < 0:
        return fallback(x, z)
    return out


_KERB_SIDES = np.array([-1.0, 1.0])  # an x on each kerb's side of the crown (which inlets the stream runs to)
_EMPTY_SPREAD = np.zeros((2, 0))


def film_depth_mm(x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, world=None, wetness=0.0,
                  gutter_k=0.0) -> np.ndarray:
    """Water film depth (mm, ≤ PUDDLE_MAX_MM = 10) on the road at x, z (m; vectorised, any world z).

    cracks, puddles: the weather's two flood levels in [0, 1]; puddle_amount in [0, 1] (settings.road): how much
    of the road can hold puddles; seed: the puddle noise map's seed (settings.road.puddle_seed); world: gives
    the road heightmap and the roofs (None: the default street, ``build_world(seed=1)``); wetness in [0, 1]
    adds the thin film of a wet road (WET_FILM_MM at 1; default 0 = standing water only). 0 off the asphalt
    (|x| > 7 m) and under roofs; gutter_k adds the kerb streams (rain_core.gutter; up to GUTTER_MAX_MM). The GLSL
    twin is ``road_film_depth_mm`` in shaders/road/film.glsl.
    """
    standing, film = water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount, seed, world, wetness, gutter_k)
    return np.maximum(standing, film)


# The compiled twins, by attribute at call time (they import this module's constants: whichever module is imported
# first, both are complete before a sample is asked for).
import rain_core.water_film_kernels as _kernels  # noqa: E402
