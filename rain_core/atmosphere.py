"""Atmosphere: visibility that follows the rain, misty glow around lights, rain-grey light (issue 9).

Extinction
    β = β_clear + fog_scale·β_rain(R) + haze, with β_rain = 0.312·R^0.67 km⁻¹ (Weber et al. 2015;
    ``physics.rain_extinction_per_km``) and β_clear the renderer's clear day (3.912 / 40 km). The scene shader
    (``shaders/common/atmosphere.glsl``) sees every surface through T = exp(−β·d) plus airlight A·(1 − T)
    (Koschmieder). That covers every view the scene shader draws: the puddle reflections are drawn by it from the
    mirrored camera, so their d is the whole reflected path; the windshield refracts a copy of this fogged frame.
    The contrast of a dark object against the horizon sky therefore falls as exp(−β·d): the meteorological
    optical range (5 % contrast, WMO) is V = −ln 0.05 / β ≈ 3.0 / β; the older 2 % threshold gives 3.912 / β.

Airlight
    A(v) = A_iso + (β_m / β)·E_sun·p(v·s): the isotropic part is the mean radiance of the surroundings — the
    horizon sky, greyed by the rain (``rain_overcast``), plus at night the lamp-lit street — and the sun's share
    is single scattering by the medium's part β_m of β (rain + haze; the analytic sky already holds the clear
    air) with a forward-peaked phase function p (two-term Henyey–Greenstein), so the sun side glows.

Sky
    The analytic sky is seen through the rain/haze layer (``LAYER_M`` thick) with β_m only: T = exp(−β_m·H / v_y),
    so the horizon goes to A(v) — far buildings fade into exactly the sky behind them, with no seam.

Rain-grey
    ``rain_overcast(R)`` = R / (R + 1.5 mm/h) in [0, 1): 0 in dry weather, 0.57 at 2 mm/h, 0.87 at 10 mm/h — a
    smooth transition, not a switch. The Scene passes it to ``lighting_for_hour(hour, overcast)`` (dimmer, greyer
    sun and sky; the exposure follows); ``sky_overcast`` applies the user's manual value or "auto". The effect
    also desaturates its airlight by the same amount, so the fog greys with the sky.

Near and far rain
    The rainfall effect draws the drops within its camera-following container (~30–50 m) as streaks; this module
    draws all rain as a medium. Both read the same ``frame.weather.rate_mm_h``, so raising R thickens both at
    once. The fog starts at d = 0 (no cut at the container's edge, so there is no seam there); the price is that
    drops inside the container extinguish light twice, once as streaks and once as fog: β·r ≈ 6 % at 10 mm/h
    and 13 % at 50 mm/h for r = 40 m — under the 20 % spread between the published β(R) fits.

Glow (post stage, ``shaders/atmosphere_*.frag``)
    A pixel at distance d loses 1 − exp(−β_m·d) of its light to scattering; the share ``GLOW_SHARE``·glow of that
    reaches the eye from nearby directions. So: c·w box-downsampled to the glow resolution, Gaussian-blurred with
    an angular σ that widens with β_m (multiple scattering broadens the atmospheric point-spread function), and
    blended back as hdr·(1 − k·w) + k·blur(c·w): a uniform region is unchanged, bright lights spread into mist.
    The nearest lights also get single scattering traced per pixel up to the depth buffer (σ_s = β_m, the
    same phase function), integrated with an equiangular substitution that is exact for the 1/r² peak; spot
    cones (headlights) show as beams.

Cost
    With no rain and no haze (or the effect off) ``active`` is False: no update, no post pass; the clear-air
    aerial perspective stays in the scene shader, one exp per pixel, at no extra cost. With fog but glow and
    light scattering both 0 the post pass draws nothing (it only resets the shared programs' uniforms).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import moderngl
import numpy as np

from rain_core import physics
from rain_core.gl import ColorView, ShaderLibrary, float_target
from rain_core.renderer import CLEAR_AIR_EXTINCTION_PER_M, Effect

LAYER_M = 1000.0  # m, thickness of the rain/haze layer the sky is seen through (keep = ATMOSPHERE_LAYER_M)
# Phase function of rain: two-term Henyey–Greenstein. The forward lobe (g = 0.7, geometric optics of mm drops
# without the diffraction spike) is what makes halos; the back lobe's weight is set so that p(180°) = 1/18.8 sr,
# the lidar ratio of liquid water drops (O'Connor et al. 2004) — it lets a driver see the rain in the own beams.
PHASE_G = 0.7
PHASE_BACK_G = -0.5
PHASE_BACK_WEIGHT = 0.0957
OVERCAST_HALF_RATE_MM_H = 1.5  # mm/h at which the sky is half-way to rain-grey
GLOW_SHARE = 0.5  # share of the scattered light that forms the visible halo at glow = 1
GLOW_SIGMA_MIN_RAD = math.radians(0.5)  # halo width in light rain …
GLOW_SIGMA_GROWTH_RAD = math.radians(3.0)  # … growing by up to this much as the medium thickens
GLOW_SIGMA_REF_M = 300.0  # m: the halo widens with the optical depth β_m·300 m
MAX_BLUR_RADIUS = 128  # taps each side of one blur direction (σ is capped at a third of it)
NIGHT_AIRLIGHT_CD_M2 = np.array([0.40, 0.36, 0.30])  # mean luminance of a lamp-lit street (4000 K LEDs)
SCATTER_SAMPLES = 8  # quadrature nodes per light and pixel
SCATTER_MAX_M = 300.0  # m, where rays into the sky stop gathering light
CONTRAST_THRESHOLD = 0.05  # meteorological optical range (WMO)

_GREY = np.array([0.96, 0.99, 1.04])  # overcast grey is slightly cool
_LUMA = np.array([0.2126, 0.7152, 0.0722])

GLOW_UNIT, DEPTH_UNIT = 10, 11  # texture units of this effect


# --- the model, in NumPy (float64; the truth the shaders are tested against) -----------------------------


def rain_extinction_per_m(rate_mm_h):
    """Extinction of rain alone (1/m) at rate R (mm/h): 0.312·R^0.67 km⁻¹ (Weber et al. 2015)."""
    return np.asarray(physics.rain_extinction_per_km(rate_mm_h), dtype=np.float64) * 1e-3


def medium_extinction_per_m(rate_mm_h: float, fog_scale: float = 1.0, haze_per_km: float = 0.0) -> float:
    """β_m (1/m): the rain's extinction × fog_scale plus the haze (1/km) — everything except the clear air."""
    return float(fog_scale * rain_extinction_per_m(rate_mm_h) + haze_per_km * 1e-3)


