"""The wet road (DESIGN §3 "Wet road"): wet BRDF, water in cracks and puddles, wind waves, planar reflections.

One model, two implementations: the scalar parts live here in NumPy (float64, the reference) and in
``shaders/common/road_film.glsl`` / ``road_surface.glsl`` (what the scene shader runs). ``test_road.py`` checks
that the constants agree and that :func:`film_depth_mm` matches the GLSL on a grid of points.

Surface model
-------------
* **Wet material** (every lit surface the rain reaches; Lagarde's game-engine form): albedo × lerp(1, 0.3, w·p)
  with p the material's porosity (asphalt 1, painted markings and metal much less), smoothness × lerp(1, 2.5, w)
  capped at 1. w is the weather's wetness times the surface's exposure: up-facing 1, vertical 0.4, facing down
  0, and 0 under a roof (the bridge deck, the fuel-station canopy; from the world's occluder map).
* **Water film**: on a wet surface a thin water layer (F0 = 0.02, roughness :data:`FILM_ROUGHNESS` — it follows
  the asphalt's macrotexture) covers a fraction w·c of it (c per material). Under water the base's own
  specular is that of an asphalt–water interface (F0 ≈ 0.004). The layer is added energy-correctly:
  L = (1 − c·F)·L_base + c·(F·L_reflected + specular of the lights), F the split-sum Fresnel of the layer.
* **Standing water** from the road heightmap h (0 lowest: cracks ≈ 0–0.35, ruts ≈ 0.5–0.65, lane centres
  0.7–0.85), the same map smoothed over PUDDLE_GROUND_SIGMA_M (h_s, without the cracks), and a seeded noise
  map n ∈ [0, 1] (uniform; periodic in 1200 m so it never tiles visibly). Cracks hold
  ``CRACK_MAX_MM · clamp((cracks · CRACK_LEVEL − h) / CRACK_DEPTH_SPAN, 0, 1)`` mm (they fill and dry with
  the fast level). Puddles lie where the blended ground ``g = (1 − K)·h_s + K·n`` is below the slow level
  ``L = PUDDLE_LEVEL_MAX · (puddles · puddle_amount)^PUDDLE_LEVEL_EXPONENT`` and hold
  ``PUDDLE_MAX_MM · clamp((L − g) / PUDDLE_DEPTH_SPAN, 0, 1)`` mm: they follow the ruts and low spots, and
  the noise decides which stretch of rut floods. The wet film itself is ``WET_FILM_MM · wetness`` mm.
  Under standing water the asphalt is soaked: the wet material uses max(w, coverage).
* **Coverage**: standing water shallower than the asphalt's macrotexture (:data:`MACROTEXTURE_MM`) only fills
  the pores (the *drenched* margin: darker, glossier, still textured); deeper water is a full water surface
  (the *puddle*: normal up + wind waves + ripples, a mirror). Coverage = clamp(standing / MACROTEXTURE_MM, 0, 1),
  so every puddle has a soft margin whose width follows the ground's slope.
* The four regions (the debug view colours them): dry, wet (film only), drenched (0 < coverage < 1), puddle
  (coverage 1).

Reflections and lights
----------------------
* The ``prepare`` pass draws the scene mirrored about y = 0 (view × diag(1, −1, 1), clipped below the road,
  at ``reflection_scale`` of the frame, mipmapped). The water samples it where its mirrored reflected ray
  projects, so wave and ripple normals distort it; a rough film blurs it over the GGX lobe, ±α vertically and
  ±α·cosθ across (vertical smears at grazing angles, as on wet streets). Where that ray leaves the texture (or
  off the road plane) the sky takes over.
* The sun, lamps and headlights reach the water as GGX highlights of the layer (roughness ≥
  LIGHT_MIN_ROUGHNESS): the long streaks of lights on a wet road at night. Their lenses are drawn dim in the
  reflection pass so they are not counted twice (emissive albedo above LIGHT_SOURCE_RADIANCE).
* Murky water: under standing water the base is tinted by MURK_TINT^(depth/10 mm) (brownish grey, low
  saturation) and darker with depth; the reflection is only the Fresnel share — puddles stay dull rather than
  shiny and colourful.

Frames: x across the road (m, |x| ≤ 7 is asphalt), z along it (m, any world z: every map here is periodic in
``layout.PERIOD_M``, so world z and the renderer's wrapped z give the same values).
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache

import moderngl
import numpy as np

from rain_core import layout
from rain_core.camera import Camera
from rain_core.mesh import (
    MAT_ASPHALT,
    MAT_CAR_PAINT,
    MAT_CONCRETE,
    MAT_EMISSIVE,
    MAT_FOLIAGE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_PAINT,
    MAT_RUBBER,
)
from rain_core.renderer import Effect, Frame, RenderContext
from rain_core.world import sample_heightmap

# --- the model's constants (shaders/common/road_film.glsl and road_surface.glsl hold the same numbers) -----
WET_ALBEDO_FACTOR = 0.3  # albedo × lerp(1, this, w·porosity)
WET_SMOOTHNESS_GAIN = 2.5  # smoothness × lerp(1, this, w), capped at 1
WATER_F0 = 0.02  # water surface, IOR 1.33
UNDERWATER_F0 = 0.004  # asphalt/binder (IOR ~1.5) under water (IOR 1.33): ((1.5 − 1.33)/(1.5 + 1.33))²
FILM_ROUGHNESS = 0.32  # the wet film follows the asphalt macrotexture: calibrated for ×5–10 peak specular
WATER_ROUGHNESS = 0.04  # standing water: suspended dirt and micro-ripples keep it from a perfect mirror
LIGHT_MIN_ROUGHNESS = 0.1  # the lights' highlight on water: a point light has no size, the lamp lens has
WET_FILM_MM = 0.2  # mm, water film on a fully wet road (between the macrotexture peaks)
MACROTEXTURE_MM = 2.0  # mm, asphalt mean texture depth: deeper water is a full water surface
CRACK_MAX_MM = 3.0  # mm, deepest water in a crack
CRACK_LEVEL = 0.42  # height01 reached by the crack level at cracks = 1 (just above the cracks, below the ruts)
CRACK_DEPTH_SPAN = 0.2  # height01 below the crack level where a crack holds CRACK_MAX_MM
PUDDLE_MAX_MM = 10.0  # mm, puddles are shallow (DESIGN §3)
PUDDLE_NOISE_WEIGHT = 0.45  # K: share of the noise map in the puddle ground g = (1 − K)·h + K·n
PUDDLE_LEVEL_MAX = 0.56  # the puddle level at puddles = puddle_amount = 1 (about half the road under water)
PUDDLE_LEVEL_EXPONENT = 0.25  # level = MAX·(puddles·amount)^this: the low ground is a thin tail, so a
#                               linear level would flood almost nothing until the end, then everything
PUDDLE_DEPTH_SPAN = 0.35  # ground units below the level where a puddle is PUDDLE_MAX_MM deep
MURK_TINT = (0.62, 0.57, 0.50)  # transmittance of 10 mm of rain-water with road dirt (brownish grey)
WAVE_SLOPE_MAX = 0.07  # slope of the wind waves at wave_strength 1 in a WAVE_FULL_WIND_M_S wind
WAVE_FULL_WIND_M_S = 8.0  # m/s
WAVE_CALM_FRACTION = 0.2  # waves left in still air (rain, passing traffic)
MIRROR_CLIP_Y_M = 0.01  # m, the reflection pass keeps geometry above the road plane (markings are 4 mm)
LIGHT_SOURCE_RADIANCE = 2.0  # emissive albedo (×683 cd/m²) above which a surface is a lamp or headlight lens
MIRROR_LENS_FACTOR = 0.05  # lenses drawn this bright in the reflection: their light comes as highlights
ROAD_HALF_WIDTH_M = layout.ROAD_HALF_WIDTH_M
PUDDLE_MAP_CELL_M = 0.25  # m, noise and shelter map texels (x over the road width, z over a period)
SHELTER_MIN_HEIGHT_M = 0.5  # m, a roof higher than this above the road keeps the rain off it

# Per material: porosity (share of the wet darkening) and the water film coverage at full wetness.
MATERIAL_POROSITY = {MAT_GENERIC: 0.6, MAT_ASPHALT: 1.0, MAT_PAINT: 0.2, MAT_CONCRETE: 0.7, MAT_METAL: 0.0,
                     MAT_GLASS: 0.0, MAT_FOLIAGE: 0.4, MAT_EMISSIVE: 0.0, MAT_CAR_PAINT: 0.0, MAT_RUBBER: 0.3}
MATERIAL_FILM = {MAT_GENERIC: 0.5, MAT_ASPHALT: 1.0, MAT_PAINT: 1.0, MAT_CONCRETE: 0.8, MAT_METAL: 0.6,
                 MAT_GLASS: 0.0, MAT_FOLIAGE: 0.3, MAT_EMISSIVE: 0.0, MAT_CAR_PAINT: 0.6, MAT_RUBBER: 0.5}

REGIONS = ("dry", "wet", "drenched", "puddle")
REGION_COLORS = ((0.55, 0.45, 0.25), (0.15, 0.55, 0.15), (0.95, 0.45, 0.05), (0.10, 0.30, 1.00))
WET_MIN = 0.02  # wetness below this counts as dry in the region view

# Texture units of this effect (DESIGN: effects use units ≥ 4).
UNIT_HEIGHT, UNIT_MAPS, UNIT_REFLECTION, UNIT_RIPPLES = 4, 5, 6, 7
UNIT_RAIN_RINGS = 3  # the renderer itself only uses unit 0


# --- wet material (NumPy twin of road_wet_material in road_surface.glsl) ---------------------------------

def wet_material(albedo, roughness, wetness, material: int = MAT_ASPHALT) -> tuple[np.ndarray, np.ndarray]:
    """Albedo (linear RGB, any shape ending in 3 or scalar) and perceptual roughness of a surface at wetness w
    in [0, 1]: albedo × lerp(1, 0.3, w·porosity), smoothness = 1 − roughness × lerp(1, 2.5, w) capped at 1
    (roughness floored at 0.02 like the scene shader)."""
    w = np.clip(np.asarray(wetness, dtype=np.float64), 0.0, 1.0)
    p = MATERIAL_POROSITY.get(int(material), MATERIAL_POROSITY[MAT_GENERIC])
    alb = np.asarray(albedo, dtype=np.float64) * (1.0 + (WET_ALBEDO_FACTOR - 1.0) * w * p)
    smooth = np.minimum(1.0, (1.0 - np.asarray(roughness, dtype=np.float64)) * (1.0 + (WET_SMOOTHNESS_GAIN - 1) * w))
    return alb, np.maximum(1.0 - smooth, 0.02)


# --- maps ------------------------------------------------------------------------------------------------

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
    nz = int(round(layout.PERIOD_M / PUDDLE_MAP_CELL_M))
    nx = int(round(2 * ROAD_HALF_WIDTH_M / PUDDLE_MAP_CELL_M))
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x70AD]))
    field = _periodic_smooth_noise(rng, (nz, nx), 6.0) + 0.35 * _periodic_smooth_noise(rng, (nz, nx), 1.5)
    ranks = np.empty(field.size)
    ranks[np.argsort(field, axis=None, kind="stable")] = (np.arange(field.size) + 0.5) / field.size
    return ranks.reshape(nz, nx).astype(np.float32)


def shelter_map(world) -> np.ndarray:
    """Where roofs keep the rain off the road, float32 in [0, 1] on the puddle-map grid (1 = fully under a
    roof higher than SHELTER_MIN_HEIGHT_M; edges softened over ~0.5 m as blown rain reaches a little under)."""
    nz = int(round(layout.PERIOD_M / PUDDLE_MAP_CELL_M))
    nx = int(round(2 * ROAD_HALF_WIDTH_M / PUDDLE_MAP_CELL_M))
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


def sample_road_map(grid: np.ndarray, x, z) -> np.ndarray:
    """Bilinear sample of a puddle-map grid (rows z over PERIOD_M, columns x over the road) at x, z (m),
    exactly as a GL LINEAR texture clamped across x and repeated along z (u = (x + 7)/14, v = z/PERIOD_M)."""
    return sample_heightmap(grid, (2 * ROAD_HALF_WIDTH_M, layout.PERIOD_M), x, z)


PUDDLE_GROUND_SIGMA_M = 0.15  # m: puddles see the road's shape, not its cracks (the crack level fills those)


def smooth_heightmap(hmap: np.ndarray, sigma_m: float = PUDDLE_GROUND_SIGMA_M) -> np.ndarray:
    """The road heightmap blurred by a Gaussian of sigma_m (m): wraps along z, clamps across x (like its
    texture). The puddles' ground: a 5 cm crack does not cut a puddle's soft margin into a hard edge."""
    from rain_core.world import HEIGHTMAP_TEXEL_M

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
def _smooth_for(world) -> np.ndarray:
    return smooth_heightmap(world.road_heightmap)


@lru_cache(maxsize=1)
def _default_world():
    from rain_core.world import build_world

    return build_world(seed=1)


@lru_cache(maxsize=4)
def _shelter_for(world) -> np.ndarray:
    return shelter_map(world)


# --- standing water (NumPy twin of road_film.glsl) --------------------------------------------------------

def _standing_water_mm(h, h_smooth, n, shelter, cracks, puddles, puddle_amount):
    crack = CRACK_MAX_MM * np.clip((cracks * CRACK_LEVEL - h) / CRACK_DEPTH_SPAN, 0.0, 1.0)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * h_smooth + PUDDLE_NOISE_WEIGHT * n
    level = PUDDLE_LEVEL_MAX * (puddles * puddle_amount) ** PUDDLE_LEVEL_EXPONENT
    puddle = PUDDLE_MAX_MM * np.clip((level - ground) / PUDDLE_DEPTH_SPAN, 0.0, 1.0)
    return np.maximum(crack, puddle) * (1.0 - shelter)


def _levels(cracks, puddles, puddle_amount, wetness):
    vals = []
    for name, v in (("cracks", cracks), ("puddles", puddles), ("puddle_amount", puddle_amount),
                    ("wetness", wetness)):
        v = float(v)
        if not (0.0 <= v <= 1.0):
            raise ValueError(f"{name} must be in [0, 1], got {v!r}")
        vals.append(v)
    return vals


def water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, world=None, wetness=0.0):
    """(standing water, film) depths in mm at road points x, z (m; arrays broadcast): standing water in cracks
    and puddles, and the wet film WET_FILM_MM·wetness. Both 0 off the asphalt (|x| > 7 m) and under roofs."""
    cracks, puddles, puddle_amount, wetness = _levels(cracks, puddles, puddle_amount, wetness)
    world = world if world is not None else _default_world()
    x = np.asarray(x_m, dtype=np.float64)
    z = np.asarray(z_m, dtype=np.float64)
    x, z = np.broadcast_arrays(x, z)
    h = sample_heightmap(world.road_heightmap, world.heightmap_extent_m, x, z)
    h_smooth = sample_heightmap(_smooth_for(world), world.heightmap_extent_m, x, z)
    n = sample_road_map(puddle_noise(int(seed)), x, z)
    shelter = sample_road_map(_shelter_for(world), x, z)
    on_road = np.abs(x) <= ROAD_HALF_WIDTH_M
    standing = np.where(on_road, _standing_water_mm(h, h_smooth, n, shelter, cracks, puddles, puddle_amount),
                        0.0)
    film = np.where(on_road, WET_FILM_MM * wetness * (1.0 - shelter), 0.0)
    return standing, film


def film_depth_mm(x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, world=None, wetness=0.0) -> np.ndarray:
    """Water film depth (mm, ≤ PUDDLE_MAX_MM = 10) on the road at x, z (m; vectorised, any world z).

    cracks, puddles: the weather's two flood levels in [0, 1]; puddle_amount in [0, 1] (settings.road): how much
    of the road can hold puddles; seed: the puddle noise map's seed (settings.road.puddle_seed); world: gives
    the road heightmap and the roofs (None: the default street, ``build_world(seed=1)``); wetness in [0, 1]
    adds the thin film of a wet road (WET_FILM_MM at 1; default 0 = standing water only). 0 off the asphalt
    (|x| > 7 m) and under roofs. The GLSL twin is ``road_film_depth_mm`` in shaders/common/road_film.glsl.
    """
    standing, film = water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount, seed, world, wetness)
    return np.maximum(standing, film)


def water_coverage(standing_mm) -> np.ndarray:
    """Share of the surface under a continuous water surface, from the standing depth (mm): the water drowns
    the asphalt macrotexture linearly up to MACROTEXTURE_MM."""
    return np.clip(np.asarray(standing_mm, dtype=np.float64) / MACROTEXTURE_MM, 0.0, 1.0)


def road_regions(x_m, z_m, wetness, cracks, puddles, puddle_amount=0.5, seed=0, world=None) -> np.ndarray:
    """Region index per point (0 dry, 1 wet, 2 drenched, 3 puddle; see REGIONS), as the debug view colours
    the road surface."""
    standing, _ = water_depths_mm(x_m, z_m, cracks, puddles, puddle_amount, seed, world, wetness)
    world = world if world is not None else _default_world()
    shelter = sample_road_map(_shelter_for(world), x_m, z_m)
    cover = water_coverage(standing)
    wet = float(wetness) * (1.0 - shelter) >= WET_MIN
    return np.where(cover >= 1.0, 3, np.where(cover > 0.0, 2, np.where(wet, 1, 0))).astype(np.int8)


def crack_level(cracks: float) -> float:
    """The crack flood level in height01 units (what the shader's u_road_levels.y holds)."""
    return float(cracks) * CRACK_LEVEL


def puddle_level(puddles: float, puddle_amount: float) -> float:
    """The puddle water level in ground units (u_road_levels.z): PUDDLE_LEVEL_MAX·(puddles·amount)^exponent."""
    return PUDDLE_LEVEL_MAX * (float(puddles) * float(puddle_amount)) ** PUDDLE_LEVEL_EXPONENT


def wave_parameters(wind_velocity_m_s, wave_strength: float) -> tuple[float, float, float]:
    """Wind ripples on standing water: (drift x, drift z) in m/s and the slope amplitude, for a wind velocity
    (m/s, world x, y, z) and settings.road.wave_strength in [0, 1]. Small ripples drift at a fraction of the
    wind (at most 0.35 m/s, the speed of capillary-gravity waves); the slope grows with the wind up to
    WAVE_FULL_WIND_M_S, and a calm share remains (rain, traffic)."""
    vx, _, vz = (float(v) for v in wind_velocity_m_s)
    speed = math.hypot(vx, vz)
    drift = min(0.35, 0.05 + 0.04 * speed)
    ux, uz = (vx / speed, vz / speed) if speed > 1e-6 else (0.0, -1.0)
    amp = float(wave_strength) * WAVE_SLOPE_MAX * (WAVE_CALM_FRACTION + (1.0 - WAVE_CALM_FRACTION)
                                                   * min(1.0, speed / WAVE_FULL_WIND_M_S))
    return ux * drift, uz * drift, amp


def mirror_about_road(camera: Camera) -> Camera:
    """The camera mirrored about the road plane y = 0 (position and forward; ``up`` stays +Y). Used for the
    reflection pass's lights and eye position; its view matrix is the original's times diag(1, −1, 1)."""
    flip = np.array([1.0, -1.0, 1.0])
    return dataclasses.replace(camera, position=np.asarray(camera.position, dtype=np.float64) * flip,
                               forward=np.asarray(camera.forward, dtype=np.float64) * flip,
                               up=np.array([0.0, 1.0, 0.0]), inside_car=False)


_MIRROR_Y = np.diag([1.0, -1.0, 1.0, 1.0])


def _release_target(ctx: moderngl.Context, target) -> None:
    """Release a RenderTarget without leaving moderngl bound to a deleted framebuffer (it would rebind that
    name after creating the next framebuffer: GL_INVALID_OPERATION): park on the default framebuffer first."""
    if target is not None:
        ctx.detect_framebuffer(0).use()
        target.release()


def _set(program, name: str, value) -> None:
    if name in program:
        if isinstance(value, bytes):
            program[name].write(value)
        else:
            program[name].value = value


class RoadEffect(Effect):
    """The wet road effect. ``RoadEffect(ctx, shaders=None, world=None, settings=None)``: world gives the road
    heightmap and the roofs (None: ``frame.world`` at the first update); settings are used when a frame
    carries none; shaders (a ShaderLibrary) only for ``film_depth_gpu`` (made on demand if None).

    Per frame: levels from ``frame.weather`` (wetness, cracks, puddles in [0, 1], pins already applied), the
    rest from ``settings.road``. ``active`` is False when the road is dry (all three levels 0) or the effect is
    disabled — then the scene shader's dry path runs and no reflection pass is drawn. The ``prepare`` stage
    draws the planar reflection (scene mirrored about y = 0, clipped below the road, at ``reflection_scale``
    of the frame, mipmapped for rough reflections). ``bind_scene`` feeds common/road_surface.glsl.

    Shared with other effects (DESIGN §1): ``update`` publishes ``rc.resources["film_depth_fn"]`` (x_m, z_m →
    standing water depth in mm, world z, at this frame's levels) and ``rc.resources["wet_film_depth_fn"]`` (the
    same plus the thin film of a wet road), and reads ``rc.resources["water_normals"]`` ((texture, origin_xz_m,
    extent_m) of ripple slopes) unless ``set_ripple_normals`` was called.
    """

    name = "road"
    stages = ("prepare",)

    def __init__(self, ctx: moderngl.Context, shaders=None, world=None, settings=None):
        self.ctx = ctx
        self.shaders = shaders  # only the film-depth evaluation needs its own program (made on demand)
        self.settings = settings
        self.world = None
        self._height_tex: moderngl.Texture | None = None
        self._shelter: np.ndarray | None = None
        self._maps_tex: moderngl.Texture | None = None
        self._maps_seed: int | None = None
        self._black = ctx.texture((1, 1), 4, np.zeros(4, np.float32).tobytes(), dtype="f4")
        self._reflection = None  # RenderTarget, created at the first reflection pass
        self._reflection_valid = False
        self._mirror_pass = False
        self._ripple_explicit = False
        self._ripple: tuple | None = None  # (texture, (origin x, origin z) world m, extent m)
        self._film_prog = None
        self._film_target = None
        self._levels = (0.0, 0.0, 0.0)
        self._road = None
        self._waves = (0.0, 0.0, 0.0)
        if world is not None:
            self.set_world(world)

    def set_world(self, world) -> None:
        """Take the road heightmap and roofs of ``world`` (done on the first update from ``frame.world`` when
        the constructor got none)."""
        if world is self.world:
            return
        hmap = np.ascontiguousarray(np.stack([world.road_heightmap, _smooth_for(world)], axis=-1), dtype=np.float32)
        for tex in (self._height_tex, self._maps_tex):
            if tex is not None:
                tex.release()
        self._height_tex = self.ctx.texture((hmap.shape[1], hmap.shape[0]), 2, hmap.tobytes(), dtype="f4")
        self._height_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._height_tex.repeat_x, self._height_tex.repeat_y = False, True
        self._shelter = _shelter_for(world)
        self._maps_tex = self._maps_seed = None
        self.world = world

    # --- settings and levels ---
    def _road_settings(self, frame: Frame):
        settings = frame.settings if frame.settings is not None else self.settings
        if settings is None:
            from rain_core.settings import RoadSection

            return RoadSection()
        return settings.road

    @staticmethod
    def levels(frame: Frame) -> tuple[float, float, float]:
        """(wetness, cracks, puddles) in [0, 1] from the frame's weather (0 without weather)."""
        weather = frame.weather
        if weather is None:
            return 0.0, 0.0, 0.0
        return tuple(min(max(float(getattr(weather, k)), 0.0), 1.0) for k in ("wetness", "cracks", "puddles"))

    def active(self, frame: Frame) -> bool:
        road = self._road_settings(frame)
        return bool(road.enabled) and (any(v > 0.0 for v in self.levels(frame)) or bool(road.debug_regions))

    def needs_reflection(self, frame: Frame) -> bool:
        """Whether this frame draws the reflection pass: reflections on, water on the road, not the debug view."""
        road = self._road_settings(frame)
        return (bool(road.enabled and road.reflections) and not road.debug_regions
                and any(v > 0.0 for v in self.levels(frame)))

    # --- textures ---
    def _maps(self, seed: int) -> moderngl.Texture:
        if self._maps_tex is None or self._maps_seed != seed:
            if self._maps_tex is not None:
                self._maps_tex.release()
            maps = np.ascontiguousarray(np.stack([puddle_noise(seed), self._shelter], axis=-1), dtype=np.float32)
            tex = self.ctx.texture((maps.shape[1], maps.shape[0]), 2, maps.tobytes(), dtype="f4")
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x, tex.repeat_y = False, True
            self._maps_tex, self._maps_seed = tex, seed
        return self._maps_tex

    def set_ripple_normals(self, texture, origin_xz_m=(0.0, 0.0), extent_m: float = 1.0) -> None:
        """Ripple slopes for the puddles' water normal: ``texture`` RG = (dh/dx, dh/dz) (an RGB normal map's
        first two channels are read the same way, so pass slopes), texel (0, 0) centred on world origin_xz_m
        (m), texel (n−1, n−1) on origin + extent_m (m), u along x, v along z; None removes them (flat water).
        Once called, this wins over ``rc.resources["water_normals"]``."""
        self._ripple_explicit = True
        self._ripple = None if texture is None else (texture, (float(origin_xz_m[0]), float(origin_xz_m[1])),
                                                     float(extent_m))

    def _need_world(self) -> None:
        if self.world is None:
            raise RuntimeError("RoadEffect has no world yet: pass one to the constructor or set_world, or render "
                               "a frame first")

    def bind_film_uniforms(self, program, wetness: float, cracks: float, puddles: float, puddle_amount: float,
                           seed: int, unit_height: int = UNIT_HEIGHT, unit_maps: int = UNIT_MAPS) -> None:
        """Bind the maps and levels of common/road_film.glsl on any program that includes it (spray, ripples):
        road_film_depth_mm(xz) then gives the film depth at wrapped-frame positions."""
        self._need_world()
        self._height_tex.use(unit_height)
        self._maps(int(seed)).use(unit_maps)
        _set(program, "u_road_height", unit_height)
        _set(program, "u_road_maps", unit_maps)
        _set(program, "u_road_levels", (float(wetness), crack_level(cracks), puddle_level(puddles, puddle_amount),
                                        0.0))
        _set(program, "u_road_height_extent", tuple(float(v) for v in self.world.heightmap_extent_m))

    def water_texture_params(self, frame: Frame | None = None) -> dict:
        """What a shader including common/road_film.glsl needs for this frame's water: textures (height, maps),
        their units and the uniform values (see bind_film_uniforms). Without a frame: the last update's levels."""
        self._need_world()
        road = self._road_settings(frame) if frame is not None else self._road
        w, c, p = self.levels(frame) if frame is not None else self._levels
        amount = road.puddle_amount if road is not None else 0.5
        seed = int(road.puddle_seed) if road is not None else 0
        return {"height_texture": self._height_tex, "maps_texture": self._maps(seed),
                "units": {"u_road_height": UNIT_HEIGHT, "u_road_maps": UNIT_MAPS},
                "uniforms": {"u_road_levels": (w, crack_level(c), puddle_level(p, amount), 0.0),
                             "u_road_height_extent": tuple(float(v) for v in self.world.heightmap_extent_m)}}

    # --- per frame ---
    def update(self, frame: Frame, rc: RenderContext) -> None:
        if self.world is None:
            self.set_world(frame.world)
        road = self._road_settings(frame)
        self._road = road
        self._levels = w, c, p = self.levels(frame)
        self._maps(int(road.puddle_seed))
        wind = getattr(getattr(frame.weather, "wind", None), "velocity_m_s", (0.0, 0.0, 0.0))
        self._waves = wave_parameters(wind, road.wave_strength)
        amount, seed, world = float(road.puddle_amount), int(road.puddle_seed), self.world

        def standing(x_m, z_m):
            return film_depth_mm(x_m, z_m, c, p, amount, seed, world)

        def with_film(x_m, z_m):
            return film_depth_mm(x_m, z_m, c, p, amount, seed, world, wetness=w)

        rc.resources["film_depth_fn"] = standing
        rc.resources["wet_film_depth_fn"] = with_film
        self._reflection_valid = False

    def render(self, stage: str, rc: RenderContext) -> None:
        if stage == "prepare" and self.needs_reflection(rc.frame):
            self._render_reflection(rc)

    def _reflection_target(self, size: tuple[int, int]):
        from rain_core.gl import float_target

        if self._reflection is None or self._reflection.size != size:
            _release_target(self.ctx, self._reflection)
            self._reflection = float_target(self.ctx, size, 4, "f2", depth=True)
            self._reflection.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        return self._reflection

    def _render_reflection(self, rc: RenderContext) -> None:
        ctx = self.ctx
        scale = float(self._road_settings(rc.frame).reflection_scale)
        size = (max(1, round(rc.size[0] * scale)), max(1, round(rc.size[1] * scale)))
        target = self._reflection_target(size)
        mirror_frame = dataclasses.replace(rc.frame, camera=mirror_about_road(rc.frame.camera))
        mrc = rc.renderer.render_context(mirror_frame, target)
        # Same projection, view × mirror: a texel of the reflection lies exactly where the main camera sees the
        # road point that reflects it (mirroring flips the winding, hence front_face below).
        mrc.view = rc.view @ _MIRROR_Y
        mrc.projection = rc.projection
        mrc.resources = rc.resources
        active = [e for e in rc.renderer.effects if e is self or e.active(rc.frame)]
        target.fbo.use()
        target.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        ctx.disable(moderngl.CULL_FACE)
        ctx.front_face = "cw"
        self._mirror_pass = True
        try:
            rc.renderer.draw_scene(mrc, active, include_sky=True, clip_plane=(0.0, 1.0, 0.0, -MIRROR_CLIP_Y_M))
        finally:
            self._mirror_pass = False
            ctx.front_face = "ccw"
        target.color.build_mipmaps()
        self._reflection_valid = True

    def reflection_image(self) -> np.ndarray | None:
        """The last reflection pass as pre-exposed HDR float32 (H, W, 3), top row first (None if none ran)."""
        if self._reflection is None or not self._reflection_valid:
            return None
        data = self._reflection.fbo.read(components=3, dtype="f4", alignment=1)
        w, h = self._reflection.size
        return np.frombuffer(data, dtype=np.float32).reshape(h, w, 3)[::-1].copy()

    def _ripple_binding(self, rc: RenderContext):
        if self._ripple_explicit:
            return self._ripple
        shared = rc.resources.get("water_normals")
        if shared is None:
            return None
        if isinstance(shared, dict):
            return shared["texture"], tuple(shared["origin_xz_m"]), float(shared["extent_m"])
        texture, origin, extent = shared
        return texture, tuple(origin), float(extent)

    def bind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        road = self._road if self._road is not None else self._road_settings(rc.frame)
        w, c, p = self._levels
        self.bind_film_uniforms(program, w, c, p, road.puddle_amount, road.puddle_seed)
        _set(program, "u_road_wet", 1.0)
        _set(program, "u_road_mirror", 1.0 if self._mirror_pass else 0.0)
        _set(program, "u_road_debug", 1.0 if road.debug_regions else 0.0)
        _set(program, "u_road_reflection", UNIT_REFLECTION)
        _set(program, "u_road_ripples", UNIT_RIPPLES)
        if self._reflection_valid and not self._mirror_pass:
            self._reflection.color.use(UNIT_REFLECTION)
            _set(program, "u_road_reflect", 1.0)
        else:
            self._black.use(UNIT_REFLECTION)  # never the texture being drawn into
            _set(program, "u_road_reflect", 0.0)
        proj = rc.projection
        _set(program, "u_road_proj_scale", (0.5 * float(proj[0, 0]), 0.5 * float(proj[1, 1])))
        ripple = None if self._mirror_pass else self._ripple_binding(rc)
        if ripple is not None:
            texture, (ox, oz), extent = ripple
            texture.use(UNIT_RIPPLES)
            _set(program, "u_road_ripple_window", (ox, oz - rc.shift_z, extent, 1.0))
        else:
            self._black.use(UNIT_RIPPLES)
            _set(program, "u_road_ripple_window", (0.0, 0.0, 1.0, 0.0))
        rings = None if self._mirror_pass else rc.resources.get("rain_ripples")
        _set(program, "u_road_rain_rings", UNIT_RAIN_RINGS)
        if rings is not None:
            rings["texture"].use(UNIT_RAIN_RINGS)
            _set(program, "u_road_rain_rings_tile", (float(rings["tile_m"]), 1.0))
        else:
            self._black.use(UNIT_RAIN_RINGS)
            _set(program, "u_road_rain_rings_tile", (1.0, 0.0))
        _set(program, "u_road_waves", self._waves)
        ego = rc.frame.ego
        if rc.frame.camera.inside_car and ego is not None and not self._mirror_pass:
            from rain_core.car_mesh import windshield_frame

            model = ego.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            cowl = windshield_frame(ego.spec)["bottom_center"]
            _set(program, "u_road_cabin", np.ascontiguousarray(np.linalg.inv(model).T, dtype=np.float32).tobytes())
            _set(program, "u_road_cabin_box", (float(cowl[2]) + 0.02, 0.2, ego.spec.width_m / 2 + 0.05, 1.0))
        else:
            _set(program, "u_road_cabin_box", (0.0, 0.0, 0.0, 0.0))

    def unbind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        for name in ("u_road_wet", "u_road_mirror", "u_road_debug", "u_road_reflect"):
            _set(program, name, 0.0)

    # --- GPU twin of film_depth_mm ---
    def film_depth_gpu(self, x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, wetness=0.0) -> np.ndarray:
        """The shader's road_water_depths_mm at points x, z (m, arrays of one shape; world z): float32 array of
        shape (…, 2) = (standing water, wet film) in mm. For tests and for CPU-side users of the GPU model."""
        from rain_core.gl import float_target

        x = np.asarray(x_m, dtype=np.float64)
        z = np.asarray(z_m, dtype=np.float64)
        x, z = np.broadcast_arrays(x, z)
        shape = x.shape
        n = x.size
        width = min(n, 1024)
        height = (n + width - 1) // width
        pts = np.zeros((height * width, 2), dtype=np.float32)
        pts[:n, 0] = x.ravel()
        pts[:n, 1] = np.mod(z.ravel(), layout.PERIOD_M)  # the wrapped frame the shader works in
        if self._film_prog is None:
            if self.shaders is None:
                from rain_core.gl import ShaderLibrary

                self.shaders = ShaderLibrary(self.ctx)
            self._film_prog = self.shaders.program("common/fullscreen.vert", "road/film.frag")
            self._film_vao = self.ctx.vertex_array(self._film_prog, [])
        prog = self._film_prog
        target = self._film_target
        if target is None or target.size != (width, height):
            _release_target(self.ctx, self._film_target)
            target = self._film_target = float_target(self.ctx, (width, height), 4, "f4", filter_linear=False)
        points = self.ctx.texture((width, height), 2, pts.tobytes(), dtype="f4")
        points.filter = (moderngl.NEAREST, moderngl.NEAREST)
        try:
            self.bind_film_uniforms(prog, wetness, cracks, puddles, puddle_amount, seed)
            points.use(0)
            _set(prog, "u_points", 0)
            self.ctx.disable(moderngl.BLEND)
            self.ctx.disable(moderngl.DEPTH_TEST)
            target.fbo.use()
            self._film_vao.render(moderngl.TRIANGLES, vertices=3)
            out = np.frombuffer(target.fbo.read(components=4, dtype="f4", alignment=1), dtype=np.float32)
        finally:
            points.release()
        return out.reshape(-1, 4)[:n, :2].reshape(*shape, 2)

    def release(self) -> None:
        for obj in (self._height_tex, self._maps_tex, self._black):
            if obj is not None:
                obj.release()
        for target in (self._reflection, self._film_target):
            _release_target(self.ctx, target)
        self._height_tex = self._maps_tex = self._black = self._reflection = self._film_target = None


def make_road(ctx: moderngl.Context, settings=None, world=None) -> RoadEffect:
    """The road effect for ``scene.default_effects`` (the world is taken from the first frame if not given)."""
    return RoadEffect(ctx, None, world, settings)
