"""Rainfall (DESIGN §3 "Near and far rain", "Rainfall container"; issue 6): streak particles in a container that
follows the camera, whose fate is settled when they spawn, drawn as motion-blurred drops, plus impact splashes.

Units: m, s, m/s; drop diameter D in mm, rain rate R in mm/h. World frame +Y up, the car drives along −Z.

Container (nested boxes, denser near the viewer)
------------------------------------------------
Four axis-aligned boxes ("layers") with horizontal half-sizes ``container_m/2 × (⅛, ¼, ½, 1)``, each centred 0.8
half-sizes ahead of the camera along its horizontal view direction (so the camera sits a tenth of the box from
its back face, where the fade ends and the view begins), from just below the ground to ``TOP_SLOPE × half-size``
above the eye (about the top of the view frustum at the far face). A box holds the view frustum's slab poorly
(~40 % of the drops are in view, the rest are the reservoir that falls or drifts into it), but it can be
refilled exactly when it moves (below). Each layer holds a Poisson process of drops with a uniform density
n_k = κ·ν_k; ν is chosen so that the summed density falls as 1/distance² (``PROFILE_EXPONENT``): every layer
gets about as many drops as the next smaller one twice, so the streaks near the eye — the ones a viewer reads as
rain — are many and faint rather than few and saturated, while the far ones, sub-pixel and short, are sparser
and carry more weight each. Membership fades linearly over the outer 20 % of each box; a drop's weight divides
by the faded summed density, so the weighted density is exact everywhere inside the outer box — except in the
outer box's own fade, where the streaks fade into the far rain (the atmosphere effect's extinction).

Keeping the container filled (no per-frame work on every drop)
-------------------------------------------------------------
Drops live in world space. Between two frames the drops of one size move by u·dt (wind, fall speed v(D)) and
the box moves with the camera. The region that is new to the box — inside it now, outside the previous box
advected with the drops — is a union of slabs on the box's leading faces (the top face while drops fall in, the
front face while the car drives, the upwind face in wind, every face when the box resizes). Those slabs are
sampled exactly (Poisson counts, D from Marshall–Palmer, a drop kept when it lies in its own D-dependent slab
and in no earlier one). On the first frame the whole box is new. So the set of drops inside each box is at all
times a sample of the world's stationary rain, whatever the camera does (turning, reversing, stopping).

A drop leaves by hitting something (its lifetime, settled at spawn) or by leaving its box. The CPU keeps a
calendar of when each drop is due for a check (its hit time, or when it would leave its box at the current
relative velocity); only the due drops are looked at (the ones that left are freed and cleared on the GPU,
the others rescheduled). The GPU computes every position from the spawn point, velocity and age, and culls what
lies outside its box. CPU work per frame is proportional to the spawn rate, not to the particle count.

Budget, thinning and compensation
---------------------------------
Physical drop densities are ~700–4000 drops/m³ (``physics.number_density_per_m3``), millions in a container. The
drawn count is ``HEADROOM × budget × min(1, N(R)/N(BUDGET_FULL_AT_MM_H))``: it follows the physical density
until the budget is full at heavy rain (8 mm/h), so light rain has fewer streaks than heavy rain, as it should.
Each drawn drop stands for w = N_eff(R)/n_draw(x) real drops (≥ 1; N_eff = density_scale·N) and is drawn
with w times the light of one drop: first **brighter** (opacity up to ``ALPHA_MAX``), then **wider** (up to
``WIDTH_MAX_PX``); only beyond that is light lost (``python -m rain_core.bench rainfall`` measures how much).
The weight is stored per drop when it spawns, so a change of rate changes the picture only as drops are
replaced — no pop. The rate the effect uses also approaches the set rate with a ``RATE_RAMP_S`` time constant.

Occlusion: a top-down roof height map, not ray casts against trimesh
-------------------------------------------------------------------
``world.occluder_height(x, z)`` is the occluder mesh (bridge deck, embankment, canopy, roofs, awnings) rendered
once into a 0.25 m top-down height map. A drop's straight path (slanted by wind) is marched through that map,
from ``BACKWARD_MAX_M`` above the drop down to the ground: the first point below a roof ends the drop's life
there; a hit before the spawn point means the drop would have come through a roof (under it, or in the strip of
rain shadow under an eave) and it is not spawned. A map lookup is a few array operations for thousands of
drops, where a trimesh ray cast costs microseconds per ray and needs its acceleration structure; two max-pooled
copies of the map (4 m and 1 m blocks) narrow each path to the stretch that can meet a roof, so a drop over the
open road costs a handful of lookups. (Sampling every 0.25 m, a slanted path can clip the corner of a roof
unseen: ~0.2 % of the drops near buildings.) The share of each box that rain can reach is tracked with probe
drops, so the budget goes to the open air, not into buildings.

Vehicles move, so they are tested analytically: the ego car and the traffic as convex pieces (the body below the
belt line, and the greenhouse with its raked windshield) moving at their velocity at spawn time; a drop whose
path relative to a vehicle enters it ends there (roof, hood, windshield, sides). A drop inside a vehicle, or that
would have left one less than ``VEHICLE_WAKE_S`` ago, is not spawned; a longer ballistic wake would be wrong,
since small drops ride the airflow around the body. A vehicle that brakes or turns after a drop spawned can
meet drops its fate did not foresee (they fall through it for the rest of their short lives).

What the camera sees
--------------------
A streak is the drop's path relative to the camera during the exposure (``camera.exposure_s``): from
p(t) to p(t − T) + v_cam·T, so rain tilts towards the windshield by atan(v_car/v(D)) and follows the car's actual
velocity (taken at the camera point of the ego car, including its yaw rate; finite differences for the free
camera). Width = the drop's projected diameter (Beard & Chuang's flattened shape for D > 1 mm) with a 1 px floor;
opacity = (weight × projected drop area) / (streak area), since a drop covers each pixel of its streak for only
a fraction of the exposure. Colour (``shaders/common/rainfall_drop.glsl``): a drop is a tiny fish-eye that
shows ~94 % of the radiance of a ~165° view behind it (Garg & Nayar), plus the sun, street lamps and headlights
scattered by the drop (two-term Henyey–Greenstein phase function, the same as the atmosphere effect), so drops
in a headlight beam glow. Streaks blend over the HDR frame with the scene's depth test, without depth writes
or sorting.

Splashes
--------
Not tied to drops (DESIGN §3): impact points are drawn at random on the open ground near the camera at the rate
of visible impacts, ∫_{D ≥ 1.5 mm} N(D)·v(D) dD per m² per s (smaller drops make no visible splash), thinned
with a fixed ratio until ``splash`` capacity is full at heavy rain — hardly any in light rain. On a puddle a
crown (height ∝ D, a few cm for the largest drops), on a wet film a smaller crown, on a dry surface a prompt
splash (droplets only); they live 100–300 ms, never under a roof or a vehicle.

Cost and skipping
-----------------
R = 0 with no drops left in the air → ``active`` is False: no update, no pass. Per frame the GPU draws the
environment map (64×32 texels, each the mean of 64 sky directions), then one instanced quad per drop slot: a
slot outside the view or its box is culled in the vertex shader before any lighting; only the lights that reach
the container are looped over. Texture units 8 (drop state) and 9 (environment).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import moderngl
import numpy as np

from rain_core import layout, physics
from rain_core.renderer import Effect

# --- constants -------------------------------------------------------------------------------------------

PERIOD_M = layout.PERIOD_M  # m, the world repeats along z
TIME_PERIOD_S = 1024.0  # s, spawn times are stored modulo this on the GPU (every lifetime is far shorter)
GROUND_Y_M = 0.0  # m, drops end at the road plane (kerbs and sidewalks hide the last 15 cm by depth test)
BOX_BOTTOM_Y_M = -0.5  # m, the boxes reach just below the ground
LAYER_SCALES = (0.125, 0.25, 0.5, 1.0)  # half-size of each layer relative to the outer one
PROFILE_EXPONENT = 2.0  # the summed density ∝ half-size^−p (see the module docstring)


def _profile(scales, p: float) -> tuple[float, ...]:
    """ν_k such that Σ_{j ≥ k} ν_j ∝ scale_k^−p, with ν of the outer layer 1."""
    total = np.asarray(scales, dtype=np.float64) ** -p
    nu = total - np.append(total[1:], 0.0)
    return tuple(float(v) for v in nu / nu[-1])


LAYER_PROFILE = _profile(LAYER_SCALES, PROFILE_EXPONENT)  # ν_k
FORWARD_OFFSET = 0.8  # box centre this many half-sizes ahead: the back face fades out just behind the eye
TOP_SLOPE = 0.8  # box top = eye height + TOP_SLOPE × half-size + TOP_PAD_M
TOP_PAD_M = 1.0
FADE_FRACTION = 0.2  # membership ramps over this share of each half-size (sides) and of the height (top)
HEADROOM = 0.8  # expected live drops = this share of the budget (room for Poisson fluctuations)
BUDGET_FULL_AT_MM_H = 8.0  # mm/h from which the whole budget is used (heavy rain)
RATE_RAMP_S = 1.5  # s, time constant with which the effect's rate follows the set rate
RATE_OFF_MM_H = 0.002  # mm/h, below this (with the set rate 0) no more drops spawn
MIN_RECHECK_S = 0.05  # s, shortest delay before a due drop that is still inside is looked at again
CALENDAR_BUCKET_S = 1.0 / 32.0  # s; a check may come up to this late (it only delays the reuse of a slot)
CALENDAR_BUCKETS = 4096  # 128 s ahead; later checks are clamped to the end
TURBULENCE = 0.15  # per-drop horizontal velocity jitter, × wind speed (m/s)
OPEN_PROBES_FIRST, OPEN_PROBES = 4096, 512  # probe points per box for the open share (first frame, later)
OPEN_PROBE_EVERY = 8  # frames between probes
OPEN_PROBE_BLEND = 0.3  # weight of a new probe in the open share's running average

# Streak drawing (keep the NumPy twin, ``streak_geometry``, in step with shaders/rainfall_streak.vert).
WIDTH_FLOOR_PX = 1.0  # px, narrowest streak; thinner drops get less opacity instead
ALPHA_MAX = 0.7  # a compensated streak gets brighter up to this opacity …
WIDTH_MAX_PX = 4.0  # … then wider up to this width; beyond, light is lost

# Occlusion march.
MARCH_STEP_M = 0.25  # m, horizontal spacing of the fine march (the height map's cell)
MARCH_MAX_SAMPLES = 128
REFINE_STEPS = 4  # bisections of the step in which a path meets a roof
FATE_CHUNK = 131072  # drops per batch of the fate tests (bounds the march's memory)
SKIP_BLOCK_M = 4.0  # m, cells of the max-pooled map used to skip paths far from any roof
FINE_BLOCK_M = 1.0  # m, cells of the second, finer pooled map
# m, how far above a drop its past path is checked for roofs. Wind inside a street canyon is far weaker than
# above the roofs, so a long ballistic rain shadow (small drops drift 2 m per m of fall in a 2 m/s wind) would put
# whole streets in the dry; a short reach keeps the dry strip under eaves, decks and canopies.
BACKWARD_MAX_M = 3.0
VEHICLE_WAKE_S = 0.05  # s, a drop that was inside a vehicle this recently is not spawned (see vehicle_fate)

# Splashes.
SPLASH_D_MIN_MM = 1.5  # mm, smaller drops make no visible splash
SPLASH_LIFE_S = (0.1, 0.3)  # s, lifetime of the smallest and largest splashing drop
SPLASH_CROWN_HEIGHT_PER_D = 7.0  # crown height / D (a 4 mm drop throws a ~3 cm crown)
SPLASH_LAYER = 1  # splashes fall on the ground inside this layer's box
SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX = 256, 65536
TYPE_PUDDLE_CROWN, TYPE_FILM_CROWN, TYPE_PROMPT = 0, 1, 2

# GPU layout: three RGBA32F texels per drop, DROPS_PER_ROW drops per texture row.
DROPS_PER_ROW = 1024
TEXELS_PER_DROP = 3
STATE_UNIT = 8  # texture unit of the drop state
ENV_UNIT = 9  # texture unit of the drop's environment (rainfall_env.frag)
ENV_SIZE = (64, 32)  # texels of that equirectangular map

# Beard & Chuang (1987) equilibrium shapes r(θ) = a·(1 + Σ C_n cos nθ), C_n × 1e4, D = 2 … 6 mm (in 0.5 mm
# steps; the table of /work/shared/reference/beard_chuang.csv).
_BC_D_MM = np.arange(2.0, 6.01, 0.5)
_BC_C = np.array([
    [-131, -120, -376, -96, -4, 15, 5, 0, -2, 0, 1],
    [-201, -172, -567, -137, 3, 29, 8, -2, -4, 0, 1],
    [-282, -230, -779, -175, 21, 46, 11, -6, -7, 0, 3],
    [-369, -285, -998, -207, 48, 68, 13, -13, -10, 0, 5],
    [-458, -335, -1211, -227, 83, 89, 12, -21, -13, 1, 8],
    [-549, -377, -1421, -240, 126, 110, 9, -31, -16, 4, 11],
    [-644, -416, -1629, -246, 176, 131, 2, -44, -18, 9, 14],
    [-742, -454, -1837, -244, 234, 150, -7, -58, -19, 15, 19],
    [-840, -480, -2034, -237, 297, 166, -21, -72, -19, 24, 23],
]) * 1e-4


def _shape_factors() -> tuple[np.ndarray, np.ndarray]:
    """(side-view area / πD²/4, horizontal width / D) of Beard & Chuang's shapes at _BC_D_MM.

    Seen from the side the silhouette is the meridian curve r(θ): area ½∮r² dθ, width 2·max r(θ)·sin θ."""
    theta = np.linspace(0.0, 2.0 * np.pi, 2049)[:-1]
    n = np.arange(11)
    r = 1.0 + _BC_C @ np.cos(np.outer(n, theta))  # (9, 2048), in units of a = D/2
    area = 0.5 * (r**2).mean(axis=1) * 2.0 * np.pi / np.pi  # / (π a²)
    width = (r * np.abs(np.sin(theta))).max(axis=1)  # half-width / a = width / D
    return area, width


SHAPE_AREA, SHAPE_WIDTH = _shape_factors()


def drop_shape_factors(d_mm) -> tuple[np.ndarray, np.ndarray]:
    """Side-view projected area (÷ πD²/4) and horizontal width (÷ D) of a falling drop of diameter d_mm (mm).

    Spheres below 1 mm; Beard & Chuang's flattened shapes from 2 mm (linear in between, held above 6 mm)."""
    d = np.asarray(d_mm, dtype=np.float64)
    xs = np.concatenate([[1.0], _BC_D_MM])
    area = np.interp(d, xs, np.concatenate([[1.0], SHAPE_AREA]))
    width = np.interp(d, xs, np.concatenate([[1.0], SHAPE_WIDTH]))
    return area, width


