"""The atmosphere's GL side: the medium every program of the frame sees, and the post pass (glow, light
scattering). The model is in ``model.py``, the NumPy references of the post pass in ``glow.py`` and
``scattering.py``.

The medium reaches the shaders through the contract (``rain_core.gfx.effect``): ``frame_uniforms`` returns the
common/atmosphere.glsl uniforms of the frame, which the renderer puts over its clear air and writes into every
program it draws with (scene, sky, rain, spray, the post passes here). So the scene, its reflections and the
transparent effects are fogged alike, and with the effect idle every program sees clear air again.

Cost: with no rain and no haze (or the effect off) ``active`` is False: no update, no post pass; the clear-air
aerial perspective stays in the scene shader, one exp per pixel, at no extra cost. With fog but glow and light
scattering both 0 the post pass draws nothing.
"""

from __future__ import annotations

import math

import moderngl

from rain_core.effects.atmosphere.glow import MAX_BLUR_RADIUS, blur_radius
from rain_core.effects.atmosphere.model import (
    AtmosphereState,
    atmosphere_state,
    atmosphere_uniforms,
    medium_extinction_per_m,
)
from rain_core.effects.atmosphere.scattering import (
    SCATTER_MAX_M,
    SCATTER_SAMPLES,
    SCATTER_SKIP,
    SCATTER_SKIP_RELATIVE,
)
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import Frame, RenderContext
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import ColorView, RenderTarget, depth_value_sampler, float_target
from rain_core.gfx.uniforms import OwnedUniforms, mat4_bytes, owned_uniforms
from rain_core.settings import AtmosphereSection


