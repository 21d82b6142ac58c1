"""The frame renderer: pass order and timing. Ordered passes into an offscreen HDR target, tone-mapped to sRGB.

Stages, in order (an effect lists the ones it draws in; see ``rain_core.gfx.effect`` for the contract):
  ``prepare``      offscreen work before the scene (simulation steps on the GPU, reflection maps)
  ``scene``        built in: sky, world tiles, vehicles, cabin — effects may only bind inputs (``bind_scene``)
  ``transparent``  blended into the HDR target with the scene's depth (rain streaks, spray)
  ``post``         full-screen HDR work (glow, fog shafts)
  ``overlay``      what sits in front of the eye (the windshield), reads a copy of the HDR frame
then ``tonemap`` to the display image.
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core import layout
from rain_core.gfx import units
from rain_core.gfx.effect import DRAW_STAGES, Effect
from rain_core.gfx.exposure import AutoExposure
from rain_core.gfx.frame import Frame, FrameUniforms, PassStat, RenderContext, SharedResources
from rain_core.gfx.frame_block import FrameBlocks
from rain_core.gfx.light_grid import TILE_PX, LightGrid
from rain_core.gfx.mirrors import DoorMirrors
from rain_core.gfx.scene_draw import SceneDrawer
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.shadow import NO_SHADOW, ShadowMap, sun_is_up
from rain_core.gfx.targets import RenderTarget, float_target
from rain_core.gfx.timing import PassTimer, cpu_ms
from rain_core.gfx.uniforms import owned_uniforms
from rain_core.lighting import (
    concat_lights,
    light_candidates,
    nearest_lights,
    pack_lights,
    pack_nearest,
    wrap_lights,
)
from rain_core.physics import CLEAR_AIR_EXTINCTION_PER_M


def clear_air_uniforms(lighting) -> dict:
    """common/atmosphere.glsl's inputs in clear air; an active medium effect overrides them (frame_uniforms)."""
    return {"u_extinction_per_m": CLEAR_AIR_EXTINCTION_PER_M,
            "u_airlight": tuple(float(x) for x in lighting.sky_horizon),
            "u_medium_extinction_per_m": 0.0, "u_airlight_sun": (0.0, 0.0, 0.0)}