def extinction_per_m(rate_mm_h: float, fog_scale: float = 1.0, haze_per_km: float = 0.0) -> float:
    """Total β (1/m) at rain rate R (mm/h): clear air + fog_scale·β_rain(R) + haze (1/km)."""
    return CLEAR_AIR_EXTINCTION_PER_M + medium_extinction_per_m(rate_mm_h, fog_scale, haze_per_km)


def visibility_m(beta_per_m, contrast: float = CONTRAST_THRESHOLD):
    """Distance (m) at which a black object's contrast against the horizon falls to ``contrast``: −ln(c)/β."""
    return -math.log(contrast) / np.asarray(beta_per_m, dtype=np.float64)


def transmittance(beta_per_m, distance_m):
    """exp(−β·d): the share of a surface's light that reaches the eye across d metres."""
    return np.exp(-np.asarray(beta_per_m, dtype=np.float64) * np.asarray(distance_m, dtype=np.float64))


def rain_overcast(rate_mm_h) -> np.ndarray | float:
    """How rain-grey the sky is, in [0, 1), at rate R (mm/h): R / (R + 1.5). 0 when dry; smooth in R."""
    r = np.asarray(physics._check_rate(rate_mm_h), dtype=np.float64)
    out = r / (r + OVERCAST_HALF_RATE_MM_H)
    return float(out) if out.ndim == 0 else out