# --- physics of the visible rain ---------------------------------------------------------------------------


def drawn_share(rate_mm_h: float) -> float:
    """Share of the budget drawn at rate R (mm/h): N(R)/N(BUDGET_FULL_AT_MM_H), at most 1 (0 at R = 0)."""
    if rate_mm_h <= 0:
        return 0.0
    return min(1.0, physics.number_density_per_m3(rate_mm_h) / physics.number_density_per_m3(BUDGET_FULL_AT_MM_H))


_SPLASH_D = np.linspace(SPLASH_D_MIN_MM, physics.D_MAX_MM, 181)
_SPLASH_V = physics.terminal_velocity(_SPLASH_D)


def splash_flux_per_m2_s(rate_mm_h: float) -> float:
    """Visible impacts per m² of ground per s at R (mm/h): ∫ N_eff(D)·v(D) dD over D ≥ SPLASH_D_MIN_MM."""
    if rate_mm_h <= 0:
        return 0.0
    lam = physics.mp_slope_per_mm(rate_mm_h)
    f = physics.effective_n0(rate_mm_h) * np.exp(-lam * _SPLASH_D) * _SPLASH_V
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(_SPLASH_D)))


def splash_life_s(d_mm) -> np.ndarray:
    """Lifetime (s) of the splash of a drop of diameter d_mm (mm): 0.1 s at 1.5 mm … 0.3 s from 4.5 mm."""
    t = np.clip((np.asarray(d_mm, dtype=np.float64) - SPLASH_D_MIN_MM) / 3.0, 0.0, 1.0)
    return SPLASH_LIFE_S[0] + (SPLASH_LIFE_S[1] - SPLASH_LIFE_S[0]) * t


def _sample_truncated_exp(rng: np.random.Generator, lam: float, lo: float, hi: float, n: int) -> np.ndarray:
    u = rng.random(n)
    return lo - np.log1p(u * np.expm1(-lam * (hi - lo))) / lam


# --- the container ---------------------------------------------------------------------------------------


@dataclass
class Boxes:
    """The layers' boxes: lo, hi (L, 3) in world coordinates (m), fade (L, 3) widths (m), profile ν (L,)."""

    lo: np.ndarray
    hi: np.ndarray
    fade: np.ndarray
    nu: np.ndarray

    @property
    def volumes(self) -> np.ndarray:
        return np.prod(self.hi - self.lo, axis=1)


def layer_boxes(camera_position, camera_forward, container_m: float) -> Boxes:
    """The container's nested boxes (m, world) for a camera at camera_position looking along camera_forward.

    container_m: horizontal size (m) of the outer box. Each box is centred FORWARD_OFFSET half-sizes ahead of the
    camera along the horizontal view direction (scaled by its horizontal share, so a camera looking straight
    down sits at the centre)."""
    cam = np.asarray(camera_position, dtype=np.float64)
    f = np.asarray(camera_forward, dtype=np.float64)
    fh = np.array([f[0], f[2]])
    n = float(np.hypot(*fh))
    fh = fh / n if n > 1e-9 else np.zeros(2)
    h = 0.5 * float(container_m) * np.asarray(LAYER_SCALES)
    centre = cam[[0, 2]][None, :] + fh[None, :] * (FORWARD_OFFSET * h * min(n, 1.0))[:, None]
    top = max(float(cam[1]), GROUND_Y_M) + TOP_SLOPE * h + TOP_PAD_M
    lo = np.stack([centre[:, 0] - h, np.full_like(h, BOX_BOTTOM_Y_M), centre[:, 1] - h], axis=1)
    hi = np.stack([centre[:, 0] + h, top, centre[:, 1] + h], axis=1)
    fade = np.stack([FADE_FRACTION * h, FADE_FRACTION * (top - BOX_BOTTOM_Y_M), FADE_FRACTION * h], axis=1)
    return Boxes(lo, hi, fade, np.asarray(LAYER_PROFILE, dtype=np.float64))


def wrap_near(z, around_z):
    """z (m) shifted by whole periods to lie within half a period of around_z (m)."""
    return z - PERIOD_M * np.round((np.asarray(z) - around_z) / PERIOD_M)


def membership(p, boxes: Boxes, layer) -> np.ndarray:
    """Fade-in factor in [0, 1] of points p (n, 3) in the boxes of their layers (n,): linear ramps over the fade
    widths at the sides and the top, none at the bottom (the ground ends the drops). Mirrors the shader."""
    lo, hi, fade = boxes.lo[layer], boxes.hi[layer], boxes.fade[layer]
    a = np.clip((p - lo) / fade, 0.0, 1.0)
    b = np.clip((hi - p) / fade, 0.0, 1.0)
    a[:, 1] = (p[:, 1] >= lo[:, 1]).astype(np.float64)
    return np.prod(a, axis=1) * np.prod(b, axis=1)


