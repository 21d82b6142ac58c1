"""The rainbow's GL side: one full-screen pass in the post stage that adds the bow (shaders/rainbow/bow.frag).
The optics are in ``optics.py`` (the P(θ) table it uploads), the rain along the rays in ``shower.py``.

Cost: nothing unless a bow can be seen — the effect is idle (no update, no pass, no table) at night, with the sun
above 54° (the whole bow, secondary included, lies below the horizon, where rays cross only the few metres of rain
above the street), with no rain and no departing shower, and when the bow's circle is outside the view. The table
is recomputed only when the rain rate moves by more than 10 % (about 60 ms on this 2-core machine).
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core.effects.atmosphere.model import rain_extinction_per_m
from rain_core.effects.rainbow.optics import THETA_RANGE_DEG, bow_lut
from rain_core.effects.rainbow.shower import RainColumn, ShowerTracker
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import Frame, RenderContext
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import ColorView, depth_value_sampler
from rain_core.gfx.uniforms import mat4_bytes, owned_uniforms
from rain_core.settings import AtmosphereSection, RainbowSection

MAX_SUN_ELEVATION_DEG = 54.0  # above it the secondary's top (≈ 53.5° from the antisolar point) is below the horizon
LUT_SAMPLES = 384
LUT_RATE_TOLERANCE = 0.1  # relative change of the rate that recomputes the table
_BOW_OUTER_RAD = math.radians(THETA_RANGE_DEG[1])


def bow_in_view(camera, sun_direction, aspect_max: float = 2.4) -> bool:
    """Whether any part of the bow (θ ≤ 62° around the antisolar point) can fall inside ``camera``'s view: the
    angle from the view axis to the antisolar point is below 62° plus the half-diagonal of the widest frame."""
    forward = np.asarray(camera.basis()[2], dtype=np.float64) if hasattr(camera, "basis") else None
    if forward is None:
        return True
    half_v = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    half_diag = math.atan(half_v * math.hypot(1.0, aspect_max))
    anti = -np.asarray(sun_direction, dtype=np.float64)
    cos_angle = float(np.dot(forward, anti) / max(np.linalg.norm(forward) * np.linalg.norm(anti), 1e-12))
    return math.acos(max(-1.0, min(1.0, cos_angle))) < _BOW_OUTER_RAD + half_diag


class RainbowEffect(Effect):
    """A primary and a secondary bow on the sunlit rain in front of the viewer (``optics`` for the physics).

    ``RainbowEffect(ctx, settings=None, *, seed=0, shaders=None)``: settings from ``frame.settings.rainbow``
    (``settings`` stands in for frames without settings); nothing is random.
    """

    name = "rainbow"
    stages = ("post",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders: ShaderLibrary | None = None):
        self.ctx = ctx
        self.settings = settings
        self._shaders = shaders
        self.shower = ShowerTracker()
        self.column: RainColumn | None = None  # of the last update
        self._lut_rate = None
        self._lut: moderngl.Texture | None = None
        self._prog: moderngl.Program | None = None
        self._vao: moderngl.VertexArray | None = None
        self._hdr_fbo = ColorView(ctx)
        self._depth_sampler = depth_value_sampler(ctx)

    def _section(self, frame) -> RainbowSection:
        settings = getattr(frame, "settings", None) or self.settings
        return getattr(settings, "rainbow", None) or RainbowSection()

    def _atmosphere(self, frame) -> AtmosphereSection:
        settings = getattr(frame, "settings", None) or self.settings
        return getattr(settings, "atmosphere", None) or AtmosphereSection()

    # --- per frame ------------------------------------------------------------------------------------------
    def observe(self, frame: Frame) -> None:
        self.shower.observe(frame.time_s, frame.rain_rate_mm_h)

    def _column(self, frame) -> RainColumn | None:
        sec = self._section(frame)
        return self.shower.column(frame.time_s, frame.rain_rate_mm_h, sec.shower_speed_m_s, sec.shower_width_m)

    def active(self, frame) -> bool:
        sec = self._section(frame)
        if not sec.enabled or sec.strength <= 0.0:
            return False
        sun = frame.lighting.sun_direction
        elevation = math.degrees(math.asin(max(-1.0, min(1.0, float(sun[1])))))
        if not (0.0 < elevation < MAX_SUN_ELEVATION_DEG) or float(np.max(frame.lighting.sun_illuminance)) <= 0.0:
            return False
        return self._column(frame) is not None and bow_in_view(frame.camera, sun)

    def describe(self) -> str:
        if self.column is None:
            return "no bow"
        if self.column.near_m <= 0.0:
            return f"on the rain ({self.column.rate_mm_h:.3g} mm/h)"
        return f"on the departing shower, {self.column.near_m / 1000.0:.2f} km away"

    def update(self, frame: Frame, rc: RenderContext) -> None:
        self.column = column = self._column(frame)
        if column is not None and (self._lut_rate is None
                                   or abs(column.rate_mm_h / self._lut_rate - 1.0) > LUT_RATE_TOLERANCE):
            self._upload_lut(column.rate_mm_h)

    def _upload_lut(self, rate_mm_h: float) -> None:
        table = bow_lut(rate_mm_h, LUT_SAMPLES).astype("f4")
        if self._lut is None:
            self._lut = self.ctx.texture((LUT_SAMPLES, 1), 3, dtype="f4")
            self._lut.filter = (moderngl.LINEAR, moderngl.LINEAR)
            self._lut.repeat_x = self._lut.repeat_y = False
        self._lut.write(table.tobytes())
        self._lut_rate = rate_mm_h

    # --- GL -------------------------------------------------------------------------------------------------
    def render(self, stage: str, rc: RenderContext) -> None:
        if stage != "post" or self.column is None or self._lut is None:
            return
        sec = self._section(rc.frame)
        if self._prog is None:
            self._prog = (self._shaders or rc.shaders).program("common/fullscreen.vert", "rainbow/bow.frag")
            self._vao = self.ctx.vertex_array(self._prog, [])
        prog = self._prog
        rc.set_frame_uniforms(prog)
        column = self.column
        far = min(column.far_m, 1e9)
        owned_uniforms(prog).update({
            "u_depth": units.RAINBOW_DEPTH, "u_bow_lut": units.RAINBOW_LUT,
            "u_inv_view_proj": mat4_bytes(np.linalg.inv(rc.view_proj)),
            "u_theta_range": tuple(math.radians(a) for a in THETA_RANGE_DEG),
            "u_rain_beta": float(rain_extinction_per_m(column.rate_mm_h)),
            "u_rain_span_m": (float(column.near_m), float(far)),
            "u_cloud_base_m": float(self._atmosphere(rc.frame).cloud_base_m), "u_strength": float(sec.strength)})
        ctx = self.ctx
        self._depth_sampler.use(units.RAINBOW_DEPTH)
        rc.hdr.depth.use(units.RAINBOW_DEPTH)
        self._lut.use(units.RAINBOW_LUT)
        ctx.disable(moderngl.DEPTH_TEST)
        self._hdr_fbo.fbo(rc.hdr.color).use()  # the pass samples the scene's depth: draw without it attached
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        self._vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)
        self._depth_sampler.clear(units.RAINBOW_DEPTH)
        rc.hdr.fbo.use()

    def release(self) -> None:
        if self._vao is not None:
            self._vao.release()
            self._vao = None
        self._prog = None  # owned by the (shared, caching) ShaderLibrary
        if self._lut is not None:
            self._lut.release()
            self._lut = None
        self._hdr_fbo.release()
        self._depth_sampler.release()