class AtmosphereEffect(Effect):
    """Rain-correlated fog and extinction, rain-grey airlight, glow and light scattering (``model``).

    ``AtmosphereEffect(ctx, settings=None, *, seed=0, shaders=None)``: the settings are read from
    ``frame.settings.atmosphere`` each frame (``settings`` only stands in for frames without settings; ``seed``
    is unused: nothing here is random); shaders default to the renderer's library. After ``update`` the frame's
    model is in ``self.state`` (None while the effect is idle). ``scatter_skip``: the exposed radiance a pixel's
    skipped lights may add up to (``scattering.SCATTER_SKIP``; 0: every light traced), and ``scatter_skip_relative``
    the share of the pixel's own light they may add on top (``scattering.SCATTER_SKIP_RELATIVE``; 0: none).
    """

    name = "atmosphere"
    stages = ("post",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders: ShaderLibrary | None = None):
        self.ctx = ctx
        self.settings = settings
        self._shaders = shaders
        self.state: AtmosphereState | None = None
        self.glow_sigma_px = 0.0  # of the last frame, full-resolution pixels
        self._post_draws = False
        self._scatter_count = 0
        self._state_of: tuple | None = None  # (world, lighting, key, state): frame_uniforms and update share it
        self._uniforms_of: tuple | None = None  # (state, its uniforms)
        self._inv_of: tuple | None = None  # (rc, view, projection, inverse view-projection bytes)
        self._glow_factor = 1
        self._programs: dict[str, moderngl.Program] = {}
        self._vaos: dict[str, moderngl.VertexArray] = {}
        self._entries: dict = {}  # key → (program, vertex array, OwnedUniforms): _program
        self._targets: tuple[int, tuple[int, int], list[RenderTarget]] | None = None  # (factor, size, [a, b])
        self._hdr_fbo = ColorView(ctx)  # the HDR colour without its depth (the pass samples that depth)
        self._depth_sampler = depth_value_sampler(ctx)
        self.scatter_skip = SCATTER_SKIP
        self.scatter_skip_relative = SCATTER_SKIP_RELATIVE

    # --- per frame ------------------------------------------------------------------------------------------
    def _section(self, frame) -> AtmosphereSection:
        settings = getattr(frame, "settings", None) or self.settings
        return settings.atmosphere if settings is not None else AtmosphereSection()

    def _state(self, frame) -> AtmosphereState:
        # The model reads the rate, these settings, the lighting (an immutable object, the same one while the hour
        # and the overcast stay) and whether the world has lamps: while they stay, frame after frame, it is the
        # same state object (and its uniforms the same dict, so the frame block is not re-walked for them).
        sec = self._section(frame)
        key = (frame.rain_rate_mm_h, sec.enabled, sec.fog_scale, sec.haze_per_km, sec.sky_darkening, sec.glow,
               sec.light_scattering)
        cached = self._state_of
        if cached is not None and cached[0] is frame.world and cached[1] is frame.lighting and cached[2] == key:
            return cached[3]
        state = atmosphere_state(sec, frame.rain_rate_mm_h, frame.lighting,
                                 lamp_lit=bool(getattr(frame.world, "lamps", None)))
        self._state_of = (frame.world, frame.lighting, key, state)
        return state

    def observe(self, frame: Frame) -> None:
        self.state = None  # until ``update`` models this frame: an idle effect holds no stale medium

    def active(self, frame) -> bool:
        """Runs only while there is a medium: rain (with fog_scale > 0) or haze, and the effect enabled."""
        sec = self._section(frame)
        return sec.enabled and medium_extinction_per_m(frame.rain_rate_mm_h, sec.fog_scale, sec.haze_per_km) > 0.0

    def frame_uniforms(self, frame: Frame) -> dict:
        """β, the rain-grey airlight and the medium's sun airlight and phase (common/atmosphere.glsl)."""
        state = self._state(frame)
        if self._uniforms_of is None or self._uniforms_of[0] is not state:
            self._uniforms_of = (state, atmosphere_uniforms(state))
        return self._uniforms_of[1]

    def describe(self) -> str:
        if self.state is None:
            return "clear air"
        return f"visibility {self.state.visibility_m / 1000.0:.2f} km (5% contrast)"

    def update(self, frame: Frame, rc: RenderContext) -> None:
        sec = self._section(frame)
        self.state = state = self._state(frame)
        focal_px = 0.5 * rc.size[1] / math.tan(math.radians(frame.camera.fov_y_deg) / 2.0)
        self.glow_sigma_px = state.glow_sigma_rad * focal_px
        scatter = state.scatter_per_m > 0.0 and sec.scatter_lights > 0 and rc.lights[3] > 0
        self._scatter_count = min(sec.scatter_lights, rc.lights[3]) if scatter else 0
        self._glow_factor = max(1, round(1.0 / sec.glow_resolution))
        self._post_draws = state.glow_strength > 0.0 or scatter

    # --- GL -------------------------------------------------------------------------------------------------
    def _program(self, rc: RenderContext, frag: str, axis: int | None = None
                 ) -> tuple[moderngl.Program, moderngl.VertexArray, OwnedUniforms]:
        """The program of ``frag``, its vertex array and its OwnedUniforms; ``axis`` (the blur's) makes one program
        per direction."""
        key = frag if axis is None else (frag, axis)
        entry = self._entries.get(key)
        if entry is None:
            lib = self._shaders or rc.shaders
            # BLUR_AXIS is not read by the shader: it only keys a second program in the library, so each direction
            # keeps its u_step and the two are not rewritten every frame (same code, same pixels).
            defines = None if axis is None else {"BLUR_AXIS": axis}
            self._programs[key] = prog = lib.program("common/fullscreen.vert", frag, defines=defines)
            self._vaos[key] = vao = self.ctx.vertex_array(prog, [])
            entry = self._entries[key] = (prog, vao, owned_uniforms(prog))  # held: no weak lookup a frame
        return entry

    def _glow_targets(self, size: tuple[int, int], factor: int) -> list[RenderTarget]:
        low = (max(1, -(-size[0] // factor)), max(1, -(-size[1] // factor)))
        if self._targets is None or self._targets[:2] != (factor, low):
            self._release_targets()
            self._targets = (factor, low, [float_target(self.ctx, low, 4, "f2") for _ in range(2)])
        return self._targets[2]

    def _frame_uniforms(self, prog: moderngl.Program, owned: OwnedUniforms, rc: RenderContext,
                        bind: bool = True) -> None:
        """The frame's uniforms (the medium included) and the inverse camera the depth reconstruction needs.
        bind=False: this context's frame block is bound already (glow_down's, just before; the blur programs bind
        none), so only the plain frame uniforms are written (none today), not the block bound again."""
        rc.set_frame_uniforms(prog, bind=bind)
        owned.set("u_inv_view_proj", self._inv_view_proj(rc))

    def _inv_view_proj(self, rc: RenderContext) -> bytes:
        """mat4 bytes of inverse(projection·view), once per render context (both post programs need it; the
        inverse itself is the context's, which the sky pass already made)."""
        cached = self._inv_of
        if cached is None or cached[0] is not rc or cached[1] is not rc.view or cached[2] is not rc.projection:
            cached = self._inv_of = (rc, rc.view, rc.projection, mat4_bytes(rc.inv_view_proj))
        return cached[3]

    def render(self, stage: str, rc: RenderContext) -> None:
        if stage == "post" and self.state is not None and self._post_draws:
            self._draw_post(rc)

    def _draw_post(self, rc: RenderContext) -> None:
        ctx = self.ctx
        ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND)  # one call for both flags
        self._depth_sampler.use(units.ATMOSPHERE_DEPTH)
        rc.hdr.depth.use(units.ATMOSPHERE_DEPTH)
        a, b = self._glow_targets(rc.size, self._glow_factor)
        glowed = self.state.glow_strength > 0.0
        # The glow's first step also finds each block's least kept light, which lets the in-scatter skip a share
        # of it: made whenever lights are traced, blurred only for a halo.
        relative = self.scatter_skip_relative if self._scatter_count > 0 else 0.0
        down = glowed or relative > 0.0
        if down:
            self._glow(rc, a, b, blur=glowed)
        prog, vao, owned = self._program(rc, "atmosphere/composite.frag")
        self._frame_uniforms(prog, owned, rc, bind=not down)
        a.color.use(units.ATMOSPHERE_GLOW)
        # Only this effect writes these names in its programs: made and compared only when what they are made of
        # changes (the key holds every value that is not a constant).
        key = (self._glow_factor, self.state.glow_strength, self._scatter_count, self.state.scatter_per_m,
               self.scatter_skip, relative)
        owned.update_for("composite", key, lambda: {
            "u_glow": units.ATMOSPHERE_GLOW, "u_depth": units.ATMOSPHERE_DEPTH, "u_glow_factor": key[0],
            "u_glow_strength": key[1], "u_scatter_count": key[2], "u_scatter_samples": SCATTER_SAMPLES,
            "u_scatter_per_m": key[3], "u_scatter_max_m": SCATTER_MAX_M, "u_scatter_skip": key[4],
            "u_scatter_skip_relative": key[5]})
        # The composite reads the scene's depth, so it writes through a framebuffer without that depth attached.
        self._hdr_fbo.fbo(rc.hdr.color).use()
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)  # as the scene pass left it
        self._depth_sampler.clear(units.ATMOSPHERE_DEPTH)
        rc.hdr.fbo.use()

    def _glow(self, rc: RenderContext, a: RenderTarget, b: RenderTarget, blur: bool = True) -> None:
        """c·w box-averaged into ``a`` (and each block's least kept light in its alpha), then, with ``blur``,
        blurred a → b → a."""
        down, down_vao, owned = self._program(rc, "atmosphere/glow_down.frag")
        self._frame_uniforms(down, owned, rc)
        rc.hdr.color.use(units.ATMOSPHERE_GLOW)
        factor, strength = self._glow_factor, self.state.glow_strength
        owned.update_for("glow_down", (factor, strength), lambda: {
            "u_color": units.ATMOSPHERE_GLOW, "u_depth": units.ATMOSPHERE_DEPTH, "u_factor": factor,
            "u_glow_strength": strength})
        a.fbo.use()
        down_vao.render(moderngl.TRIANGLES, vertices=3)
        if not blur:
            return
        sigma = min(self.glow_sigma_px / self._glow_factor, MAX_BLUR_RADIUS / 3.0)
        radius = blur_radius(sigma)
        for axis, step, src, dst in ((0, (1, 0), a, b), (1, (0, 1), b, a)):
            _, blur_vao, owned = self._program(rc, "atmosphere/blur.frag", axis)  # one program per direction
            owned.update_for("blur", sigma, lambda step=step: {"u_src": units.ATMOSPHERE_GLOW, "u_sigma_px": sigma,
                                                               "u_radius": radius, "u_step": step})
            src.color.use(units.ATMOSPHERE_GLOW)
            dst.fbo.use()
            blur_vao.render(moderngl.TRIANGLES, vertices=3)

    def _release_targets(self) -> None:
        if self._targets is not None:
            for t in self._targets[2]:
                t.release()
            self._targets = None

    def release(self) -> None:
        self._release_targets()
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
        self._entries.clear()
        self._programs.clear()  # owned by the (shared, caching) ShaderLibrary: not ours to release
        self._hdr_fbo.release()
        self._depth_sampler.release()


class NoAirEffect(Effect):
    """No aerial perspective at all (β = 0): a surface's own radiance, for measuring what the medium does to it
    (tests, the atmosphere bench). Draws nothing."""

    name = "no_air"

    def __init__(self, ctx=None, settings=None, *, seed: int = 0, shaders=None):
        pass

    def active(self, frame) -> bool:
        return True

    def frame_uniforms(self, frame) -> dict:
        return {"u_extinction_per_m": 0.0}