def drawn_density_factor(p, boxes: Boxes) -> np.ndarray:
    """max(Σ_k ν_k·m_k(p), ν_outer) at points p (n, 3): the drawn density ÷ κ that a weight divides by."""
    p = np.atleast_2d(p)
    total = np.zeros(len(p))
    for k in range(len(boxes.nu)):
        total += boxes.nu[k] * membership(p, boxes, np.full(len(p), k))
    return np.maximum(total, boxes.nu[-1])


# --- occlusion ---------------------------------------------------------------------------------------------


class OccluderField:
    """The static roofs as a top-down height map (``world.occluder_height``: the occluder mesh rendered once, 0.25 m
    cells, −inf where open) and a max-pooled copy (SKIP_BLOCK_M cells, dilated by one cell) that tells which
    stretches of a path cannot meet a roof. ``heights`` reads the fine map's array directly (the same values as
    ``world.occluder_height``, a few times faster) and defers to the world beyond the fine map's x range."""

    def __init__(self, world):
        self.world = world
        fine = world.occluder_map
        coarse = world.occluder_map_coarse
        finite = [g[np.isfinite(g)] for g in (fine.grid, coarse.grid)]
        self.max_height = max((float(f.max()) for f in finite if f.size), default=-np.inf)
        self._grid = np.ascontiguousarray(fine.grid, dtype=np.float32)
        self._x0, self._cell = float(fine.x0_m), float(fine.cell_m)
        self._span_z = self._grid.shape[0] * self._cell
        self._pooled = self._unified_pool(fine, coarse)
        self._pooled_fine = self._pool(fine, FINE_BLOCK_M)
        self._pooled_fine[0][:, [0, -1]] = np.inf  # its edge blocks cannot see roofs beyond the fine map

    @staticmethod
    def _pool(occ_map, block_m: float = SKIP_BLOCK_M):
        """Block max of a map's grid over block_m cells, dilated by one block (z periodic)."""
        k = max(1, int(round(block_m / occ_map.cell_m)))
        nz, nx = occ_map.grid.shape
        bz, bx = -(-nz // k), -(-nx // k)
        grid = np.full((bz * k, bx * k), -np.inf, dtype=np.float64)
        grid[:nz, :nx] = occ_map.grid
        grid[nz:, :nx] = occ_map.grid[: bz * k - nz]  # z wraps
        blocks = grid.reshape(bz, k, bx, k).max(axis=(1, 3))
        dil = blocks.copy()
        for dz in (-1, 0, 1):
            rolled = np.roll(blocks, dz, axis=0)
            dil = np.maximum(dil, rolled)
            dil[:, 1:] = np.maximum(dil[:, 1:], rolled[:, :-1])
            dil[:, :-1] = np.maximum(dil[:, :-1], rolled[:, 1:])
        return dil, float(occ_map.x0_m), occ_map.cell_m * k, nz * occ_map.cell_m

    @classmethod
    def _unified_pool(cls, fine, coarse):
        """One pooled grid over the coarse map's extent, raised to the fine map's pooled values where that one
        reaches (the 2 m raster can miss roofs narrower than a cell; the fine one misses nothing)."""
        grid_c, x0_c, cell, span_z = cls._pool(coarse)
        grid_f, x0_f, cell_f, _ = cls._pool(fine)
        offset = (x0_f - x0_c) / cell
        if abs(cell_f - cell) > 1e-9 or abs(offset - round(offset)) > 1e-9 or grid_f.shape[0] != grid_c.shape[0]:
            raise ValueError("the fine and coarse occluder maps do not share the pooled block lattice")
        i0 = int(round(offset))
        grid = grid_c.copy()
        grid[:, i0: i0 + grid_f.shape[1]] = np.maximum(grid[:, i0: i0 + grid_f.shape[1]], grid_f)
        return grid, x0_c, cell, span_z

    def near_max(self, x, z, fine: bool = False) -> np.ndarray:
        """Highest roof (m) within at least SKIP_BLOCK_M (fine: FINE_BLOCK_M) of (x, z) (m). Outside the map:
        −inf for the coarse map (there is nothing), +inf for the fine one (it does not know: march)."""
        grid, x0, cell, span_z = self._pooled_fine if fine else self._pooled
        fx = (x - x0) / cell
        inside = (fx >= 0.0) & (fx < grid.shape[1])
        i = np.clip(fx, 0, grid.shape[1] - 1).astype(np.int64)
        j = (np.mod(z, span_z) / cell).astype(np.int64) % grid.shape[0]
        return np.where(inside, grid[j, i], np.inf if fine else -np.inf)

    @staticmethod
    def _ragged(t_a, t_b, counts):
        """Sample times of ragged series: counts[i] evenly spaced times from t_a[i] to t_b[i] (counts ≥ 2).
        Returns (owner index, local index, times, starts)."""
        idx = np.repeat(np.arange(counts.size), counts)
        starts = np.zeros(counts.size, dtype=np.int64)
        np.cumsum(counts[:-1], out=starts[1:])
        local = np.arange(idx.size) - starts[idx]
        tau = t_a[idx] + (t_b - t_a)[idx] * (local / (counts[idx] - 1))
        return idx, local, tau, starts

    def _risky_stretch(self, p, u, t_a, t_b, spacing_m, fine):
        """For paths p + u·τ over [t_a, t_b], the stretch [first, last] between samples ≤ spacing_m apart that
        may meet a roof, judged on a pooled map. Returns (indices of risky paths, their t_a, their t_b)."""
        speed_h = np.hypot(u[:, 0], u[:, 2])
        counts = np.minimum(np.ceil(speed_h * (t_b - t_a) / spacing_m).astype(np.int64), 62) + 2
        idx, local, tau, starts = self._ragged(t_a, t_b, counts)
        near = self.near_max(p[idx, 0] + u[idx, 0] * tau, p[idx, 2] + u[idx, 2] * tau, fine)
        y = p[idx, 1] + u[idx, 1] * tau
        nxt = np.minimum(np.arange(idx.size) + 1, idx.size - 1)
        risky = (local < counts[idx] - 1) & (y[nxt] < np.maximum(near, near[nxt]))
        big = int(counts.max()) + 1
        first = np.minimum.reduceat(np.where(risky, local, big), starts)
        final = np.maximum.reduceat(np.where(risky, local, -1), starts)
        sel = np.flatnonzero(first < big)
        step = (t_b - t_a)[sel] / (counts[sel] - 1)
        return sel, t_a[sel] + step * first[sel], t_a[sel] + step * (final[sel] + 1)

    def heights(self, x, z) -> np.ndarray:
        """Roof height (m) over (x, z) (m), −inf where open: ``world.occluder_height``."""
        nz, nx = self._grid.shape
        fx = (x - self._x0) / self._cell
        inside = (fx >= 0.0) & (fx < nx)
        i = np.clip(fx, 0, nx - 1).astype(np.int64)
        j = (np.mod(z, self._span_z) / self._cell).astype(np.int64) % nz
        h = self._grid[j, i].astype(np.float64)
        if not inside.all():
            miss = ~inside
            h[miss] = np.asarray(self.world.occluder_height(x[miss], z[miss]))
        return h

    def fate(self, p0: np.ndarray, u: np.ndarray, life: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """March the straight paths p0 + u·τ (m, m/s; u_y < 0) through the roof map, from BACKWARD_MAX_M above
        the drop (at most the highest roof) down to the ground. Returns (keep, life): keep is False where the
        path meets a roof before τ = 0 (under a roof or in its rain shadow); life (s) is cut at the first roof
        after. A drop under the roof of its own column is refused at once; for the others a coarse pass on the
        pooled map finds the stretch of the path that can meet a roof, and only that stretch is marched, every
        MARCH_STEP_M of horizontal travel (at most MARCH_MAX_SAMPLES samples), a block of samples at a time so
        that drops leave the march at their first roof."""
        n = len(p0)
        keep = np.ones(n, dtype=bool)
        life = life.copy()
        if n == 0 or not np.isfinite(self.max_height):
            return keep, life
        keep = self.heights(p0[:, 0], p0[:, 2]) <= p0[:, 1]
        rest = np.flatnonzero(keep)
        if rest.size == 0:
            return keep, life
        p, uu = p0[rest], u[rest]
        fall = -uu[:, 1]
        y_top = np.maximum(p[:, 1], np.minimum(self.max_height, p[:, 1] + BACKWARD_MAX_M)) + 0.01
        tau0 = -(y_top - p[:, 1]) / fall  # ≤ 0: when the drop was at y_top
        tau1 = (p[:, 1] - GROUND_Y_M) / fall  # when it reaches the ground
        # Two passes on pooled maps narrow the stretch that can meet a roof: samples ≤ 2·block apart keep every
        # point of the path within one block of a sample, which the dilation covers; a stretch between two
        # samples is safe when the path's lower end is above both pooled maxima.
        cand, t_a, t_b = self._risky_stretch(p, uu, tau0, tau1, 2.0 * SKIP_BLOCK_M, fine=False)
        if cand.size == 0:
            return keep, life
        sub, t_a, t_b = self._risky_stretch(p[cand], uu[cand], t_a, t_b, 2.0 * FINE_BLOCK_M, fine=True)
        cand = cand[sub]
        if cand.size == 0:
            return keep, life
        speed_h = np.hypot(uu[cand, 0], uu[cand, 2])
        nf = np.clip(np.ceil(speed_h * (t_b - t_a) / MARCH_STEP_M).astype(np.int64) + 1, 2,
                     MARCH_MAX_SAMPLES)
        step = (t_b - t_a) / (nf - 1)
        pc, uc = p[cand], uu[cand]
        tau_hit = np.full(cand.size, np.inf)
        active = np.arange(cand.size)
        block = 16
        for k0 in range(0, int(nf.max()), block):
            active = active[nf[active] > k0]
            if active.size == 0:
                break
            ks = k0 + np.arange(block)
            tau_k = t_a[active, None] + step[active, None] * ks[None, :]  # (m, block)
            valid = ks[None, :] < nf[active, None]
            yk = pc[active, 1, None] + uc[active, 1, None] * tau_k
            hk = self.heights((pc[active, 0, None] + uc[active, 0, None] * tau_k).ravel(),
                              (pc[active, 2, None] + uc[active, 2, None] * tau_k).ravel()).reshape(tau_k.shape)
            below = valid & (yk < hk)
            found = below.any(axis=1)
            if found.any():
                rows = np.flatnonzero(found)
                col = np.argmax(below[rows], axis=1)
                drops = active[rows]
                hi = tau_k[rows, col]
                lo = np.where(k0 + col > 0, hi - step[drops], hi)
                for _ in range(REFINE_STEPS):  # bisect to where the path enters the roof's column
                    mid = 0.5 * (lo + hi)
                    under = (pc[drops, 1] + uc[drops, 1] * mid
                             < self.heights(pc[drops, 0] + uc[drops, 0] * mid, pc[drops, 2] + uc[drops, 2] * mid))
                    hi = np.where(under, mid, hi)
                    lo = np.where(under, lo, mid)
                h_hit = self.heights(pc[drops, 0] + uc[drops, 0] * hi, pc[drops, 2] + uc[drops, 2] * hi)
                t_cross = (h_hit - pc[drops, 1]) / uc[drops, 1]  # when y(τ) = that roof's height
                tau_hit[drops] = np.clip(t_cross, lo, hi)
                active = active[~found]
        hit = np.isfinite(tau_hit)
        drops = rest[cand[hit]]
        keep[drops] = tau_hit[hit] > 0.0
        life[drops] = np.minimum(life[drops], np.maximum(tau_hit[hit], 0.0))
        return keep, life


def _near_boxes(vehicle, boxes: Boxes, margin_m: float = 10.0) -> bool:
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


# --- the ring buffer ---------------------------------------------------------------------------------------


class DropPool:
    """A fixed-size buffer of drop slots with a free list, and a calendar of when each live slot is due.

    ``allocate(n)`` pops up to n free slots (lowest first at the start), ``release(slots)`` returns them,
    ``schedule(slots, due_s)`` files live slots under their due time, ``pop_due(t)`` returns the live slots due
    by time t (each once per schedule). Invariant (``check``): live + free = capacity, no slot twice."""

    def __init__(self, capacity: int):
        if capacity < 0:
            raise ValueError(f"capacity must be ≥ 0, got {capacity}")
        self.capacity = int(capacity)
        self.alive = np.zeros(self.capacity, dtype=bool)
        self._free = np.arange(self.capacity, dtype=np.int64)[::-1].copy()
        self._n_free = self.capacity
        self._due = np.full(self.capacity, -1, dtype=np.int64)
        self._buckets: list[list[tuple[np.ndarray, int]]] = [[] for _ in range(CALENDAR_BUCKETS)]
        self._last_bucket: int | None = None
        self.high_water = 0  # one past the highest slot ever allocated (the GPU draws this many)
        self.overflow = 0  # spawns refused because the buffer was full (cumulative)

    @property
    def live(self) -> int:
        return self.capacity - self._n_free

    @property
    def n_free(self) -> int:
        return self._n_free

    def free_slots(self) -> np.ndarray:
        return self._free[: self._n_free].copy()

    def allocate(self, n: int) -> np.ndarray:
        n = int(min(max(n, 0), self._n_free))
        slots = self._free[self._n_free - n: self._n_free][::-1].copy()
        self._n_free -= n
        self.alive[slots] = True
        if n:
            self.high_water = max(self.high_water, int(slots.max()) + 1)
        return slots

    def release(self, slots: np.ndarray) -> None:
        slots = np.asarray(slots, dtype=np.int64)
        if slots.size == 0:
            return
        if not self.alive[slots].all() or np.unique(slots).size != slots.size:
            raise RuntimeError("DropPool.release: a slot is not live or appears twice")
        self.alive[slots] = False
        self._due[slots] = -1
        self._free[self._n_free: self._n_free + slots.size] = slots[::-1]
        self._n_free += slots.size

    def _bucket(self, t: float) -> int:
        return int(math.floor(t / CALENDAR_BUCKET_S))

    def schedule(self, slots: np.ndarray, due_s: np.ndarray, now_s: float) -> None:
        slots = np.asarray(slots, dtype=np.int64)
        if slots.size == 0:
            return
        now = self._bucket(now_s)
        if self._last_bucket is None:
            self._last_bucket = now
        b = np.ceil(np.asarray(due_s, dtype=np.float64) * (1.0 / CALENDAR_BUCKET_S))  # inf: the horizon
        b = np.maximum(np.minimum(b, now + CALENDAR_BUCKETS - 1), max(now, self._last_bucket) + 1).astype(np.int64)
        self._due[slots] = b
        if b.size == 1 or b[0] == b[-1] and (b == b[0]).all():
            self._buckets[int(b[0]) % CALENDAR_BUCKETS].append((slots.copy(), int(b[0])))
            return
        order = np.argsort(b, kind="stable")
        bs, ss = b[order], slots[order]
        edges = np.concatenate([[0], np.flatnonzero(np.diff(bs)) + 1, [bs.size]]).tolist()
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            when = int(bs[lo])
            self._buckets[when % CALENDAR_BUCKETS].append((ss[lo:hi], when))

    def pop_due(self, now_s: float) -> np.ndarray:
        now = self._bucket(now_s)
        if self._last_bucket is None:
            self._last_bucket = now
            return np.zeros(0, dtype=np.int64)
        if now <= self._last_bucket:
            return np.zeros(0, dtype=np.int64)
        out = []
        first = max(self._last_bucket + 1, now - CALENDAR_BUCKETS + 1)
        for b in range(first, now + 1):
            entries = self._buckets[b % CALENDAR_BUCKETS]
            if not entries:
                continue
            self._buckets[b % CALENDAR_BUCKETS] = []
            for slots, when in entries:
                valid = slots[self.alive[slots] & (self._due[slots] == when)]
                if valid.size:
                    self._due[valid] = -1
                    out.append(valid)
        self._last_bucket = now
        return np.concatenate(out) if out else np.zeros(0, dtype=np.int64)

    def check(self) -> None:
        """Raise AssertionError if the free list and the live flags disagree (a leak or a double use)."""
        free = self._free[: self._n_free]
        assert 0 <= self._n_free <= self.capacity
        assert np.unique(free).size == free.size, "a free slot is listed twice"
        assert not self.alive[free].any(), "a live slot is on the free list"
        assert int(self.alive.sum()) + self._n_free == self.capacity, "slots leaked"
        live = np.flatnonzero(self.alive)
        assert (self._due[live] >= 0).all(), "a live slot is not scheduled"


# --- the simulation (CPU, no GL) ---------------------------------------------------------------------------


@dataclass
class RainInput:
    """What the rain simulation needs from one frame. Positions and velocities in the world frame (m, m/s)."""

    time_s: float
    camera_position: np.ndarray
    camera_forward: np.ndarray
    camera_velocity: np.ndarray
    rate_mm_h: float
    wind_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    container_m: float = 40.0
    density_scale: float = 1.0
    splashes: bool = True
    wetness: float = 0.0
    puddles: float = 0.0
    vehicles: tuple = ()


@dataclass
class RainUpdate:
    """What changed in one ``advance``: GPU writes and statistics."""

    spawn_slots: np.ndarray
    spawn_texels: np.ndarray  # (n, 3, 4) float32, the GPU layout of the new drops
    kill_slots: np.ndarray  # slots freed this frame (cleared on the GPU)
    splash_slots: np.ndarray
    splash_data: np.ndarray  # (m, 8) float32
    candidates: int = 0  # drops sampled in the new region (before occlusion and the budget)
    rejected: int = 0  # of those, under a roof, in a rain shadow or inside a vehicle
    overflow: int = 0  # refused because the buffer was full
    cpu_ms: float = 0.0


def _empty_update() -> RainUpdate:
    return RainUpdate(np.zeros(0, np.int64), np.zeros((0, 3, 4), np.float32), np.zeros(0, np.int64),
                      np.zeros(0, np.int64), np.zeros((0, 8), np.float32))


class RainfallSim:
    """The CPU side of the rainfall: the drop pool, the container, spawning with settled fates, and splashes.

    capacity: the particle budget (drops); seed: seeds every random draw (same seed and inputs → same drops);
    world: a rain_core.world.World (its roof map) or None for open ground everywhere.
    ``advance(RainInput) -> RainUpdate``; the per-slot arrays (``pos0``, ``vel``, ``t0``, ``t_hit``,
    ``diameter``, ``weight``, ``layer``) describe the live drops (``pool.alive``)."""

    def __init__(self, capacity: int, seed: int = 0, world=None):
        self.capacity = int(capacity)
        self.seed = int(seed)
        self.world = world
        self.occluders = OccluderField(world) if world is not None and hasattr(world, "occluder_map") else None
        self.splash_capacity = int(np.clip(self.capacity // 16, SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX))
        self.reset()

    def reset(self) -> None:
        """Forget every drop and splash (the next ``advance`` fills the container at once)."""
        c = self.capacity
        self.rng = np.random.default_rng(self.seed)
        self.pool = DropPool(c)
        self.pos0 = np.zeros((c, 3))
        self.vel = np.zeros((c, 3))
        self.t0 = np.zeros(c)
        self.t_hit = np.zeros(c)
        self.diameter = np.zeros(c)
        self.weight = np.zeros(c)
        self.layer = np.zeros(c, dtype=np.int64)
        self.rate_eff = 0.0
        self.kappa = 0.0
        self.boxes: Boxes | None = None
        self.open_fraction: np.ndarray | None = None
        self._probe_frames = 0
        self.t_prev: float | None = None
        self.splash_head = 0
        self.splash_t0 = np.full(self.splash_capacity, -np.inf)
        self.splash_life = np.zeros(self.splash_capacity)
        self.splash_pos = np.zeros((self.splash_capacity, 3))
        self.splash_weight = np.zeros(self.splash_capacity)
        self.generation = getattr(self, "generation", -1) + 1  # tells the GPU side to clear its copy

    @property
    def live(self) -> int:
        return self.pool.live

    def splashes_live(self, time_s: float) -> int:
        return int(np.count_nonzero(self.splash_t0 + self.splash_life > time_s))

    def target_count(self, rate_mm_h: float, density_scale: float) -> float:
        """Expected live drops at rate R (mm/h): HEADROOM × budget × drawn_share(density_scale·…)."""
        return HEADROOM * self.capacity * min(1.0, density_scale * drawn_share(rate_mm_h))

    def positions(self, slots, time_s: float) -> np.ndarray:
        """World positions (m) of drops at time_s (no z wrap)."""
        slots = np.asarray(slots)
        return self.pos0[slots] + self.vel[slots] * (time_s - self.t0[slots])[:, None]

    # --- one frame ---

    def advance(self, inp: RainInput) -> RainUpdate:
        """Advance to inp.time_s: retire due drops, spawn into the new region, spawn splashes."""
        t_start = time.perf_counter()
        t = float(inp.time_s)
        if self.t_prev is not None and t < self.t_prev - 1e-9:
            self.reset()
        first = self.t_prev is None
        dt = 0.0 if first else t - self.t_prev
        target = max(float(inp.rate_mm_h), 0.0)
        if first:
            self.rate_eff = target
        else:
            self.rate_eff = target + (self.rate_eff - target) * math.exp(-dt / RATE_RAMP_S)
            if target == 0.0 and self.rate_eff < RATE_OFF_MM_H:
                self.rate_eff = 0.0
        boxes = layer_boxes(inp.camera_position, inp.camera_forward, inp.container_m)
        upd = _empty_update()
        v_cam = np.asarray(inp.camera_velocity, dtype=np.float64)
        kills = self._retire(t, boxes, v_cam)
        if self.capacity > 0 and self.rate_eff > 0.0:
            self._spawn(t, dt, boxes, None if first else self.boxes, inp, v_cam, upd)
        upd.kill_slots = kills
        if inp.splashes and (first or dt > 0):
            self._spawn_splashes(t, SPLASH_LIFE_S[1] if first else dt, boxes, inp, upd)
        self.boxes = boxes
        self.t_prev = t
        upd.cpu_ms = (time.perf_counter() - t_start) * 1e3
        return upd

    def _retire(self, t: float, boxes: Boxes, v_cam: np.ndarray) -> np.ndarray:
        due = self.pool.pop_due(t)
        if due.size == 0:
            return due
        p = self.positions(due, t)
        lay = self.layer[due]
        p[:, 2] = wrap_near(p[:, 2], 0.5 * (boxes.lo[lay, 2] + boxes.hi[lay, 2]))
        inside = np.all((p >= boxes.lo[lay]) & (p <= boxes.hi[lay]), axis=1)
        dead = (t >= self.t_hit[due] - 1e-9) | ~inside
        self.pool.release(due[dead])
        keep = due[~dead]
        self._schedule(keep, p[~dead], t, boxes, v_cam)
        return due[dead]

    def _schedule(self, slots, p, t, boxes: Boxes, v_cam) -> None:
        """File slots under min(hit time, when they would leave their box at the current relative velocity)."""
        if slots.size == 0:
            return
        lay = self.layer[slots]
        w = self.vel[slots] - v_cam
        lo, hi = boxes.lo[lay], boxes.hi[lay]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_axis = np.where(w > 1e-6, (hi - p) / w, np.where(w < -1e-6, (lo - p) / w, np.inf))
        t_exit = np.min(t_axis, axis=1)
        due = np.minimum(self.t_hit[slots], t + np.maximum(t_exit, MIN_RECHECK_S))
        self.pool.schedule(slots, due, t)

    def fate(self, pos: np.ndarray, u: np.ndarray, boxes: Boxes, vehicles=()) -> tuple[np.ndarray, np.ndarray]:
        """(keep, lifetime s) of drops at pos (m) moving at u (m/s): the ground, the roofs, the nearby vehicles
        (those within FATE_CHUNK-sized batches, to bound memory)."""
        near = [v for v in vehicles if _near_boxes(v, boxes)]
        keep = np.empty(len(pos), dtype=bool)
        life = np.empty(len(pos))
        for a in range(0, len(pos), FATE_CHUNK):
            p, w = pos[a: a + FATE_CHUNK], u[a: a + FATE_CHUNK]
            t = (p[:, 1] - GROUND_Y_M) / -w[:, 1]
            k = p[:, 1] > GROUND_Y_M
            if self.occluders is not None:
                k2, t = self.occluders.fate(p, w, t)
                k &= k2
            if near:
                k3, t = vehicle_fate(p, w, t, near)
                k &= k3
            keep[a: a + FATE_CHUNK] = k & (t > 0.0)
            life[a: a + FATE_CHUNK] = t
        return keep, life

    def _probe_open(self, boxes: Boxes, wind, rate: float, vehicles, first: bool) -> None:
        """Track the share of each box that rain can reach (not under roofs, not inside vehicles), so that the
        budget goes to the open air: an exponential average over random probe drops put through the same fate
        tests as the real ones."""
        n = OPEN_PROBES_FIRST if first else OPEN_PROBES
        if self.occluders is None and not vehicles:
            self.open_fraction = np.ones(len(boxes.nu))
            return
        if not first and self.open_fraction is not None and self._probe_frames > 0:
            self._probe_frames -= 1
            return
        self._probe_frames = OPEN_PROBE_EVERY - 1
        rng = np.random.default_rng(self.rng.integers(2**63))  # its own stream: probes never shift the drops
        frac = np.empty(len(boxes.nu))
        for k in range(len(boxes.nu)):
            p = boxes.lo[k] + rng.random((n, 3)) * (boxes.hi[k] - boxes.lo[k])
            u = np.zeros((n, 3))
            u[:, [0, 2]] = wind[[0, 2]]
            u[:, 1] = -physics.terminal_velocity(physics.sample_drop_diameters(rate, n, rng))
            frac[k] = max(self.fate(p, u, boxes, vehicles)[0].mean(), 0.05)
        if first or self.open_fraction is None:
            self.open_fraction = frac
        else:
            self.open_fraction += OPEN_PROBE_BLEND * (frac - self.open_fraction)

    def _new_region(self, k: int, boxes: Boxes, prev: Boxes | None, wind_xz, dt: float, density: float,
                    rate: float) -> tuple[np.ndarray, np.ndarray]:
        """Sample the drops (positions m, diameters mm) in layer k's box that were not in its previous box."""
        rng = self.rng
        lo, hi = boxes.lo[k], boxes.hi[k]
        ext = hi - lo
        if prev is None:
            n = int(rng.poisson(density * float(np.prod(ext))))
            pos = lo + rng.random((n, 3)) * ext
            return pos, physics.sample_drop_diameters(rate, n, rng)
        lo_p, hi_p = prev.lo[k], prev.hi[k]
        v_max = float(physics.terminal_velocity(physics.D_MAX_MM))
        shift_h = {0: wind_xz[0] * dt, 2: wind_xz[1] * dt}

        def prev_interval(axis, v):
            s = -v * dt if axis == 1 else shift_h[axis]
            return lo_p[axis] + s, hi_p[axis] + s

        def in_slab(axis, side, p_axis, v):
            a, b = prev_interval(axis, v)
            if side == 0:
                return p_axis < np.minimum(a, hi[axis])
            return p_axis > np.maximum(b, lo[axis])

        slabs = [(axis, side) for axis in (0, 2, 1) for side in (0, 1)]
        out_p, out_d = [], []
        for i, (axis, side) in enumerate(slabs):
            vs = (0.0, v_max) if axis == 1 else (0.0,)
            thick = 0.0
            for v in vs:
                a, b = prev_interval(axis, v)
                th = (min(a, hi[axis]) - lo[axis]) if side == 0 else (hi[axis] - max(b, lo[axis]))
                thick = max(thick, min(max(th, 0.0), ext[axis]))
            if thick <= 0.0:
                continue
            others = [j for j in range(3) if j != axis]
            n = int(rng.poisson(density * thick * ext[others[0]] * ext[others[1]]))
            if n == 0:
                continue
            pos = lo + rng.random((n, 3)) * ext
            r = rng.random(n) * thick
            pos[:, axis] = lo[axis] + r if side == 0 else hi[axis] - r
            d = physics.sample_drop_diameters(rate, n, rng)
            v = physics.terminal_velocity(d)
            ok = in_slab(axis, side, pos[:, axis], v)
            for axis_j, side_j in slabs[:i]:
                ok &= ~in_slab(axis_j, side_j, pos[:, axis_j], v)
            out_p.append(pos[ok])
            out_d.append(d[ok])
        if not out_p:
            return np.zeros((0, 3)), np.zeros(0)
        return np.concatenate(out_p), np.concatenate(out_d)

    def _spawn(self, t, dt, boxes: Boxes, prev: Boxes | None, inp: RainInput, v_cam, upd: RainUpdate) -> None:
        rate = self.rate_eff
        n_eff = inp.density_scale * physics.number_density_per_m3(rate)
        if n_eff <= 0.0:
            return
        target = self.target_count(rate, inp.density_scale)
        wind = np.asarray(inp.wind_m_s, dtype=np.float64)
        self._probe_open(boxes, wind, rate, inp.vehicles, first=prev is None)
        open_volume = float(np.sum(boxes.nu * boxes.volumes * self.open_fraction))
        kappa = min(target / max(open_volume, 1e-9), n_eff / float(np.sum(boxes.nu)))
        if kappa <= 0.0:
            return
        self.kappa = kappa
        if prev is not None:
            # The previous boxes in the current period image (the camera may have crossed a tile boundary).
            dz = wrap_near(prev.lo[0, 2] - boxes.lo[0, 2], 0.0) - (prev.lo[0, 2] - boxes.lo[0, 2])
            prev = Boxes(prev.lo + [0.0, 0.0, dz], prev.hi + [0.0, 0.0, dz], prev.fade, prev.nu)
        pos_l, d_l, lay_l = [], [], []
        for k in range(len(boxes.nu)):
            pos, d = self._new_region(k, boxes, prev, wind[[0, 2]], dt, kappa * boxes.nu[k], rate)
            pos_l.append(pos)
            d_l.append(d)
            lay_l.append(np.full(len(d), k, dtype=np.int64))
        pos, d, lay = np.concatenate(pos_l), np.concatenate(d_l), np.concatenate(lay_l)
        n = len(d)
        upd.candidates = n
        if n == 0:
            return
        speed_w = float(np.hypot(wind[0], wind[2]))
        u = np.zeros((n, 3))
        u[:, 0] = wind[0]
        u[:, 2] = wind[2]
        if speed_w > 0:
            u[:, [0, 2]] += self.rng.normal(0.0, TURBULENCE * speed_w, (n, 2))
        u[:, 1] = -physics.terminal_velocity(d)
        keep, life = self.fate(pos, u, boxes, inp.vehicles)
        upd.rejected = int(n - keep.sum())
        idx = np.flatnonzero(keep)
        if idx.size > self.pool.n_free:
            upd.overflow = int(idx.size - self.pool.n_free)
            self.pool.overflow += upd.overflow
            idx = np.sort(self.rng.permutation(idx)[: self.pool.n_free])
        slots = self.pool.allocate(idx.size)
        if slots.size == 0:
            return
        self.pos0[slots] = pos[idx]
        self.vel[slots] = u[idx]
        self.t0[slots] = t
        self.t_hit[slots] = t + life[idx]
        self.diameter[slots] = d[idx]
        self.weight[slots] = n_eff / kappa
        self.layer[slots] = lay[idx]
        self._schedule(slots, pos[idx], t, boxes, v_cam)
        upd.spawn_slots = slots
        upd.spawn_texels = self._pack(pos[idx], u[idx], t, life[idx], d[idx], n_eff / kappa, lay[idx])

    def texels(self, slots) -> np.ndarray:
        """The GPU record (n, 3, 4) float32 of slots: (x, y, z mod PERIOD_M, t0 mod TIME_PERIOD_S),
        (u_x, u_y, u_z, lifetime), (D mm, weight, layer, 0)."""
        slots = np.asarray(slots)
        return self._pack(self.pos0[slots], self.vel[slots], self.t0[slots], self.t_hit[slots] - self.t0[slots],
                          self.diameter[slots], self.weight[slots], self.layer[slots])

    @staticmethod
    def _pack(pos, vel, t0, life, d, weight, layer) -> np.ndarray:
        out = np.zeros((len(pos), 3, 4), dtype=np.float32)
        out[:, 0, 0:2] = pos[:, 0:2]
        out[:, 0, 2] = np.mod(pos[:, 2], PERIOD_M)
        out[:, 0, 3] = np.mod(t0, TIME_PERIOD_S)
        out[:, 1, 0:3] = vel
        out[:, 1, 3] = life
        out[:, 2, 0] = d
        out[:, 2, 1] = weight
        out[:, 2, 2] = layer
        return out

    # --- splashes ---

    def splash_rate_per_s(self, rate_mm_h: float, area_m2: float, density_scale: float = 1.0) -> tuple[float, float]:
        """(splashes drawn per s, real impacts each stands for) on area_m2 of open ground at R (mm/h)."""
        phys = density_scale * splash_flux_per_m2_s(rate_mm_h) * area_m2
        cap = 0.8 * self.splash_capacity / SPLASH_LIFE_S[1]
        ref = splash_flux_per_m2_s(BUDGET_FULL_AT_MM_H) * area_m2
        drawn = min(cap, phys * min(1.0, cap / ref)) if ref > 0 else 0.0
        return drawn, (phys / drawn if drawn > 0 else 0.0)

    def _spawn_splashes(self, t, span, boxes: Boxes, inp: RainInput, upd: RainUpdate) -> None:
        """Impacts during the last ``span`` seconds on the open ground of the splash layer's box."""
        rate = self.rate_eff
        if rate <= 0.0 or self.splash_capacity == 0:
            return
        lo, hi = boxes.lo[SPLASH_LAYER], boxes.hi[SPLASH_LAYER]
        area = float((hi[0] - lo[0]) * (hi[2] - lo[2]))
        per_s, weight = self.splash_rate_per_s(rate, area, inp.density_scale)
        n = min(int(self.rng.poisson(per_s * span)), self.splash_capacity)
        if n == 0:
            return
        rng = self.rng
        x = lo[0] + rng.random(n) * (hi[0] - lo[0])
        z = lo[2] + rng.random(n) * (hi[2] - lo[2])
        t_imp = t - rng.random(n) * span
        open_ = np.ones(n, dtype=bool)
        if self.world is not None and hasattr(self.world, "occluder_height"):
            open_ &= ~np.isfinite(np.asarray(self.world.occluder_height(x, z)))
        for veh in inp.vehicles:
            c = np.asarray(veh.position, dtype=np.float64)
            rx, rz = x - c[0], wrap_near(z - c[2], 0.0)
            cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
            lx, lz = cy * rx - sy * rz, sy * rx + cy * rz
            open_ &= ~((np.abs(lx) < veh.spec.width_m / 2 + 0.05) & (np.abs(lz) < veh.spec.length_m / 2 + 0.05))
        # Splashing drops: D ≥ SPLASH_D_MIN_MM, impacts ∝ N(D)·v(D) (rejection on v).
        lam = physics.mp_slope_per_mm(rate)
        d = _sample_truncated_exp(rng, lam, SPLASH_D_MIN_MM, physics.D_MAX_MM, 4 * n)
        d = d[rng.random(d.size) * physics.terminal_velocity(physics.D_MAX_MM) < physics.terminal_velocity(d)]
        if d.size < n:
            d = np.concatenate([d, np.full(n - d.size, SPLASH_D_MIN_MM)])
        d = d[:n]
        kerb = (np.abs(x) >= layout.ROAD_HALF_WIDTH_M) & (np.abs(x) <= layout.ROAD_HALF_WIDTH_M
                                                          + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M)
        y = np.where(kerb, layout.KERB_HEIGHT_M, GROUND_Y_M)
        on_road = np.abs(x) < layout.ROAD_HALF_WIDTH_M
        if self.world is not None and hasattr(self.world, "road_height01"):
            puddle = on_road & (np.asarray(self.world.road_height01(x, z)) < inp.puddles)
        else:
            puddle = np.zeros(n, dtype=bool)
        kind = np.where(puddle, TYPE_PUDDLE_CROWN, np.where(inp.wetness >= 0.3, TYPE_FILM_CROWN, TYPE_PROMPT))
        life = splash_life_s(d)
        keep = np.flatnonzero(open_)
        m = keep.size
        if m == 0:
            return
        slots = (self.splash_head + np.arange(m)) % self.splash_capacity
        self.splash_head = int((self.splash_head + m) % self.splash_capacity)
        self.splash_t0[slots] = t_imp[keep]
        self.splash_life[slots] = life[keep]
        self.splash_pos[slots] = np.stack([x[keep], y[keep], z[keep]], axis=1)
        self.splash_weight[slots] = weight
        data = np.zeros((m, 8), dtype=np.float32)
        data[:, 0] = x[keep]
        data[:, 1] = y[keep]
        data[:, 2] = np.mod(z[keep], PERIOD_M)
        data[:, 3] = np.mod(t_imp[keep], TIME_PERIOD_S)
        data[:, 4] = d[keep]
        data[:, 5] = life[keep]
        data[:, 6] = kind[keep] + 0.999 * rng.random(m)  # type + a seed for the droplet pattern
        data[:, 7] = weight
        upd.splash_slots = slots
        upd.splash_data = data


# --- measurements shared by tests and the benchmark ---------------------------------------------------------


def drop_weights(sim: RainfallSim, slots, p: np.ndarray, boxes: Boxes) -> np.ndarray:
    """Real drops each of ``slots`` (at positions p, m) stands for: a·m_own/max(Σν·m, ν_outer). Mirrors the
    shader; 0 outside its box."""
    slots = np.asarray(slots)
    return sim.weight[slots] * membership(p, boxes, sim.layer[slots]) / drawn_density_factor(p, boxes)


def weighted_count(sim: RainfallSim, time_s: float, lo, hi) -> tuple[float, int]:
    """(Σ weights, number of drawn drops) of the live drops inside the box [lo, hi] (m, world) at time_s."""
    slots = np.flatnonzero(sim.pool.alive)
    if slots.size == 0 or sim.boxes is None:
        return 0.0, 0
    p = sim.positions(slots, time_s)
    centre_z = 0.5 * (lo[2] + hi[2])
    p[:, 2] = wrap_near(p[:, 2], centre_z)
    live = time_s < sim.t_hit[slots]
    inside = live & np.all((p >= lo) & (p <= hi), axis=1)
    w = drop_weights(sim, slots[inside], p[inside], sim.boxes)
    return float(w.sum()), int(inside.sum())


def full_region(boxes: Boxes, layer: int = -1) -> tuple[np.ndarray, np.ndarray]:
    """The part of a layer's box (default the outer one) where no fade applies (m, world): lo, hi."""
    lo = boxes.lo[layer] + boxes.fade[layer] * np.array([1.0, 0.0, 1.0])
    hi = boxes.hi[layer] - boxes.fade[layer]
    lo = lo.copy()
    lo[1] = GROUND_Y_M
    return lo, hi


# --- the NumPy twin of the streak shader ---------------------------------------------------------------------


@dataclass
class StreakCamera:
    """What the streak shader knows of the camera: view_proj (4×4, wrapped frame), position (m, wrapped),
    shift_z (m), velocity (m/s), exposure (s), viewport (px), near plane (m)."""

    view_proj: np.ndarray
    position: np.ndarray
    shift_z: float
    velocity: np.ndarray
    exposure_s: float
    viewport: tuple[int, int]
    near_m: float = 0.05

    @property
    def focal_px(self) -> float:
        """Pixels per unit tan(angle), vertically (view_proj[1, 1] equals the projection's since the view has no
        scale)."""
        return float(np.linalg.norm(self.view_proj[1, :3])) * self.viewport[1] / 2.0


def streak_geometry(sim: RainfallSim, slots, time_s: float, cam: StreakCamera, boxes: Boxes,
                    brightness: float = 1.0) -> dict[str, np.ndarray]:
    """The streaks of ``slots`` as ``shaders/rainfall_streak.vert`` draws them, in float64.

    Returns arrays: ``visible`` (bool), ``head``/``tail`` (n, 3) m in the wrapped frame (the drop now, and where
    it was relative to the camera when the shutter opened), ``head_px``/``tail_px`` (n, 2) px from the image
    centre (y up), ``width_px``, ``alpha``, ``light_px2`` (the light budget: weight × projected area) and
    ``drawn_px2`` (what the quad carries: alpha × width × (length + width))."""
    slots = np.asarray(slots)
    tex = sim.texels(slots).astype(np.float64)
    s0, s1, s2 = tex[:, 0], tex[:, 1], tex[:, 2]
    age = np.mod(np.float32(np.mod(time_s, TIME_PERIOD_S)) - s0[:, 3], TIME_PERIOD_S)
    age = np.where(age > 0.5 * TIME_PERIOD_S, 0.0, age)
    life = s1[:, 3]
    cam_z = cam.position[2]
    p0 = np.stack([s0[:, 0], s0[:, 1], s0[:, 2] - PERIOD_M * np.floor((s0[:, 2] - cam_z) / PERIOD_M + 0.5)], axis=1)
    u = s1[:, :3]
    age_head = np.minimum(age, life)
    head = p0 + u * age_head[:, None]
    wrapped = Boxes(boxes.lo - [0.0, 0.0, cam.shift_z], boxes.hi - [0.0, 0.0, cam.shift_z], boxes.fade, boxes.nu)
    layer = (s2[:, 2] + 0.5).astype(np.int64)
    weight = s2[:, 1] * membership(head, wrapped, layer) / drawn_density_factor(head, wrapped)
    a_w = head + cam.velocity * (age - age_head)[:, None]
    b_w = p0 + u * (age - cam.exposure_s)[:, None] + cam.velocity * cam.exposure_s
    ca = np.c_[a_w, np.ones(len(a_w))] @ cam.view_proj.T
    cb = np.c_[b_w, np.ones(len(b_w))] @ cam.view_proj.T
    wmin = cam.near_m * 1.01
    visible = (life > 0) & (age - cam.exposure_s <= life) & (weight > 0) & ~((ca[:, 3] < wmin) & (cb[:, 3] < wmin))
    with np.errstate(divide="ignore", invalid="ignore"):
        fa = np.where(ca[:, 3] < wmin, (wmin - ca[:, 3]) / (cb[:, 3] - ca[:, 3]), 0.0)[:, None]
        ca = np.where(fa > 0, ca + (cb - ca) * fa, ca)
        fb = np.where(cb[:, 3] < wmin, (wmin - cb[:, 3]) / (ca[:, 3] - cb[:, 3]), 0.0)[:, None]
        cb = np.where(fb > 0, cb + (ca - cb) * fb, cb)
        half = 0.5 * np.asarray(cam.viewport, dtype=np.float64)
        sa = ca[:, :2] / ca[:, 3:4] * half
        sb = cb[:, :2] / cb[:, 3:4] * half
    length = np.linalg.norm(sb - sa, axis=1)
    d_px = s2[:, 0] * 1e-3 * cam.focal_px / ca[:, 3]
    area_f, width_f = drop_shape_factors(s2[:, 0])
    light = np.pi / 4.0 * d_px**2 * area_f * weight * brightness
    w = np.maximum(d_px * width_f, WIDTH_FLOOR_PX)
    alpha = light / (w * (length + w))
    over = alpha > ALPHA_MAX
    wide = 0.5 * (-length + np.sqrt(length**2 + 4.0 * light / ALPHA_MAX))
    w = np.where(over, np.minimum(np.maximum(wide, w), WIDTH_MAX_PX), w)
    alpha = np.where(over, np.minimum(light / (w * (length + w)), ALPHA_MAX), alpha)
    return {"visible": visible, "head": head, "tail": b_w, "head_px": sa, "tail_px": sb, "width_px": w,
            "alpha": alpha, "light_px2": light, "drawn_px2": alpha * w * (length + w)}


# --- the effect (GL) ---------------------------------------------------------------------------------------


_SCATTER_DTYPE = np.dtype([("texel", "<i4"), ("value", "<f4", (4,))])


def _set(prog: moderngl.Program, name: str, value) -> None:
    if name not in prog:
        return
    if isinstance(value, bytes):
        prog[name].write(value)
    elif isinstance(value, np.ndarray):
        prog[name].write(np.ascontiguousarray(value, dtype=np.float32).tobytes())
    else:
        prog[name].value = value


class RainfallEffect(Effect):
    """Falling rain: streaks in the camera-following container and impact splashes (module docstring).

    ctx: moderngl context; shaders: a ShaderLibrary (default: a new one); settings: the Settings used when a frame
    carries none; seed: seeds the drops. Draws in the ``transparent`` stage; texture unit 8 holds the drop state.
    Reads frame.settings.rainfall (enabled, density_scale, streak_brightness, splashes, container_m),
    quality.particle_budget, camera.exposure_s and camera.mode (driver/chase: the camera moves with the ego car;
    free: its velocity is the finite difference of its positions)."""

    name = "rainfall"
    stages = ("transparent",)

    def __init__(self, ctx: moderngl.Context, shaders=None, settings=None, seed: int = 0):
        from rain_core.gl import ShaderLibrary
        from rain_core.settings import Settings

        self.ctx = ctx
        self.shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        self.settings = settings if settings is not None else Settings()
        self.seed = int(seed)
        layers = {"LAYERS": len(LAYER_SCALES)}
        self.streak_prog = self.shaders.program("rainfall/streak.vert", "rainfall/streak.frag", defines=layers)
        self.splash_prog = self.shaders.program("rainfall/splash.vert", "rainfall/splash.frag")
        self.scatter_prog = self.shaders.program("rainfall/scatter.vert", "rainfall/scatter.frag")
        self.env_prog = self.shaders.program("common/fullscreen.vert", "rainfall/env.frag")
        self._streak_vao = ctx.vertex_array(self.streak_prog, [])
        self._env_vao = ctx.vertex_array(self.env_prog, [])
        self._env_tex = ctx.texture(ENV_SIZE, 4, dtype="f2")
        self._env_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._env_tex.repeat_x, self._env_tex.repeat_y = True, False
        self._env_fbo = ctx.framebuffer(color_attachments=[self._env_tex])
        self.sim: RainfallSim | None = None
        self._world = None
        self._generation = None
        self._state_tex = self._state_fbo = None
        self._scatter_buf = self._scatter_vao = None
        self._splash_buf = self._splash_vao = None
        self._prev_cam: tuple[np.ndarray, float] | None = None
        self.camera_velocity_m_s = np.zeros(3)
        self.last_update: RainUpdate | None = None
        area, width = drop_shape_factors(np.concatenate([[1.0], _BC_D_MM]))
        self._shape_area = area.astype(np.float32)
        self._shape_width = width.astype(np.float32)

    # --- settings and resources ---

    def describe(self) -> str:
        upd = self.last_update
        if upd is None:
            return ""
        return f"{self.sim.live} drops alive, {len(upd.spawn_slots)} spawned, {upd.rejected} under roofs"

    def _settings(self, frame):
        return frame.settings if frame.settings is not None else self.settings

    def _ensure(self, capacity: int, world) -> None:
        if self.sim is not None and self.sim.capacity == capacity and self._world is world:
            return
        self._release_buffers()
        self.sim = RainfallSim(capacity, seed=self.seed, world=world)
        self._world = world
        rows = max(1, -(-capacity // DROPS_PER_ROW))
        self._state_tex = self.ctx.texture((DROPS_PER_ROW * TEXELS_PER_DROP, rows), 4, dtype="f4")
        self._state_tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._state_fbo = self.ctx.framebuffer(color_attachments=[self._state_tex])
        self._splash_buf = self.ctx.buffer(reserve=self.sim.splash_capacity * 32)
        self._splash_vao = self.ctx.vertex_array(self.splash_prog, [(self._splash_buf, "4f 4f/i", "in_a", "in_b")])
        self._generation = None

    def _release_buffers(self) -> None:
        for obj in (self._state_fbo, self._state_tex, self._scatter_vao, self._scatter_buf, self._splash_vao,
                    self._splash_buf):
            if obj is not None:
                obj.release()
        self._state_tex = self._state_fbo = self._scatter_buf = self._scatter_vao = None
        self._splash_buf = self._splash_vao = None

    def _clear_gpu(self) -> None:
        self._state_fbo.clear(0.0, 0.0, 0.0, 0.0)
        self._splash_buf.write(bytes(self._splash_buf.size))

    # --- Effect API ---

    def active(self, frame) -> bool:
        s = self._settings(frame)
        if not s.rainfall.enabled or s.quality.particle_budget <= 0:
            if self.sim is not None and self.sim.t_prev is not None:
                self.sim.reset()
            self._prev_cam = None
            return False
        if frame.rain_rate_mm_h > 0.0:
            return True
        sim = self.sim
        return sim is not None and (sim.rate_eff > 0.0 or sim.live > 0 or sim.splashes_live(frame.time_s) > 0)

    def camera_velocity(self, frame) -> np.ndarray:
        """Velocity (m/s, world) of the camera: the ego car's at the camera point (with its yaw rate) for the
        driver and chase cameras, else the finite difference of the camera's positions over time."""
        s = self._settings(frame)
        pos = np.asarray(frame.camera.position, dtype=np.float64)
        ego = frame.ego
        if ego is not None and s.camera.mode in ("driver", "chase"):
            rel = pos - np.asarray(ego.position, dtype=np.float64)
            rel[2] = wrap_near(rel[2], 0.0)
            v = np.asarray(ego.velocity(), dtype=np.float64).copy()
            omega = float(getattr(ego, "yaw_rate_rad_s", 0.0))
            v[0] += omega * rel[2]
            v[2] -= omega * rel[0]
            return v
        prev = self._prev_cam
        if prev is None or frame.time_s <= prev[1]:
            return self.camera_velocity_m_s if prev is not None else np.zeros(3)
        step = pos - prev[0]
        step[2] = wrap_near(step[2], 0.0)
        v = step / (frame.time_s - prev[1])
        return v if np.linalg.norm(v) < 100.0 else self.camera_velocity_m_s  # a jump is a cut, not motion

    def update(self, frame, rc) -> None:
        s = self._settings(frame)
        self._ensure(int(s.quality.particle_budget), frame.world)
        v_cam = self.camera_velocity(frame)
        weather = frame.weather
        wind = np.asarray(weather.wind.velocity_m_s if weather is not None else (0.0, 0.0, 0.0), dtype=np.float64)
        inp = RainInput(time_s=frame.time_s, camera_position=np.asarray(frame.camera.position, dtype=np.float64),
                        camera_forward=np.asarray(frame.camera.forward, dtype=np.float64), camera_velocity=v_cam,
                        rate_mm_h=frame.rain_rate_mm_h, wind_m_s=wind, container_m=s.rainfall.container_m,
                        density_scale=s.rainfall.density_scale, splashes=s.rainfall.splashes,
                        wetness=getattr(weather, "wetness", 0.0), puddles=getattr(weather, "puddles", 0.0),
                        vehicles=tuple(frame.vehicles))
        upd = self.sim.advance(inp)
        if self._generation != self.sim.generation:
            self._clear_gpu()
            self._generation = self.sim.generation
        self._upload(upd)
        self.camera_velocity_m_s = v_cam
        if frame.time_s > (self._prev_cam[1] if self._prev_cam is not None else -math.inf):
            self._prev_cam = (np.asarray(frame.camera.position, dtype=np.float64).copy(), frame.time_s)
        self.last_update = upd

    def _upload(self, upd: RainUpdate) -> None:
        n_kill, n_new = upd.kill_slots.size, upd.spawn_slots.size
        if n_kill + n_new:
            rec = np.zeros(n_kill + 3 * n_new, dtype=_SCATTER_DTYPE)
            kill = upd.kill_slots
            rec["texel"][:n_kill] = self._texel(kill, 1)  # lifetime 0: culled (and never revived by the wrap)
            new = upd.spawn_slots
            for j in range(TEXELS_PER_DROP):
                part = rec[n_kill + j * n_new: n_kill + (j + 1) * n_new]
                part["texel"] = self._texel(new, j)
                part["value"] = upd.spawn_texels[:, j, :]
            data = rec.tobytes()
            if self._scatter_buf is None or self._scatter_buf.size < len(data):
                if self._scatter_vao is not None:
                    self._scatter_vao.release()
                    self._scatter_buf.release()
                self._scatter_buf = self.ctx.buffer(reserve=max(len(data), 1 << 16) * 2)
                self._scatter_vao = self.ctx.vertex_array(
                    self.scatter_prog, [(self._scatter_buf, "1i 4f", "in_texel", "in_value")])
            self._scatter_buf.write(data)
            self.ctx.disable(moderngl.BLEND)
            self.ctx.disable(moderngl.DEPTH_TEST)
            self._state_fbo.use()
            self.scatter_prog["u_size"].value = self._state_tex.size
            self._scatter_vao.render(moderngl.POINTS, vertices=len(rec))
        if upd.splash_slots.size:
            slots, data = upd.splash_slots, upd.splash_data
            cut = int(np.flatnonzero(np.diff(slots) != 1)[0]) + 1 if np.any(np.diff(slots) != 1) else slots.size
            for part_s, part_d in ((slots[:cut], data[:cut]), (slots[cut:], data[cut:])):
                if part_s.size:
                    self._splash_buf.write(np.ascontiguousarray(part_d).tobytes(), offset=int(part_s[0]) * 32)

    @staticmethod
    def _texel(slots: np.ndarray, j: int) -> np.ndarray:
        row = slots // DROPS_PER_ROW
        return (row * DROPS_PER_ROW * TEXELS_PER_DROP + TEXELS_PER_DROP * (slots - row * DROPS_PER_ROW) + j
                ).astype(np.int32)

    def streak_camera(self, rc) -> StreakCamera:
        """The camera as the streak shader sees it this frame (for the NumPy twin)."""
        s = self._settings(rc.frame)
        return StreakCamera(rc.view_proj, rc.camera_position, rc.shift_z, self.camera_velocity_m_s,
                            s.camera.exposure_s, rc.size, rc.frame.camera.near_m)

    def _lights(self, rc, boxes: Boxes) -> tuple:
        """rc.lights without the lights whose range cannot reach the outer box (wrapped frame)."""
        pos_b, dir_b, col_b, count = rc.lights
        pos = np.frombuffer(pos_b, np.float32).reshape(-1, 4)
        lo = boxes.lo[-1] - [0.0, 0.0, rc.shift_z]
        hi = boxes.hi[-1] - [0.0, 0.0, rc.shift_z]
        gap = np.maximum(np.maximum(lo - pos[:count, :3], pos[:count, :3] - hi), 0.0)
        keep = np.flatnonzero(np.linalg.norm(gap, axis=1) < np.abs(pos[:count, 3]))  # w < 0: a low beam
        out = []
        for buf in (pos_b, dir_b, col_b):
            arr = np.frombuffer(buf, np.float32).reshape(-1, 4)
            packed = np.zeros_like(arr)
            packed[: keep.size] = arr[keep]
            out.append(packed.tobytes())
        return (*out, int(keep.size))

    def _draw_environment(self, rc) -> None:
        rc.set_frame_uniforms(self.env_prog)
        self.ctx.disable(moderngl.BLEND)
        self.ctx.disable(moderngl.DEPTH_TEST)
        self._env_fbo.use()
        self._env_vao.render(moderngl.TRIANGLES, vertices=3)
        rc.hdr.fbo.use()

    def render(self, stage: str, rc) -> None:
        if stage != "transparent" or self.sim is None or self.sim.boxes is None:
            return
        s = self._settings(rc.frame)
        ctx = rc.ctx
        boxes = self.sim.boxes
        shift = np.array([0.0, 0.0, rc.shift_z])
        self._draw_environment(rc)
        lights = self._lights(rc, boxes)
        common = {
            "u_period_z": PERIOD_M, "u_time_mod": float(np.mod(rc.frame.time_s, TIME_PERIOD_S)),
            "u_time_period": TIME_PERIOD_S, "u_viewport": tuple(float(v) for v in rc.size),
            "u_focal_px": float(rc.projection[1, 1]) * rc.size[1] / 2.0,
            "u_brightness": float(s.rainfall.streak_brightness), "u_rain_env": ENV_UNIT,
            "u_light_pos": lights[0], "u_light_dir": lights[1], "u_light_color": lights[2],
            "u_light_count": lights[3],
        }
        self._env_tex.use(ENV_UNIT)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        rc.hdr.fbo.depth_mask = False
        try:
            count = self.sim.pool.high_water
            if count:
                prog = self.streak_prog
                rc.set_frame_uniforms(prog)
                for name, value in common.items():
                    _set(prog, name, value)
                values = {
                    "u_state": STATE_UNIT, "u_drops_per_row": DROPS_PER_ROW,
                    "u_cam_vel": tuple(self.camera_velocity_m_s), "u_exposure_s": float(s.camera.exposure_s),
                    "u_near": float(rc.frame.camera.near_m), "u_box_lo": boxes.lo - shift,
                    "u_box_hi": boxes.hi - shift, "u_box_fade": boxes.fade, "u_layer_nu": boxes.nu,
                    "u_shape_area": self._shape_area, "u_shape_width": self._shape_width,
                    "u_width_floor_px": WIDTH_FLOOR_PX, "u_width_max_px": WIDTH_MAX_PX, "u_alpha_max": ALPHA_MAX,
                }
                for name, value in values.items():
                    _set(prog, name, value)
                self._state_tex.use(STATE_UNIT)
                self._streak_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=count)
            if s.rainfall.splashes and self.sim.splashes_live(rc.frame.time_s):
                prog = self.splash_prog
                rc.set_frame_uniforms(prog)
                for name, value in common.items():
                    _set(prog, name, value)
                _set(prog, "u_crown_per_d", SPLASH_CROWN_HEIGHT_PER_D)
                _set(prog, "u_splash_alpha_max", ALPHA_MAX)
                self._splash_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.sim.splash_capacity)
        finally:
            rc.hdr.fbo.depth_mask = True
            ctx.disable(moderngl.BLEND)
            ctx.blend_func = moderngl.DEFAULT_BLENDING

    def release(self) -> None:
        self._release_buffers()
        for obj in (self._streak_vao, self._env_vao, self._env_fbo, self._env_tex):
            obj.release()


def make_rainfall(ctx: moderngl.Context, settings=None, shaders=None, seed: int = 0) -> RainfallEffect:
    """The rainfall effect for ``ctx`` (see RainfallEffect)."""
    return RainfallEffect(ctx, shaders=shaders, settings=settings, seed=seed)