def sky_overcast(section, rate_mm_h: float) -> float:
    """The overcast to pass to ``lighting_for_hour``: the user's ``sky_darkening`` if set, else
    ``rain_overcast(R)`` (R in mm/h); 0 with the atmosphere effect off and no manual value."""
    if section.sky_darkening is not None:
        return float(section.sky_darkening)
    return rain_overcast(rate_mm_h) if section.enabled else 0.0


def phase_hg(mu, g: float):
    """Henyey–Greenstein phase function (1/sr) at cos(scattering angle) ``mu``; integrates to 1 over the sphere."""
    mu = np.asarray(mu, dtype=np.float64)
    d = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))


def phase_rain(mu):
    """The medium's phase function (1/sr): (1 − w)·HG(PHASE_G) + w·HG(PHASE_BACK_G), w = PHASE_BACK_WEIGHT."""
    return (1.0 - PHASE_BACK_WEIGHT) * phase_hg(mu, PHASE_G) + PHASE_BACK_WEIGHT * phase_hg(mu, PHASE_BACK_G)


def glow_sigma_rad(medium_per_m: float) -> float:
    """Angular standard deviation (rad) of the halo around lights for the medium's β_m (1/m)."""
    return GLOW_SIGMA_MIN_RAD + GLOW_SIGMA_GROWTH_RAD * (1.0 - math.exp(-medium_per_m * GLOW_SIGMA_REF_M))


@dataclass(frozen=True)
class AtmosphereState:
    """The atmosphere of one frame. β in 1/m, radiance in cd/m², illuminance in lux, directions unit vectors."""

    extinction_per_m: float  # total β (clear air + rain + haze)
    medium_per_m: float  # β_m, the rain + haze share
    airlight: np.ndarray  # isotropic airlight (cd/m², RGB)
    airlight_sun: np.ndarray  # (β_m/β)·E_sun (lux, RGB): weight of the phase function
    sun_direction: np.ndarray
    overcast: float
    glow_strength: float  # k: GLOW_SHARE × the user's glow
    glow_sigma_rad: float
    scatter_per_m: float  # σ_s of the light scattering pass, × the user's scale

    @property
    def visibility_m(self) -> float:
        return float(visibility_m(self.extinction_per_m))


def atmosphere_state(section, rate_mm_h: float, lighting, lamp_lit: bool = False) -> AtmosphereState:
    """The atmosphere for settings ``section`` (AtmosphereSection), rain rate R (mm/h) and ``lighting``
    (rain_core.lighting.Lighting). ``lamp_lit``: the street has lamps, which light the fog at night."""
    haze = section.haze_per_km if section.enabled else 0.0
    scale = section.fog_scale if section.enabled else 0.0
    beta_m = medium_extinction_per_m(rate_mm_h, scale, haze)
    beta = CLEAR_AIR_EXTINCTION_PER_M + beta_m
    overcast = sky_overcast(section, rate_mm_h)
    horizon = np.asarray(lighting.sky_horizon, dtype=np.float64)
    grey = float(horizon @ _LUMA) * _GREY
    airlight = horizon * (1.0 - overcast) + grey * overcast
    if lamp_lit:
        airlight = airlight + NIGHT_AIRLIGHT_CD_M2 * float(lighting.night_factor)
    sun = np.asarray(lighting.sun_illuminance, dtype=np.float64) * (beta_m / beta)
    return AtmosphereState(beta, beta_m, airlight, sun, np.asarray(lighting.sun_direction, dtype=np.float64),
                           overcast, GLOW_SHARE * section.glow if section.enabled else 0.0,
                           glow_sigma_rad(beta_m), beta_m * section.light_scattering if section.enabled else 0.0)


def airlight(state: AtmosphereState, view_dirs) -> np.ndarray:
    """Airlight (cd/m², RGB) seen along unit ``view_dirs`` (…, 3), eye outwards (twin of atmosphere_airlight)."""
    v = np.asarray(view_dirs, dtype=np.float64)
    p = phase_rain(v @ state.sun_direction)
    return state.airlight + state.airlight_sun * p[..., None]