class Renderer:
    """Draws frames of the street into an HDR target and tone-maps them.

    ``render(frame)`` runs the passes; ``image()`` returns the last frame as uint8 (H, W, 3) sRGB, top row first;
    ``present(fbo, size)`` draws it into a window's framebuffer. ``stats`` lists the passes of the last frame:
    CPU ms always, GPU ms only while ``gpu_timing`` is on (a timer query per pass, read two frames late; turn it
    on only while someone looks at the figures — a performance table).
    """

    def __init__(self, ctx: moderngl.Context, size: tuple[int, int], world, effects=(),
                 shaders: ShaderLibrary | None = None, gpu_timing: bool = True):
        width, height = (int(v) for v in size)
        if width <= 0 or height <= 0:
            raise ValueError(f"render size must be positive, got {size!r}")
        self.ctx = ctx
        self.size = (width, height)
        self.world = world
        self._owns_shaders = shaders is None
        self.shaders = shaders or ShaderLibrary(ctx)
        self.effects = list(effects)
        self._gpu_timing = bool(gpu_timing)
        self._gpu_source = "none"
        self.stats: list[PassStat] = []
        self._to_describe: list = []  # (PassStat, effect) whose note pass_table() fills in

        self._make_targets()
        self.shadow = ShadowMap(ctx, self.shaders)
        self.scene = SceneDrawer(ctx, self.shaders, world, self.shadow.program)
        self.tonemap_prog = self.shaders.program("common/fullscreen.vert", "core/tonemap.frag")
        self.blit_prog = self.shaders.program("common/fullscreen.vert", "core/blit.frag")
        self._tonemap_vao = ctx.vertex_array(self.tonemap_prog, [])
        self.exposure = AutoExposure(ctx, self.shaders)
        self.mirrors = DoorMirrors(ctx)
        self.light_grid_px = TILE_PX  # the views' light tiles (pixels); 0: no grid, every light everywhere
        self._blit_vao = ctx.vertex_array(self.blit_prog, [])
        self._timers: dict[str, PassTimer] = {}
        self.frame_blocks = FrameBlocks(ctx)
        self._lights_cache = None  # (key, light candidates) of the frame being rendered
        self._mirror_plans: list = []  # ((rc, target, camera, mirror), its mirror context) of the frame being rendered
        self._effect_lights = None  # LightSet the active effects add this frame (Effect.frame_lights), or None
        self._proj_cache = None  # (lens and size, projection matrix)
        self._clear_air = None  # (lighting, its clear-air and no-shadow uniforms)
        self._undrawn_s = 0.0  # s stepped in frames not drawn since the eye last metered one (render(draw=False))

    @property
    def scene_prog(self) -> moderngl.Program:
        return self.scene.scene_prog

    @property
    def light_grid(self) -> LightGrid:
        """The views' light grids (the scene drawer builds them after each view's depth pre-pass)."""
        return self.scene.light_grid

    @property
    def gpu_timing(self) -> bool:
        """Whether passes are timed on the GPU too (timer queries, read two frames late). Switch it on only while
        the figures are shown: it adds queries to every pass."""
        return self._gpu_timing

    @gpu_timing.setter
    def gpu_timing(self, on: bool) -> None:
        on = bool(on)
        if on != self._gpu_timing:
            for timer in self._timers.values():
                timer.forget()  # a result from before the switch would be read as this frame's
        self._gpu_timing = on

    @property
    def timing_source(self) -> str:
        """Where the GPU ms come from: "none" while ``gpu_timing`` is off."""
        return self._gpu_source if self._gpu_timing else "none"

    def _make_targets(self):
        self.hdr = float_target(self.ctx, self.size, 4, "f2", depth=True)
        self.ldr_color = self.ctx.texture(self.size, 4)
        self.ldr_color.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self.ldr = self.ctx.framebuffer(color_attachments=[self.ldr_color])

    def resize(self, size: tuple[int, int]) -> None:
        """New frame size in pixels (a minimised window reports 0: keep the old targets then)."""
        width, height = (int(v) for v in size)
        if width <= 0 or height <= 0 or (width, height) == self.size:
            return
        self.hdr.release()
        self.ctx.detect_framebuffer(0).use()
        self.ldr.release()
        self.ldr_color.release()
        self.size = (width, height)
        self._make_targets()

    # --- views ----------------------------------------------------------------------------------------------
    def render_context(self, frame: Frame, fbo_target: RenderTarget | None = None, *, view: np.ndarray | None = None,
                       projection: np.ndarray | None = None, **fields) -> RenderContext:
        """The context of a view of ``frame``: its camera's matrices (or ``view``/``projection`` as given, in the
        wrapped frame), its lights, the clear-air and no-shadow defaults; ``fields``: other RenderContext fields
        (``shared``, ``uniforms``, ``active``) taken as given."""
        camera = frame.camera
        shift_z = math.floor(float(camera.position[2]) / layout.PERIOD_M) * layout.PERIOD_M
        if view is None:
            view = camera.view_matrix(shift=(0.0, 0.0, shift_z))
        if projection is None:
            projection = self._projection(camera)
        cam = np.asarray(camera.position, dtype=np.float64) - np.array([0.0, 0.0, shift_z])
        candidates = self._light_candidates(frame, shift_z, float(cam[2]))
        if self._effect_lights is not None:  # the active effects' own lights (a flash) lead the list
            packed = pack_lights(concat_lights([wrap_lights(self._effect_lights, shift_z),
                                                nearest_lights(candidates, cam)]))
        else:
            packed = pack_nearest(candidates, cam)  # pack_lights(nearest_lights(…)) from rows packed once
        if "uniforms" not in fields:
            fields["uniforms"] = self._default_uniforms(frame.lighting)
        return RenderContext(self.ctx, self.shaders, frame, fbo_target or self.hdr, self.size, shift_z, view,
                             projection, packed, self, frame_blocks=self.frame_blocks, **fields)

    def _projection(self, camera) -> np.ndarray:
        """camera.projection_matrix at this frame's aspect, kept while the lens and the size stay (read-only)."""
        key = (camera.fov_y_deg, camera.near_m, camera.far_m, self.size)
        if self._proj_cache is None or self._proj_cache[0] != key:
            projection = camera.projection_matrix(self.size[0] / self.size[1])
            projection.flags.writeable = False
            self._proj_cache = (key, projection)
        return self._proj_cache[1]

    def _default_uniforms(self, lighting) -> dict:
        """A new dict of the clear-air and no-shadow uniforms (built once per lighting object, copied per view:
        the frame adds to it)."""
        if self._clear_air is None or self._clear_air[0] is not lighting:
            self._clear_air = (lighting, {**clear_air_uniforms(lighting), **NO_SHADOW})
        return FrameUniforms(self._clear_air[1])

    def _light_candidates(self, frame: Frame, shift_z: float, camera_z: float):
        """lighting.light_candidates, kept for the frame being rendered: the road's mirror view (same vehicles,
        lighting and camera z) only sorts them again by distance to its camera."""
        key = (frame.vehicles, frame.lighting, frame.headlights_on, shift_z, camera_z)
        cached = self._lights_cache
        if cached is not None and all(a is b or (type(a) is float and a == b)
                                      for a, b in zip(cached[0], key, strict=True)):
            return cached[1]
        lights = light_candidates(getattr(self.world, "lamps", []), frame.vehicles, camera_z, frame.lighting,
                                  shift_z, layout.PERIOD_M, frame.headlights_on)
        if self.scene.in_frame:  # outside render() the vehicles may move between calls: nothing kept
            self._lights_cache = (key, lights)
        return lights

    def _draw_scene(self, rc: RenderContext, include_sky: bool = True, clip_plane=None, mirror_view=None) -> None:
        self.shadow.bind()  # re-bound per draw: a GPU simulation may have used the unit
        self.scene.draw(rc, self.effects, include_sky=include_sky, clip_plane=clip_plane, mirror_view=mirror_view)

    def mirror_context(self, rc: RenderContext, target: RenderTarget, camera, mirror: np.ndarray) -> RenderContext:
        """The context ``draw_mirror_view`` draws ``rc``'s view reflected by ``mirror`` with (same arguments), made
        once per frame with its draw list. An effect may ask for it in its update, before the frame's draws: on
        llvmpipe the draws leave Python's caches cold, and this work cost ~3 times as much between them."""
        key = (rc, target, camera, mirror)
        for planned, mrc in self._mirror_plans:
            if all(a is b for a, b in zip(planned, key, strict=True)):
                return mrc
        mrc = self.render_context(rc.frame.with_camera(camera), target, view=rc.view @ mirror,
                                  projection=rc.projection, shared=rc.shared, uniforms=rc.uniforms, active=rc.active,
                                  light_grid_px=self.light_grid_px)
        if self.scene.in_frame:  # kept for this frame alone (holding the key's objects keeps them from being reused)
            self._mirror_plans.append((key, mrc))
            self.scene.draw_items(mrc, True, cull=True)
            mrc.frame_block_bytes()
            mrc.inv_view_proj  # noqa: B018 - made and kept by the context
        return mrc

    def draw_mirror_view(self, rc: RenderContext, target: RenderTarget, camera, mirror: np.ndarray,
                         clip_plane: tuple[float, float, float, float]) -> None:
        """Draw the scene reflected by ``mirror`` (a 4×4 reflection in the wrapped frame) into ``target``, as seen
        through the main view's projection: a texel of ``target`` lies where the main camera sees the surface
        point that reflects it. ``camera``: the mirrored camera (its position lights the speculars);
        ``clip_plane`` (a, b, c, d) keeps what is on its positive side. Same effects, same shared value."""
        mrc = self.mirror_context(rc, target, camera, mirror)
        target.fbo.use()
        target.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        self.ctx.disable(moderngl.CULL_FACE)
        self.ctx.front_face = "cw"  # mirroring flips the winding
        try:
            self._draw_scene(mrc, include_sky=True, clip_plane=clip_plane)
        finally:
            self.ctx.front_face = "ccw"

    # --- passes ---------------------------------------------------------------------------------------------
    def _timed(self, name: str, fn) -> None:
        # Every pass goes through here: rain_core.bench.frame wraps this method (keep its signature) to sort the
        # GL calls it counts by pass, also when it measures older trees.
        if not self._gpu_timing:  # no timer object to look up: ~24 passes a frame
            self.stats.append(PassStat(name, True, cpu_ms(fn), None))
            return
        timer = self._timers.get(name)
        if timer is None:
            timer = self._timers[name] = PassTimer(self.ctx, gpu=False, lagged=True)
        cpu, gpu = timer.measure(fn, True)
        self._gpu_source = timer.gpu_source
        self.stats.append(PassStat(name, True, cpu, gpu))

    def render(self, frame: Frame, draw: bool = True) -> None:
        """Run every pass of one frame into the HDR target and tone-map it. ``draw=False``: a frame nobody looks
        at (a headless run that keeps only its last picture): the effects observe and update (their simulations
        advance the same) and run the stages that carry their state on the GPU from frame to frame
        (``Effect.state_stages``); nothing of the view is drawn, and ``image()`` still holds the last drawn frame.
        The next drawn frame's eye adapts over the time since the last one it metered."""
        self.scene.begin_frame()
        try:
            self._render(frame, bool(draw))
        finally:
            self.scene.end_frame()
            self._lights_cache = None
            self._mirror_plans = []
            self._effect_lights = None

    def _render(self, frame: Frame, draw: bool) -> None:
        ctx = self.ctx
        if self._gpu_timing:  # the timer queries due (two frames old), read before any pass (PassTimer.collect)
            for timer in self._timers.values():
                timer.collect()
        self.stats = []
        self._to_describe = []
        self.scene.forget_vehicles(frame.vehicles)
        observed = {}
        for effect in self.effects:
            if type(effect).observe is Effect.observe:  # the base class's: nothing to do, nothing to time
                continue
            self._timed(f"{effect.name}.observe", lambda e=effect: e.observe(frame))
            observed[effect] = self.stats.pop()
        active = tuple(e for e in self.effects if e.active(frame))
        # An effect's observe is its own work (the spray evaluates its water model there): listed with its passes
        # while it runs; an idle effect keeps its one "not run" row.
        self.stats.extend(observed[e] for e in active if e in observed)
        self.stats.extend(PassStat(e.name, False) for e in self.effects if e not in active)
        added = [lights for e in active if (lights := e.frame_lights(frame)) is not None and len(lights)]
        self._effect_lights = concat_lights(added) if added else None
        # The view's light grid is built in the scene pass.
        rc = self.render_context(frame, light_grid_px=self.light_grid_px, drawn=draw)
        # projection @ view now, just after the view's own BLAS product: first asked after the shadow's and the
        # reflection's draws (the door mirrors' plan), it ran cold.
        rc.view_proj  # noqa: B018 - made and kept by the context
        rc.active = active
        rc.shared = SharedResources()
        for effect in active:  # e.g. the rain medium, which every program of the frame sees (and an update reads)
            rc.uniforms.update(effect.frame_uniforms(frame))
        if not draw:
            self._advance(frame, rc, active)
            return
        # The frame's plan before its first GL call: on llvmpipe each draw runs the vertex work on this thread and
        # leaves Python's caches cold, and this small work cost 4-10 times as much between the passes (the
        # mirror plan ~70 µs there, ~6 µs here). The draw lists are kept for the frame (SceneDrawer.begin_frame).
        view = getattr(frame.settings, "camera", None)  # a Frame without settings: defaults, no mirrors
        mirrors = self.mirrors.views(rc) if view is not None and view.mirrors else []
        sun_up = sun_is_up(frame.lighting)
        if sun_up:
            self.scene.draw_items(rc, False, cull=self.shadow.light_view_proj(rc))
        self.scene.draw_items(rc, True, cull=True)
        if sun_up:
            rc.uniforms.update(self.shadow.frame_uniforms(rc))
        rc.frame_block_bytes()  # every frame uniform is known now: packed here, once, for all the passes
        rc.inv_view_proj  # noqa: B018 - for the sky and the post passes (a mirror view's is then this one's mirror)
        self._update_effects(frame, rc, active)
        self._run_stage("upload", rc, active)  # what the updates made new, written before the first draw
        if sun_up:
            self._timed("shadow", lambda: self.shadow.render(
                rc, self.scene.draw_items(rc, False, cull=self.shadow.light_view_proj(rc))))
        else:  # the sun is down: nothing casts a sun shadow
            self.stats.append(PassStat("shadow", False))
        self._run_stage("prepare", rc, active)
        if mirrors:
            self._timed("mirrors", lambda: self.mirrors.render(rc, mirrors))
        else:  # outside the car, out of view, too small or switched off
            self.stats.append(PassStat("mirrors", False))

        def scene():
            self.hdr.fbo.use()
            self.hdr.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
            ctx.disable(moderngl.CULL_FACE)  # meshes are not all consistently wound; shading flips back faces
            self._draw_scene(rc, mirror_view=self.mirrors.texture if mirrors else None)

        self._timed("scene", scene)
        for stage in DRAW_STAGES:
            for effect in active:
                if stage in effect.stages:
                    def draw(e=effect, s=stage):
                        self.hdr.fbo.use()
                        e.render(s, rc)
                    self._timed(f"{effect.name}.{stage}", draw)

        auto = bool(view is not None and view.auto_exposure)
        compensation = float(view.exposure_compensation_ev) if view is not None else 0.0
        self._display_ev = (auto, compensation)
        # The eye adapts over the time since the frame it last metered: this frame's step and any undrawn ones.
        unmetered_s, self._undrawn_s = self._undrawn_s, 0.0
        if auto:
            self._timed("exposure", lambda: self.exposure.update(self.hdr.color, frame.dt_s + unmetered_s,
                                                                 view.adaptation_s, compensation))
        else:
            self.stats.append(PassStat("exposure", False))
            self.exposure.reset()  # switched back on later: adapt from what the eye sees then

        def tonemap():
            ctx.disable(moderngl.DEPTH_TEST)
            ctx.disable(moderngl.BLEND)
            self.ldr.use()
            self.hdr.color.use(units.IMAGE)
            self.exposure.texture.use(units.SCRATCH[1])
            # Written by renderers alone, through OwnedUniforms: unchanged from frame to frame, skipped.
            owned_uniforms(self.tonemap_prog).update_for("tonemap", (auto, compensation), lambda: {
                "u_hdr": units.IMAGE, "u_exposure_ev": units.SCRATCH[1], "u_auto_exposure": auto,
                "u_compensation_ev": compensation})
            self._tonemap_vao.render(moderngl.TRIANGLES, vertices=3)

        self._timed("tonemap", tonemap)

    def _update_effects(self, frame: Frame, rc: RenderContext, active: tuple) -> None:
        for effect in active:
            self._timed(f"{effect.name}.update", lambda e=effect: e.update(frame, rc))
            # Its note is written when the table is asked for (pass_table): a headless frame never reads it.
            self._to_describe.append((self.stats[-1], effect))

    def _run_stage(self, stage: str, rc: RenderContext, active: tuple, state_only: bool = False) -> None:
        """``stage`` of the active effects that have it (``state_only``: of those that list it in state_stages)."""
        for effect in active:
            if stage in effect.stages and (not state_only or stage in effect.state_stages):
                self._timed(f"{effect.name}.{stage}", lambda e=effect: e.render(stage, rc))

    def _advance(self, frame: Frame, rc: RenderContext, active: tuple) -> None:
        """An undrawn frame (``render(frame, draw=False)``) after its observes and frame uniforms: the active
        effects' updates and their state stages, in the drawn frame's order (updates, uploads, prepares)."""
        self._update_effects(frame, rc, active)
        self._run_stage("upload", rc, active, state_only=True)
        self._run_stage("prepare", rc, active, state_only=True)
        self._undrawn_s += frame.dt_s

    # --- output ---------------------------------------------------------------------------------------------
    def image(self) -> np.ndarray:
        """The last tone-mapped frame, uint8 (H, W, 3) sRGB, top row first."""
        data = self.ldr.read(components=3, alignment=1)
        img = np.frombuffer(data, dtype=np.uint8).reshape(self.size[1], self.size[0], 3)
        return np.ascontiguousarray(img[::-1])

    def display_ev100(self, lighting) -> float:
        """The EV100 the last frame was displayed at: the hour's meter (``lighting.ev100``) less the stops the
        automatic exposure (or the compensation) added. Reads the GPU back: for labels, not per frame."""
        auto, compensation = getattr(self, "_display_ev", (False, 0.0))
        return float(lighting.ev100) - (self.exposure.read_ev() if auto else compensation)

    def hdr_image(self) -> np.ndarray:
        """The last pre-exposed HDR frame, float32 (H, W, 3), top row first (for tests: NaN checks, ratios)."""
        data = self.hdr.fbo.read(components=3, dtype="f4", alignment=1)
        return np.frombuffer(data, dtype=np.float32).reshape(self.size[1], self.size[0], 3)[::-1].copy()

    def present(self, fbo: moderngl.Framebuffer, viewport: tuple[int, int, int, int] | None = None) -> None:
        """Draw the last display image into ``fbo`` (a window's framebuffer), scaled to its viewport."""
        self.ctx.disable(moderngl.DEPTH_TEST)
        self.ctx.disable(moderngl.BLEND)
        fbo.use()
        if viewport is not None:
            fbo.viewport = viewport
        self.ldr_color.use(units.IMAGE)
        self.blit_prog["u_image"].value = units.IMAGE
        self._blit_vao.render(moderngl.TRIANGLES, vertices=3)

    def pass_table(self) -> list[tuple[str, bool, float, float | None, str]]:
        """(pass, ran, CPU ms, GPU ms or None, note) for each pass of the last frame. The notes (each effect's
        ``describe()``) are taken now, on the first call after the frame."""
        for stat, effect in self._to_describe:
            stat.note = effect.describe()
        self._to_describe = []
        return [(s.name, s.ran, s.cpu_ms, s.gpu_ms, s.note) for s in self.stats]

    def release(self) -> None:
        for effect in self.effects:
            effect.release()
        self.hdr.release()
        self.ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
        self.ldr.release()
        self.ldr_color.release()
        self.shadow.release()
        self.exposure.release()
        self.mirrors.release()
        self.scene.release()
        for obj in (self._tonemap_vao, self._blit_vao):
            obj.release()
        self.frame_blocks.release()
        self._timers.clear()  # moderngl queries have no release(); they go with their context
        if self._owns_shaders:
            self.shaders.release()
