"""The wet road's GL effect: the road maps as textures, the planar reflection pass, the scene shader's inputs
(shaders/road/surface.glsl and film.glsl) and a GPU evaluation of the film model for tests."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core import layout
from rain_core.effects.road.mirror import MIRROR_CLIP_PLANE, MIRROR_Y, mirror_about_road
from rain_core.effects.road.surface import wave_parameters
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import Frame, RenderContext, WaterNormals
from rain_core.gfx.linalg import inverse
from rain_core.gfx.targets import float_target
from rain_core.gfx.uniforms import mat4_bytes, owned_uniforms, set_uniform
from rain_core.gutter import frame_spread_coefficient
from rain_core.settings import RoadSection
from rain_core.water_film import (
    crack_level,
    film_depth_sampler,
    puddle_level,
    puddle_noise,
    shelter_map_for,
    smooth_heightmap_for,
)

# The scene shader's dry path (the road effect inactive), as (name, value) pairs for OwnedUniforms.update_once.
_UNBOUND = (("u_road_wet", 0.0), ("u_road_mirror", 0.0), ("u_road_debug", 0.0), ("u_road_reflect", 0.0))
# The reflection pass's own inputs: no reflection, ripples, rain rings or cabin in the mirrored view.
_MIRROR_PASS = (("u_road_mirror", 1.0), ("u_road_reflect", 0.0), ("u_road_ripple_window", (0.0, 0.0, 1.0, 0.0)),
                ("u_road_rain_rings_tile", (1.0, 0.0)), ("u_road_cabin_box", (0.0, 0.0, 0.0, 0.0)))


def _any_positive(levels: tuple[float, float, float]) -> bool:
    """any(v > 0.0 for v in levels) without a generator (NaN counts as not positive, as there)."""
    return levels[0] > 0.0 or levels[1] > 0.0 or levels[2] > 0.0


class RoadEffect(Effect):
    """The wet road effect. ``RoadEffect(ctx, settings=None, *, seed=0, shaders=None)``: settings are used when
    a frame carries none; shaders (a ShaderLibrary) only for ``film_depth_gpu`` (made on demand if None); the
    puddle noise's seed is ``settings.road.puddle_seed`` (``seed`` is unused: the one factory signature). The
    world (road heightmap, roofs) is ``frame.world`` at the first update, or ``set_world``.

    Per frame: levels from ``frame.weather`` (wetness, cracks, puddles in [0, 1], pins already applied), the
    rest from ``settings.road``. ``active`` is False when the road is dry (all three levels 0) or the effect is
    disabled — then the scene shader's dry path runs and no reflection pass is drawn. The ``prepare`` stage
    draws the planar reflection through ``rc.renderer.draw_mirror_view`` (scene mirrored about y = 0, clipped
    below the road, at ``reflection_scale`` of the frame, mipmapped for rough reflections). ``bind_scene``
    feeds shaders/road/surface.glsl.

    Shared (``rc.shared``): ``update`` publishes ``film_depth_fn`` (x_m, z_m → standing water depth in mm, world
    z, at this frame's levels); ``bind_scene`` reads ``water_normals`` (ripple slopes; unless
    ``set_ripple_normals`` was called) and ``rain_rings`` (raindrop rings on standing water).
    """

    name = "road"
    stages = ("prepare",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders=None):
        self.ctx = ctx
        self.settings = settings
        self.shaders = shaders  # only the film-depth evaluation needs its own program (made on demand)
        self._own_shaders = False
        self.world = None
        self._height_tex: moderngl.Texture | None = None
        self._shelter: np.ndarray | None = None
        self._maps_tex: moderngl.Texture | None = None
        self._maps_seed: int | None = None
        self._black = ctx.texture((1, 1), 4, np.zeros(4, np.float32).tobytes(), dtype="f4")
        self._reflection = None  # RenderTarget, created at the first reflection pass
        self._reflection_valid = False
        self._planned_view = None  # (render context, (target, mirrored camera)) of the frame's reflection pass
        self._reflects = None  # (frame, needs_reflection(frame)) decided in update
        self._sampler = None  # (key, world, film_depth_sampler) of the last frame
        self._mirror_pass = False  # True while the reflection pass draws: no reflection, ripples, rings, cabin
        self._ripple_explicit = False
        self._ripple: WaterNormals | None = None
        self._film_prog = None
        self._film_vao = None
        self._film_target = None
        self._levels = (0.0, 0.0, 0.0)
        self._gutter_k = 0.0  # the kerb streams' spread coefficient this frame (rain_core.gutter)
        self._road = None
        self._waves = (0.0, 0.0, 0.0)
        self._film_values = None  # (levels key, film uniform pairs, world) last made
        self._scene_plan = None  # (key, projection, {mirror pass: the scene inputs that stay}), see _plan_scene
        self._cabin_spec = None  # (car spec, cabin box)
        self._cabin_inv = None  # (ego model array, shift_z, u_road_cabin bytes), made in update

    def set_world(self, world) -> None:
        """Take the road heightmap and roofs of ``world`` (done on the first update from ``frame.world`` when
        none was set)."""
        if world is self.world:
            return
        hmap = np.ascontiguousarray(np.stack([world.road_heightmap, smooth_heightmap_for(world)], axis=-1),
                                    dtype=np.float32)
        for tex in (self._height_tex, self._maps_tex):
            if tex is not None:
                tex.release()
        self._height_tex = self.ctx.texture((hmap.shape[1], hmap.shape[0]), 2, hmap.tobytes(), dtype="f4")
        self._height_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._height_tex.repeat_x, self._height_tex.repeat_y = False, True
        self._shelter = shelter_map_for(world)
        self._maps_tex = self._maps_seed = None
        self.world = world

    # --- settings and levels ---
    def _road_settings(self, frame: Frame):
        settings = frame.settings if frame.settings is not None else self.settings
        return RoadSection() if settings is None else settings.road

    @staticmethod
    def levels(frame: Frame) -> tuple[float, float, float]:
        """(wetness, cracks, puddles) in [0, 1] from the frame's weather (0 without weather)."""
        weather = frame.weather
        if weather is None:
            return 0.0, 0.0, 0.0
        # Spelled out, no generator: asked three times a frame (active, update, needs_reflection)
        return (min(max(float(weather.wetness), 0.0), 1.0), min(max(float(weather.cracks), 0.0), 1.0),
                min(max(float(weather.puddles), 0.0), 1.0))

    def active(self, frame: Frame) -> bool:
        road = self._road_settings(frame)
        return bool(road.enabled) and (_any_positive(self.levels(frame)) or bool(road.debug_regions))

    def needs_reflection(self, frame: Frame) -> bool:
        """Whether this frame draws the reflection pass: reflections on, water on the road, not the debug view."""
        road = self._road_settings(frame)
        return (bool(road.enabled and road.reflections) and not road.debug_regions
                and _any_positive(self.levels(frame)))

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
        Once called, this wins over ``rc.shared.water_normals``."""
        self._ripple_explicit = True
        self._ripple = None if texture is None else WaterNormals(
            texture, (float(origin_xz_m[0]), float(origin_xz_m[1])), float(extent_m))

    def bind_film_uniforms(self, program, wetness: float, cracks: float, puddles: float, puddle_amount: float,
                           seed: int, gutter_k: float = 0.0) -> None:
        """Bind the maps and levels of shaders/road/film.glsl on a program that includes it:
        road_film_depth_mm(xz) then gives the film depth at wrapped-frame positions. gutter_k: the kerb streams'
        spread coefficient (rain_core.gutter; 0 without)."""
        pairs = self._film_pairs(wetness, cracks, puddles, puddle_amount, gutter_k)
        self._height_tex.use(units.ROAD_HEIGHT)
        self._maps(int(seed)).use(units.ROAD_MAPS)
        owned_uniforms(program).update_pairs(pairs)

    def _film_pairs(self, wetness, cracks, puddles, puddle_amount, gutter_k) -> tuple:
        """shaders/road/film.glsl's uniforms as (name, value) pairs: the same tuple while the levels stay."""
        if self.world is None:
            raise RuntimeError("RoadEffect has no world yet: call set_world or render a frame first")
        key = (float(wetness), float(cracks), float(puddles), float(puddle_amount), float(gutter_k))
        if self._film_values is None or self._film_values[0] != key or self._film_values[2] is not self.world:
            self._film_values = (key, (
                ("u_road_height", units.ROAD_HEIGHT), ("u_road_maps", units.ROAD_MAPS),
                ("u_road_levels", (key[0], crack_level(cracks), puddle_level(puddles, puddle_amount), key[4])),
                ("u_road_height_extent", tuple(float(v) for v in self.world.heightmap_extent_m))), self.world)
        return self._film_values[1]

    # --- per frame ---
    def update(self, frame: Frame, rc: RenderContext) -> None:
        if self.world is None:
            self.set_world(frame.world)
        road = self._road_settings(frame)
        self._road = road
        self._levels = _, c, p = self.levels(frame)
        self._maps(int(road.puddle_seed))
        wind = getattr(getattr(frame.weather, "wind", None), "velocity_m_s", (0.0, 0.0, 0.0))
        self._waves = wave_parameters(wind, road.wave_strength)
        amount, seed, world = float(road.puddle_amount), int(road.puddle_seed), self.world
        self._gutter_k = k = frame_spread_coefficient(frame)

        # Everything the depths depend on besides (x, z): consumers may cache depths while the key is unchanged
        # (the ripples then ask only for cells that scrolled into their field).
        key = ("film", c, p, amount, seed, id(world), k)
        if self._sampler is None or self._sampler[0] != key or self._sampler[1] is not world:
            # film_depth_mm with these arguments checked once (the same values bit for bit), kept while they stay
            self._sampler = (key, world, film_depth_sampler(c, p, amount, seed, world, gutter_k=k))
        sampler = self._sampler[2]

        def standing(x_m, z_m):
            x, z = np.asarray(x_m, dtype=np.float64), np.asarray(z_m, dtype=np.float64)
            if x.shape != z.shape:
                x, z = np.broadcast_arrays(x, z)
            return sampler(x, z)

        standing.cache_key = key
        rc.shared.film_depth_fn = standing
        self._reflection_valid = False
        if not rc.drawn:  # the rest plans the frame's picture: the cabin, the scene's inputs, the reflection
            return
        ego = frame.ego
        if frame.camera.inside_car and ego is not None:
            # The main view's u_road_cabin made now, before the frame's draws (LAPACK's code is warm: the renderer
            # has just inverted the view-projection); bind_scene then finds it kept. Made between the draws (in
            # the reflection or the scene pass) it cost ~85 µs instead of ~10.
            self._cabin_inverse(ego, rc.shift_z)
        self._plan_scene(road, rc.projection)
        self._reflects = (frame, self.needs_reflection(frame))
        if self._reflects[1]:
            # The reflection's camera and context planned now, before the frame's draws (see mirror_context)
            target, camera = self._reflection_view(rc)
            rc.renderer.mirror_context(rc, target, camera, MIRROR_Y)

    def render(self, stage: str, rc: RenderContext) -> None:
        if stage != "prepare":
            return
        decided = self._reflects  # update's answer: asked again here, between the draws, it cost ~10 µs
        if decided is None or decided[0] is not rc.frame:  # not updated for this frame
            decided = (rc.frame, self.needs_reflection(rc.frame))
        if decided[1]:
            self._render_reflection(rc)

    def _reflection_target(self, size: tuple[int, int]):
        if self._reflection is None or self._reflection.size != size:
            if self._reflection is not None:
                self._reflection.release()
            self._reflection = float_target(self.ctx, size, 4, "f2", depth=True)
            self._reflection.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        return self._reflection

    def _reflection_view(self, rc: RenderContext):
        """(target, the camera mirrored about the road) of ``rc``'s reflection pass, made once per context."""
        planned = self._planned_view
        if planned is not None and planned[0] is rc:
            return planned[1]
        scale = float(self._road_settings(rc.frame).reflection_scale)
        size = (max(1, round(rc.size[0] * scale)), max(1, round(rc.size[1] * scale)))
        view = (self._reflection_target(size), mirror_about_road(rc.frame.camera))
        self._planned_view = (rc, view)
        return view

    def _render_reflection(self, rc: RenderContext) -> None:
        target, camera = self._reflection_view(rc)
        self._mirror_pass = True
        try:
            rc.renderer.draw_mirror_view(rc, target, camera, MIRROR_Y, MIRROR_CLIP_PLANE)
        finally:
            self._mirror_pass = False
        target.color.build_mipmaps()
        self._reflection_valid = True

    def reflection_image(self) -> np.ndarray | None:
        """The last reflection pass as pre-exposed HDR float32 (H, W, 3), top row first (None if none ran)."""
        if self._reflection is None or not self._reflection_valid:
            return None
        data = self._reflection.fbo.read(components=3, dtype="f4", alignment=1)
        w, h = self._reflection.size
        return np.frombuffer(data, dtype=np.float32).reshape(h, w, 3)[::-1].copy()

    # --- the scene shader's inputs ---
    def bind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        # The road alone writes u_road_* in the scene programs. What stays from frame to frame was planned in
        # update (_plan_scene) as one tuple per view: one identity test while it stays (the reflection pass has
        # nothing else); owned_uniforms skips the rest's values it wrote last.
        road = self._road if self._road is not None else self._road_settings(rc.frame)
        mirror = self._mirror_pass
        plan = self._scene_plan
        if plan is None or plan[1] is not rc.projection:
            plan = self._plan_scene(road, rc.projection)
        self._height_tex.use(units.ROAD_HEIGHT)
        self._maps(int(road.puddle_seed)).use(units.ROAD_MAPS)
        out = owned_uniforms(program)
        out.update_once(plan[2][mirror])
        out.set("u_road_waves", self._waves)  # the wind's: changes with the gusts
        if mirror:  # never the texture being drawn into
            for unit in (units.ROAD_REFLECTION, units.ROAD_RIPPLES, units.ROAD_RAIN_RINGS):
                self._black.use(unit)
            return
        if self._reflection_valid:
            self._reflection.color.use(units.ROAD_REFLECTION)
            out.set("u_road_reflect", 1.0)
        else:
            self._black.use(units.ROAD_REFLECTION)
            out.set("u_road_reflect", 0.0)
        ripple = self._ripple if self._ripple_explicit else rc.shared.water_normals
        if ripple is not None:
            ripple.texture.use(units.ROAD_RIPPLES)
            ox, oz = (float(v) for v in ripple.origin_xz_m)
            out.set("u_road_ripple_window", (ox, oz - rc.shift_z, float(ripple.extent_m), 1.0))
        else:
            self._black.use(units.ROAD_RIPPLES)
            out.set("u_road_ripple_window", (0.0, 0.0, 1.0, 0.0))
        rings = rc.shared.rain_rings
        if rings is not None:
            rings.texture.use(units.ROAD_RAIN_RINGS)
            out.set("u_road_rain_rings_tile", (float(rings.tile_m), 1.0))
        else:
            self._black.use(units.ROAD_RAIN_RINGS)
            out.set("u_road_rain_rings_tile", (1.0, 0.0))
        ego = rc.frame.ego
        if rc.frame.camera.inside_car and ego is not None:
            out.set("u_road_cabin", self._cabin_inverse(ego, rc.shift_z))
            out.set("u_road_cabin_box", self._cabin_box(ego.spec))
        else:
            out.set("u_road_cabin_box", (0.0, 0.0, 0.0, 0.0))

    def _plan_scene(self, road, projection: np.ndarray) -> tuple:
        """(key, projection, {mirror pass: pairs}): the scene shader's road inputs that only the levels, the
        settings and the lens change (film, texture units, debug view, projection scale; in the reflection pass
        also its fixed ones), the same tuples while they stay so that bind_scene writes them through
        ``OwnedUniforms.update_once``. Made in update, before the frame's draws, where it is cheap."""
        w, c, p = self._levels
        film = self._film_pairs(w, c, p, road.puddle_amount, self._gutter_k)
        key = (bool(road.debug_regions), 0.5 * float(projection[0, 0]), 0.5 * float(projection[1, 1]))
        plan = self._scene_plan
        if plan is not None and plan[0][0] is film and plan[0][1:] == key:
            if plan[1] is not projection:
                plan = self._scene_plan = (plan[0], projection, plan[2])
            return plan
        shared = film + (
            ("u_road_wet", 1.0), ("u_road_debug", 1.0 if key[0] else 0.0), ("u_road_proj_scale", key[1:]),
            ("u_road_reflection", units.ROAD_REFLECTION), ("u_road_ripples", units.ROAD_RIPPLES),
            ("u_road_rain_rings", units.ROAD_RAIN_RINGS))
        plan = self._scene_plan = ((film, *key), projection,
                                   {False: shared + (("u_road_mirror", 0.0),), True: shared + _MIRROR_PASS})
        return plan

    def _cabin_inverse(self, ego, shift_z: float) -> bytes:
        """u_road_cabin: the inverse of the ego's model matrix in the wrapped frame, kept while its read-only model
        array (the same object while the pose stays) and the shift are the same."""
        model = ego.model_matrix()
        cached = self._cabin_inv
        if cached is not None and cached[0] is model and cached[1] == shift_z:
            return cached[2]
        shifted = model.copy()
        shifted[2, 3] -= shift_z
        data = mat4_bytes(inverse(shifted))
        self._cabin_inv = (model, shift_z, data) if not model.flags.writeable else None
        return data

    def _cabin_box(self, spec) -> tuple:
        """(cowl z + 2 cm, 0.2, half width + 5 cm, 1): where the cabin hides the road (per car spec)."""
        if self._cabin_spec is None or self._cabin_spec[0] is not spec:
            from rain_core.car_mesh import windshield_frame

            cowl = windshield_frame(spec)["bottom_center"]
            self._cabin_spec = (spec, (float(cowl[2]) + 0.02, 0.2, spec.width_m / 2 + 0.05, 1.0))
        return self._cabin_spec[1]

    def unbind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        owned_uniforms(program).update_once(_UNBOUND)  # bind_scene's tuples are then written in full again

    # --- GPU twin of film_depth_mm ---
    def film_depth_gpu(self, x_m, z_m, cracks, puddles, puddle_amount=0.5, seed=0, wetness=0.0,
                       gutter_k=0.0) -> np.ndarray:
        """The shader's road_water_depths_mm at points x, z (m, arrays of one shape; world z): float32 array of
        shape (…, 2) = (standing water, wet film) in mm. For tests and for CPU-side users of the GPU model."""
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
                from rain_core.gfx.shaders import ShaderLibrary

                self.shaders = ShaderLibrary(self.ctx)
                self._own_shaders = True
            self._film_prog = self.shaders.program("common/fullscreen.vert", "road/film.frag")
            self._film_vao = self.ctx.vertex_array(self._film_prog, [])
        prog = self._film_prog
        target = self._film_target
        if target is None or target.size != (width, height):
            if target is not None:
                target.release()
            target = self._film_target = float_target(self.ctx, (width, height), 4, "f4", filter_linear=False)
        points = self.ctx.texture((width, height), 2, pts.tobytes(), dtype="f4")
        points.filter = (moderngl.NEAREST, moderngl.NEAREST)
        try:
            self.bind_film_uniforms(prog, wetness, cracks, puddles, puddle_amount, seed, gutter_k)
            points.use(units.SCRATCH[0])
            set_uniform(prog, "u_points", units.SCRATCH[0])
            self.ctx.disable(moderngl.BLEND)
            self.ctx.disable(moderngl.DEPTH_TEST)
            target.fbo.use()
            self._film_vao.render(moderngl.TRIANGLES, vertices=3)
            out = np.frombuffer(target.fbo.read(components=4, dtype="f4", alignment=1), dtype=np.float32)
        finally:
            points.release()
        return out.reshape(-1, 4)[:n, :2].reshape(*shape, 2)

    def release(self) -> None:
        """Free the textures, targets and vertex array, and the film program when the shader library is our own
        (a shared library caches its programs for every user)."""
        for obj in (self._height_tex, self._maps_tex, self._black, self._film_vao):
            if obj is not None:
                obj.release()
        for target in (self._reflection, self._film_target):
            if target is not None:
                target.release()  # parks on the default framebuffer first
        if self._own_shaders and self._film_prog is not None:
            self._film_prog.release()
        self._height_tex = self._maps_tex = self._black = self._reflection = self._film_target = None
        self._film_vao = self._film_prog = None