def apply_atmosphere(radiance, distance_m, view_dirs, state: AtmosphereState) -> np.ndarray:
    """What the eye sees of surfaces of ``radiance`` (…, 3) cd/m² at ``distance_m`` (…) m along ``view_dirs``."""
    t = transmittance(state.extinction_per_m, distance_m)[..., None]
    return np.asarray(radiance, dtype=np.float64) * t + airlight(state, view_dirs) * (1.0 - t)


def apply_sky_atmosphere(radiance, view_dirs, state: AtmosphereState) -> np.ndarray:
    """The sky's ``radiance`` (…, 3) seen through the rain/haze layer along ``view_dirs`` (twin of the GLSL)."""
    v = np.asarray(view_dirs, dtype=np.float64)
    t = transmittance(state.medium_per_m, LAYER_M / np.maximum(v[..., 1], 1e-3))[..., None]
    return np.asarray(radiance, dtype=np.float64) * t + airlight(state, v) * (1.0 - t)


def _spot(light, to_light) -> np.ndarray:
    """Twin of spot_factor in shaders/common/lighting.glsl; to_light (…, 3) unit vectors towards the light."""
    if light.cos_outer <= -1.0:
        return np.ones(to_light.shape[:-1])
    x = np.clip((-(to_light @ light.direction) - light.cos_outer) / (light.cos_inner - light.cos_outer), 0.0, 1.0)
    f = x * x * (3.0 - 2.0 * x)
    if getattr(light, "low_beam", False):
        below_deg = np.degrees(np.arcsin(np.clip(to_light[..., 1], -1.0, 1.0)))
        f = f * np.exp(-np.maximum(below_deg - 1.5, 0.0) / 3.0)
    return f


def light_inscatter_reference(eye, view_dirs, t_max, light, extinction_per_m: float, scatter_per_m: float,
                              n: int = 20000) -> np.ndarray:
    """Single scattering (cd/m², RGB) from ``light`` (a rain_core.lighting.Light, position in the same frame as
    ``eye``, m) along unit ``view_dirs`` (…, 3) from ``eye`` up to ``t_max`` (…) m, by a dense midpoint rule in
    t (float64): ∫ σ_s·p·I·spot·window·exp(−β(t + r)) / r² dt, r clamped ≥ 0.15 m as in the shader."""
    v = np.asarray(view_dirs, dtype=np.float64)
    tm = np.broadcast_to(np.asarray(t_max, dtype=np.float64), v.shape[:-1])
    tm = np.minimum(tm, np.linalg.norm(light.position - eye) + light.range_m)  # nothing reaches further
    s = (np.arange(n) + 0.5) / n
    t = tm[..., None] * s  # (…, n)
    x = eye + v[..., None, :] * t[..., None]
    d = light.position - x
    r2 = np.maximum(np.sum(d * d, axis=-1), 0.15**2)
    r = np.sqrt(r2)
    lvec = d / r[..., None]
    window = np.clip(1.0 - (r2 / light.range_m**2) ** 2, 0.0, 1.0) ** 2
    spot = _spot(light, lvec)
    mu = np.sum(lvec * v[..., None, :], axis=-1)
    f = phase_rain(mu) * spot * window * np.exp(-extinction_per_m * (t + r)) / r2
    integral = f.mean(axis=-1) * tm * scatter_per_m
    return integral[..., None] * (np.asarray(light.color, dtype=np.float64) * light.intensity_cd)


def pixel_distances(depth, view_proj, eye, sky_m: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) and unit eye ray (wrapped frame) of every pixel of a depth buffer (H, W) in [0, 1], bottom
    row first as GL stores it, for the camera ``view_proj`` (4×4) at ``eye`` (m); sky pixels (depth 1) get sky_m.
    Twin of atmosphere_pixel_ray in shaders/atmosphere_depth.glsl."""
    depth = np.asarray(depth, dtype=np.float64)
    h, w = depth.shape
    x, y = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, (np.arange(h) + 0.5) / h * 2 - 1)
    sky = depth >= 1.0
    clip = np.stack([x, y, np.where(sky, 1.0, depth * 2 - 1), np.ones_like(x)], axis=-1)
    p = clip @ np.linalg.inv(np.asarray(view_proj, dtype=np.float64)).T
    d = p[..., :3] / p[..., 3:] - np.asarray(eye, dtype=np.float64)
    dist = np.linalg.norm(d, axis=-1)
    return np.where(sky, sky_m, dist), d / dist[..., None]


def gaussian_weights(sigma_px: float) -> np.ndarray:
    """The blur's normalised discrete Gaussian (taps −r … r, r = blur_radius(σ)); σ in texels."""
    r = blur_radius(sigma_px)
    k = np.arange(-r, r + 1, dtype=np.float64)
    w = np.exp(-0.5 * k * k / max(sigma_px * sigma_px, 1e-6))
    return w / w.sum()


def blur_radius(sigma_px: float) -> int:
    """Taps each side of the blur for σ (texels): ⌈3σ⌉, at most MAX_BLUR_RADIUS."""
    return int(min(MAX_BLUR_RADIUS, max(1, math.ceil(3.0 * sigma_px))))


def glow_reference(color, weight, strength: float, sigma_px: float) -> np.ndarray:
    """The glow at full resolution in NumPy: color·(1 − k·w) + k·G_σ * (color·w), edges clamped.

    color (H, W, 3) pre-exposed HDR; weight (H, W) the scattered share w = 1 − exp(−β_m·d); σ in pixels."""
    c = np.asarray(color, dtype=np.float64)
    w = np.asarray(weight, dtype=np.float64)[..., None]
    src = c * w
    g = gaussian_weights(sigma_px)
    r = (len(g) - 1) // 2
    for axis in (1, 0):
        pad = [(0, 0)] * 3
        pad[axis] = (r, r)
        p = np.pad(src, pad, mode="edge")
        n = src.shape[axis]
        src = sum(g[i] * np.take(p, np.arange(i, i + n), axis=axis) for i in range(len(g)))
    return c * (1.0 - strength * w) + strength * src


# --- the effect -----------------------------------------------------------------------------------------


def _set(program, name: str, value) -> None:
    if name in program:
        program[name].value = value


def medium_uniforms(state: AtmosphereState | None) -> dict:
    """The atmosphere.glsl uniforms this effect owns; None gives the clear-air values (its terms vanish).
    The renderer writes them into every program that declares them (rain, spray, scene, sky)."""
    if state is None:
        return {"u_medium_extinction_per_m": 0.0, "u_airlight_sun": (0.0, 0.0, 0.0)}
    return {"u_medium_extinction_per_m": state.medium_per_m,
            "u_airlight_sun": tuple(float(x) for x in state.airlight_sun),
            "u_airlight_sun_dir": tuple(float(x) for x in state.sun_direction),
            "u_phase_g": PHASE_G, "u_phase_back_g": PHASE_BACK_G, "u_phase_back_weight": PHASE_BACK_WEIGHT}


def _write_medium(program, state: AtmosphereState | None) -> None:
    for name, value in medium_uniforms(state).items():
        _set(program, name, value)


class Atmosphere(Effect):
    """Rain-correlated fog and extinction, rain-grey airlight, glow and light scattering (module docstring).

    ``Atmosphere(ctx, shaders=None, settings=None)``: shaders default to the renderer's library, settings are
    read from ``frame.settings.atmosphere`` each frame. After ``update`` the frame's model is in ``self.state``.
    """

    name = "atmosphere"

    def __init__(self, ctx: moderngl.Context, shaders: ShaderLibrary | None = None, settings=None):
        self.ctx = ctx
        self._shaders = shaders
        self.stages: tuple[str, ...] = ("post",)
        self._post_draws = False
        self.state: AtmosphereState | None = None
        self._renderer = None
        self._programs: dict[str, moderngl.Program] = {}
        self._vaos: dict[str, moderngl.VertexArray] = {}
        self._targets = None  # (factor, size, [RenderTarget, RenderTarget])
        self._hdr_fbo = ColorView(ctx)  # the HDR colour without its depth (the pass samples that depth)
        self._depth_sampler = ctx.sampler(compare_func="", filter=(moderngl.NEAREST, moderngl.NEAREST),
                                          repeat_x=False, repeat_y=False)
        self.glow_sigma_px = 0.0  # of the last frame, full-resolution pixels

    # --- per frame ------------------------------------------------------------------------------------------
    @staticmethod
    def _section(frame):
        from rain_core.settings import AtmosphereSection

        settings = getattr(frame, "settings", None)
        return settings.atmosphere if settings is not None else AtmosphereSection()

    def active(self, frame) -> bool:
        """Runs only while there is a medium: rain (with fog_scale > 0) or haze, and the effect enabled."""
        sec = self._section(frame)
        on = sec.enabled and medium_extinction_per_m(frame.rain_rate_mm_h, sec.fog_scale, sec.haze_per_km) > 0.0
        if not on:
            self._restore()
        return on

    def describe(self) -> str:
        if self.state is None:
            return "clear air"
        return f"visibility {self.state.visibility_m / 1000.0:.2f} km (5% contrast)"

    def _restore(self) -> None:
        """Give the renderer back its clear air (also the sky's uniforms, which no bind_scene reaches)."""
        renderer, self._renderer, self.state = self._renderer, None, None
        if renderer is not None:
            renderer.extinction_per_m = CLEAR_AIR_EXTINCTION_PER_M
            renderer.airlight = None
            renderer.medium_uniforms = medium_uniforms(None)

    def update(self, frame, rc) -> None:
        sec = self._section(frame)
        state = atmosphere_state(sec, frame.rain_rate_mm_h, frame.lighting,
                                 lamp_lit=bool(getattr(frame.world, "lamps", None)))
        self.state = state
        self._renderer = rc.renderer
        rc.renderer.extinction_per_m = state.extinction_per_m
        rc.renderer.airlight = state.airlight
        rc.renderer.medium_uniforms = medium_uniforms(state)
        focal_px = 0.5 * rc.size[1] / math.tan(math.radians(frame.camera.fov_y_deg) / 2.0)
        self.glow_sigma_px = state.glow_sigma_rad * focal_px
        scatter = state.scatter_per_m > 0.0 and sec.scatter_lights > 0 and rc.lights[3] > 0
        self._scatter_count = min(sec.scatter_lights, rc.lights[3]) if scatter else 0
        self._glow_factor = max(1, round(1.0 / sec.glow_resolution))
        self._post_draws = state.glow_strength > 0.0 or scatter

    def bind_scene(self, program, rc) -> None:
        _write_medium(program, self.state)

    def unbind_scene(self, program, rc) -> None:
        self._restore()
        _write_medium(program, None)
        _set(program, "u_extinction_per_m", CLEAR_AIR_EXTINCTION_PER_M)
        if "u_airlight" in program:
            program["u_airlight"].value = tuple(float(x) for x in rc.frame.lighting.sky_horizon)

    # --- GL -------------------------------------------------------------------------------------------------
    def _program(self, rc, frag: str) -> tuple[moderngl.Program, moderngl.VertexArray]:
        if frag not in self._programs:
            lib = self._shaders or rc.shaders
            self._programs[frag] = prog = lib.program("common/fullscreen.vert", frag)
            self._vaos[frag] = self.ctx.vertex_array(prog, [])
        return self._programs[frag], self._vaos[frag]

    def _glow_targets(self, size: tuple[int, int], factor: int):
        low = (max(1, -(-size[0] // factor)), max(1, -(-size[1] // factor)))
        if self._targets is None or self._targets[:2] != (factor, low):
            if self._targets is not None:
                for t in self._targets[2]:
                    t.release()
            self._targets = (factor, low, [float_target(self.ctx, low, 4, "f2") for _ in range(2)])
        return self._targets[2]

    def _hdr_color_fbo(self, rc) -> moderngl.Framebuffer:
        # The composite reads the scene's depth, so it writes through a framebuffer without that depth attached.
        return self._hdr_fbo.fbo(rc.hdr.color)

    def _frame_uniforms(self, prog, rc) -> None:
        rc.set_frame_uniforms(prog)
        _write_medium(prog, self.state)
        _set(prog, "u_extinction_per_m", self.state.extinction_per_m)
        _set(prog, "u_airlight", tuple(float(x) for x in self.state.airlight))
        if "u_inv_view_proj" in prog:
            prog["u_inv_view_proj"].write(np.ascontiguousarray(
                np.linalg.inv(rc.view_proj).astype(np.float32).T).tobytes())

    def render(self, stage: str, rc) -> None:
        if stage != "post" or self.state is None:
            return
        if self._post_draws:
            self._draw_post(rc)
        # The scene and sky programs are shared (cached by the ShaderLibrary) with every other view and renderer,
        # and only this effect knows its uniforms: leave them at their clear-air values once the frame is drawn.
        _write_medium(rc.renderer.scene_prog, None)
        _write_medium(rc.renderer.sky_prog, None)

    def _draw_post(self, rc) -> None:
        ctx = self.ctx
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.BLEND)
        self._depth_sampler.use(DEPTH_UNIT)
        rc.hdr.depth.use(DEPTH_UNIT)
        a, b = self._glow_targets(rc.size, self._glow_factor)
        if self.state.glow_strength > 0.0:
            self._glow(rc, a, b)
        prog, vao = self._program(rc, "atmosphere/composite.frag")
        self._frame_uniforms(prog, rc)
        a.color.use(GLOW_UNIT)
        values = {"u_glow": GLOW_UNIT, "u_depth": DEPTH_UNIT, "u_glow_factor": self._glow_factor,
                  "u_glow_strength": self.state.glow_strength, "u_scatter_count": self._scatter_count,
                  "u_scatter_samples": SCATTER_SAMPLES, "u_scatter_per_m": self.state.scatter_per_m,
                  "u_scatter_max_m": SCATTER_MAX_M}
        for name, value in values.items():
            _set(prog, name, value)
        self._hdr_color_fbo(rc).use()
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)  # as the scene pass left it
        self._depth_sampler.clear(DEPTH_UNIT)
        rc.hdr.fbo.use()

    def _glow(self, rc, a, b) -> None:
        """c·w box-averaged into ``a``, then blurred a → b → a."""
        down, down_vao = self._program(rc, "atmosphere/glow_down.frag")
        self._frame_uniforms(down, rc)
        rc.hdr.color.use(GLOW_UNIT)
        _set(down, "u_color", GLOW_UNIT)
        _set(down, "u_depth", DEPTH_UNIT)
        _set(down, "u_factor", self._glow_factor)
        a.fbo.use()
        down_vao.render(moderngl.TRIANGLES, vertices=3)
        sigma = min(self.glow_sigma_px / self._glow_factor, MAX_BLUR_RADIUS / 3.0)
        blur, blur_vao = self._program(rc, "atmosphere/blur.frag")
        _set(blur, "u_src", GLOW_UNIT)
        _set(blur, "u_sigma_px", sigma)
        _set(blur, "u_radius", blur_radius(sigma))
        for step, src, dst in (((1, 0), a, b), ((0, 1), b, a)):
            _set(blur, "u_step", step)
            src.color.use(GLOW_UNIT)
            dst.fbo.use()
            blur_vao.render(moderngl.TRIANGLES, vertices=3)

    def release(self) -> None:
        if self._targets is not None:
            for t in self._targets[2]:
                t.release()
            self._targets = None
        self._hdr_fbo.release()
        self._depth_sampler.release()


def make_atmosphere(ctx: moderngl.Context, settings=None) -> Atmosphere:
    """The atmosphere effect for ``Scene``'s effect list (settings are read per frame)."""
    return Atmosphere(ctx, settings=settings)
