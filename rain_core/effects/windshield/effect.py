"""``WindshieldEffect``: runs ``WindshieldSim`` and draws the water on the glass and the refraction through it.

The GPU water texture is a *rendering* of the simulation's state plus purely visual detail: drops are splatted
into a height texture each frame, and a high-resolution film texture carries what the coarse CPU grid cannot
(streaks of wiper residue, wet trail lines, splash speckle, the slow beading of a thin film). Each frame that
texture is rescaled so that its local mean over a coarse cell equals the CPU film there (its mipmap at the
coarse level is the cell mean), so the picture never shows water the bookkeeping does not have.
"""

from __future__ import annotations

import math
import struct

import moderngl
import numpy as np

from rain_core.car_mesh import windshield_surface
from rain_core.checks import MAX_FRAME_DT_S
from rain_core.effects.windshield.constants import FILM_CELLS, HEIGHT_PER_RADIUS, SPHERE_PER_RADIUS
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.sim import WindshieldSim
from rain_core.effects.windshield.splats import DropRows, FilmRows
from rain_core.effects.windshield.water_pass import (  # noqa: F401 - the water pass's constants, re-exported
    _UNIT_A,
    _UNIT_B,
    _UNIT_C,
    _UNIT_D,
    BEAD_LIFE_S,
    FILM_BEAD_RATE_PER_S,
    FILM_DIFFUSION_M2_S,
    WaterPass,
)
from rain_core.gfx.effect import Effect
from rain_core.gfx.light_grid import LightGrid
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import depth_value_sampler, float_target, fullscreen_triangle
from rain_core.gfx.uniforms import mat4_bytes, owned_uniforms, set_uniform, set_uniforms
from rain_core.vehicles import CAR_SPEC, VehicleSpec

CABIN_DEPTH_M = 1.3  # the frame nearer than this (view depth) is the cabin: refracted rays see past it
PUPIL_RADIUS_M = 0.002  # the driver's eye, focused on the road, sees each point of the glass through its pupil
EYE_APERTURE_BLUR = 0.0037  # blur through water as a fraction of the frame height (a ~4 mm pupil at ~1 m)
FILM_EXTRA_LOD = 2.5  # the misted film shows the street this many mip levels blurrier than a drop does
DROP_LENS = 0.5  # the lens's slopes × the contact angle's: seen at the raked glass's grazing angle the full cap
# is mostly totally reflecting (a black blot); drops on a real, used windshield sit flatter than on clean glass
DROP_RIM = 0.45  # darkening of a drop towards its outline, on top of the Fresnel reflection of the cabin
DROP_HIGHLIGHT = 6.0  # the sky focused by the cap: its highlight is brighter than the sky, × the zenith radiance
_DROP_FORMAT = "4f 1f/i"  # splats.DROP_ROW: a drop's (s, t, vs, vt) or a bead's line, and the radius


def roof_height(world, x: float, z: float) -> float:
    """The roof height (m) over one point (x, z) m: ``World.occluder_height_at`` (Python scalars); a world without
    it (a test double) is asked through ``occluder_height``."""
    at = getattr(world, "occluder_height_at", None)
    return at(x, z) if at is not None else float(np.asarray(world.occluder_height(x, z)))


class WindshieldEffect(WaterPass, Effect):
    """The windshield effect: runs ``WindshieldSim``, draws the glass.

    Stages: ``upload`` (the CPU film and the splat rows the update made, written before the frame's first draw),
    ``prepare`` (the water textures: film relaxation and deposits with the beads of drops' trails, drop
    and bead splats, the water thickness/slope texture) and ``overlay`` (copy the frame without the glass, then
    draw the glass mesh over it with the film's refraction, beads, haze, glints and the blades, then each drop
    as an analytic lens from the same instance rows the drop texture was splatted with). Active only with the
    camera inside the car and the effect enabled, and then only if there is water on the glass, rain reaching
    it, or the wipers are running: a dry, clean glass costs nothing.

    ``WindshieldEffect(ctx, settings=None, *, seed=0, shaders=None, spec=CAR_SPEC)``. ``status()`` gives numbers
    for a panel (drops, water on the glass in g, wiper cycles, rain-sensor reading).
    """

    name = "windshield"
    stages = ("upload", "prepare", "overlay")
    # The water pass (upload, prepare) relaxes last frame's film texture and adds the step's trails: the glass's
    # state on the GPU, stepped in every frame, drawn or not.
    state_stages = ("upload", "prepare")

    def __init__(self, ctx, settings=None, *, seed: int = 0, shaders=None, spec: VehicleSpec = CAR_SPEC):
        self.ctx = ctx
        self._owns_shaders = shaders is None  # then the programs are ours to release
        self.shaders = shaders or ShaderLibrary(ctx)
        self.settings = settings
        self.seed = int(seed)
        self.sim = WindshieldSim(spec, seed)
        self.glass = self.sim.glass
        self._right_up = (self.glass.right.tolist(), self.glass.up.tolist())  # the glass's axes, car-local
        self._centre_local = self.glass.local_points(np.array([[0.0, 0.5 * self.glass.height]]))[0].tolist()
        self._shelter_memo = None  # ((world, x, z), roof height m) of the last _sheltered lookup
        self.film_prog = self.shaders.program("common/fullscreen.vert", "windshield/film.frag")
        self.normals_prog = self.shaders.program("common/fullscreen.vert", "windshield/normals.frag")
        self.splat_prog = self.shaders.program("windshield/splat.vert", "windshield/splat.frag")
        self.drop_splat_prog = self.shaders.program("windshield/drop_splat.vert", "windshield/splat.frag")
        self.glass_prog = self.shaders.program("windshield/glass.vert", "windshield/glass.frag")
        self.drop_prog = self.shaders.program("windshield/drop.vert", "windshield/drop.frag")
        self.copy_prog = self.shaders.program("common/fullscreen.vert", "windshield/frame_copy.frag")
        set_uniforms(self.copy_prog, u_color=_UNIT_A, u_depth=_UNIT_B)
        LightGrid.read_by(self.glass_prog, self.drop_prog)  # their glints visit the tile's lights
        progs = (self.film_prog, self.normals_prog, self.splat_prog, self.drop_splat_prog, self.glass_prog,
                 self.drop_prog)
        for prog in progs:
            set_uniform(prog, "u_glass", (self.glass.width_bottom, self.glass.width_top, self.glass.height))
        self.splat_prog["u_cap_rn"].value = SPHERE_PER_RADIUS
        set_uniforms(self.drop_splat_prog, u_cap_rn=SPHERE_PER_RADIUS, u_height_per_radius=HEIGHT_PER_RADIUS)
        g = self.glass
        set_uniforms(
            self.drop_prog,
            u_cap_rn=SPHERE_PER_RADIUS,
            u_glass_origin=tuple(g.bottom_center),
            u_glass_right=tuple(g.right),
            u_glass_up=tuple(g.up),
            u_glass_normal=tuple(g.normal),
            u_glass_sag=g.sag,
            u_rim=DROP_RIM,
            u_lens=DROP_LENS,
            u_highlight=DROP_HIGHLIGHT,
        )
        # Each program's OwnedUniforms, looked up once (owned_uniforms keeps one per program while it lives).
        self._film_u, self._splat_u, self._normals_u, self._glass_u, self._drop_u = (
            owned_uniforms(p) for p in (self.film_prog, self.drop_splat_prog, self.normals_prog, self.glass_prog,
                                        self.drop_prog))
        self._film_vao = fullscreen_triangle(ctx, self.film_prog)
        self._copy_vao = fullscreen_triangle(ctx, self.copy_prog)
        # The frame's depth read as values (its texture compares by default), by the frame copy.
        self._depth_sampler = depth_value_sampler(ctx)
        self._normals_vao = fullscreen_triangle(ctx, self.normals_prog)
        pos, nrm, uv, tris = windshield_surface(spec, 48, 24)
        verts = np.hstack([pos, nrm, uv]).astype(np.float32)
        self._mesh_vbo = ctx.buffer(verts.tobytes())
        self._mesh_ibo = ctx.buffer(np.asarray(tris, np.int32).tobytes())
        self._glass_vao = ctx.vertex_array(
            self.glass_prog,
            [(self._mesh_vbo, "3f 3f 2f", "in_position", "in_normal", "in_uv")],
            index_buffer=self._mesh_ibo,
            index_element_size=4,
        )
        # One instance buffer per water target (film deposits, drops), each written once a frame with only what
        # the frame draws, then drawn with one instanced call (so no buffer is rewritten while a draw may read it).
        # The drop rows are the drops' positions, velocities and radii as they are (splats.DROP_ROW): the shaders
        # lay the tails and widen the sub-texel drops.
        self._splat_bufs = [ctx.buffer(reserve=32 * 1024) for _ in range(2)]
        self._splat_vaos = [
            ctx.vertex_array(self.splat_prog, [(self._splat_bufs[0], "4f 4f/i", "in_seg", "in_info")]),
            ctx.vertex_array(self.drop_splat_prog, [(self._splat_bufs[1], _DROP_FORMAT, "in_seg", "in_radius")]),
        ]
        # The drop pass reads the drops' rows where the drop texture's splats left them: nothing more is uploaded.
        self._drop_vao = ctx.vertex_array(self.drop_prog, [(self._splat_bufs[1], _DROP_FORMAT, "in_seg", "in_radius")])
        self._drop_builder = DropRows()
        self._early = None  # what update made for the water pass: water_pass._make_rows_early
        self._uploaded = None  # (rc, film splats, drop splats) the upload stage wrote for the water pass
        self._film_builder = FilmRows()
        self._drop_rows = 0  # rows in the drop buffer this frame
        self.upload_bytes = 0  # bytes written to the GPU by the last frame's water pass
        self.splat_draws = 0  # instanced splat draws in the last frame
        self.resolution = 0
        self._film: list = []
        self._film_index = 0
        # The CPU film as half floats (the film texture it rescales is half float too): half the upload.
        self._coarse = [ctx.texture((FILM_CELLS, FILM_CELLS), 1, dtype="f2") for _ in range(2)]
        for tex in self._coarse:
            tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            tex.write(np.zeros((FILM_CELLS, FILM_CELLS), np.float16).tobytes())
        self._coarse_index = 0
        self._coarse_scratch = None  # (float64, float32 and uint16 arrays, flat views) of _coarse_bits
        self._frame_copy = None
        self._last_time: float | None = None
        self._inputs = GlassInputs()
        self._dt = 0.0
        self._token = object()  # names this instance in the static uniform keys (update_for)
        self._blades_memo = None  # (sim.blades, their u_blade bytes)
        self._inputs_memo = None  # (what the last GlassInputs was made of, it, its settings' types): inputs_for
        self._head_memo = (None, 0.0)  # (inputs, the head wind over the glass that dries the film, m/s)

    # --- resources ------------------------------------------------------------------------------------------
    @property
    def water_texture(self) -> moderngl.Texture | None:
        """The water texture of the last frame (RGBA f16 over the glass's UV square: drop thickness mm, film µm,
        slopes), or None before the first ``prepare``."""
        return self._water.color if self.resolution else None

    def _ensure_frame_copy(self, size: tuple[int, int]):
        if self._frame_copy is None or self._frame_copy.size != tuple(size):
            if self._frame_copy is not None:
                self._frame_copy.release()
            self._frame_copy = float_target(self.ctx, size, 4, "f2", depth=True)
            self._frame_copy.depth.compare_func = ""
            self._frame_copy.color.build_mipmaps()
            self._frame_copy.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        return self._frame_copy

    # --- the contract ---------------------------------------------------------------------------------------
    def _settings(self, frame):
        return frame.settings if frame.settings is not None else self.settings

    def _sheltered(self, frame) -> bool:
        """Whether a roof is over the glass's centre. ``active`` and ``inputs_for`` both ask each frame: the
        answer for the last world and position is kept (the occluders do not move), so the lookup runs once."""
        ego = frame.ego
        lx, ly, lz = self._centre_local  # ego.to_world of the glass centre, in scalars
        c, s = math.cos(ego.yaw), math.sin(ego.yaw)
        px, py, pz = ego.position.tolist()
        x, y, z = lx * c + lz * s + px, ly + py, -lx * s + lz * c + pz
        key = (frame.world, x, z)
        memo = self._shelter_memo
        if memo is None or memo[0][0] is not key[0] or memo[0][1:] != key[1:]:
            memo = self._shelter_memo = (key, roof_height(frame.world, x, z))
        return memo[1] > y

    def active(self, frame) -> bool:
        settings = self._settings(frame)
        if not frame.camera.inside_car or frame.ego is None:
            return False
        if settings is not None and not settings.windshield.enabled:
            return False
        if self.sim.has_water() or self.sim.wipers.running:
            return True
        if settings is not None and settings.wipers.mode in ("intermittent", "low", "high"):
            return True
        scale = settings.windshield.drop_scale if settings is not None else 1.0
        return frame.rain_rate_mm_h > 0.0 and scale > 0.0 and not self._sheltered(frame)

    def inputs_for(self, frame) -> GlassInputs:
        """The GlassInputs of a frame (weather, ego motion, roof, settings). The last one is given again while
        everything it is made of is the same (a parked car): not checked again, and the simulation's per-inputs
        work is skipped for the same object."""
        settings = self._settings(frame)
        ego = frame.ego
        wind = np.zeros(3)
        if frame.weather is not None:
            wind = np.asarray(frame.weather.wind.velocity_m_s, dtype=np.float64)
        kw = {}
        if settings is not None:
            w, ws = settings.wipers, settings.windshield
            kw = dict(
                drop_scale=ws.drop_scale,
                drop_budget=ws.drop_budget,
                wiper_mode=w.mode,
                wiper_interval_s=w.interval_s,
                wiper_low_cpm=w.low_cycles_per_min,
                wiper_high_cpm=w.high_cycles_per_min,
                wiper_sensitivity=w.auto_sensitivity,
                blade_wear=w.blade_wear,
            )
        velocity = ego.velocity()
        rotation = ego.model_matrix()[:3, :3]
        sheltered = self._sheltered(frame)
        # Compared as bytes: the same bits give the same checked inputs.
        key = (frame.rain_rate_mm_h, velocity.tobytes(), wind.tobytes(), rotation.tobytes(), sheltered,
               *kw.values())
        memo = self._inputs_memo
        if memo is not None and memo[0] == key:
            return memo[1]
        types = tuple(map(type, kw.values()))  # (1 and True are equal, not checked alike)
        if memo is not None and memo[0][5:] == key[5:] and memo[2] == types:  # the same settings: only the motion
            inputs = memo[1].moved(frame.rain_rate_mm_h, velocity, wind, rotation, sheltered)
        else:
            inputs = GlassInputs(
                rate_mm_h=frame.rain_rate_mm_h,
                car_velocity_m_s=velocity,
                wind_m_s=wind,
                car_rotation=rotation,
                sheltered=sheltered,
                **kw,
            )
        self._inputs_memo = (key, inputs, types)
        return inputs

    def update(self, frame, rc) -> None:
        # The time since the last update: the scene may step several times between renders.
        if self._last_time is None or frame.time_s < self._last_time:
            dt = float(frame.dt_s)
        else:
            dt = float(frame.time_s - self._last_time)
        self._last_time = float(frame.time_s)
        self._inputs = self.inputs_for(frame)
        self._dt = min(dt, MAX_FRAME_DT_S)
        sim = self.sim
        sim.step(self._dt, self._inputs)
        if rc is not None:
            self._make_rows_early(rc)

    def render(self, stage: str, rc) -> None:
        if stage == "upload":
            self._upload_water(rc)
        elif stage == "prepare":
            self._draw_water(rc)
        elif stage == "overlay":
            self._draw_glass(rc)

    def describe(self) -> str:
        st = self.status()
        return f"{st['drops']} drops, {st['water_g']:.1f} g on the glass, {st['wipe_cycles']} wipes"

    def status(self) -> dict:
        """Numbers for the Rain Manager: drops, water on the glass (g), wiper cycles, sensor (g/m²)."""
        sim = self.sim
        return {
            "drops": sim.count,
            "water_g": 1e3 * sim.mass_on_glass(),
            "film_g": 1e3 * float(sim.film.sum()),
            "wipe_cycles": sim.wipers.cycles,
            "sensor_g_m2": 1e3 * sim.sensor_kg_m2,
            "arrived_g": 1e3 * sim.arrived,
            "wiped_g": 1e3 * sim.wiped,
            "shed_g": 1e3 * sim.shed,
            "upload_kb": self.upload_bytes / 1024.0,
        }

    # --- the glass ------------------------------------------------------------------------------------------
    def _draw_glass(self, rc) -> None:
        ctx = self.ctx
        frame = rc.frame
        settings = self._settings(frame)
        copy = self._copy_frame(rc)
        prog = self.glass_prog
        rc.set_frame_uniforms(prog)
        # The car's uniforms in Python floats (a few NumPy calls on 3- and 4-vectors cost more than the arithmetic).
        model = frame.ego.model_matrix().tolist()
        model[2][3] -= rc.shift_z
        lighting = frame.lighting
        exposure = float(lighting.exposure)
        cabin = tuple(0.02 * 0.5 * (float(z) + float(h)) * exposure
                      for z, h in zip(lighting.sky_zenith, lighting.sky_horizon, strict=True))
        camera = frame.camera
        blades = self._blades_bytes()
        refraction = float(settings.windshield.refraction) if settings is not None else 1.0
        focus = min(float(getattr(camera, "focus_m", math.inf)), 1e9)
        # What the glass pass and the drop pass both read: the view's (written when it changes) and the car's.
        view_key = (self._token, self.resolution, blades, rc.size[1], refraction, focus, camera.near_m,
                    camera.far_m, camera.fov_y_deg)

        def view_values() -> dict:
            return dict(
                u_refraction=refraction,
                u_drop_lod=math.log2(max(1.0, EYE_APERTURE_BLUR * rc.size[1])) + 0.5,
                u_aperture_m=PUPIL_RADIUS_M,
                u_focus_m=focus,
                u_near_far=(camera.near_m, camera.far_m),
                u_cabin_depth=CABIN_DEPTH_M,
                u_frame=_UNIT_B,
                u_depth=_UNIT_C,
            )

        right, up = self._right_up
        moving = dict(
            u_model=struct.pack("16f", *(row[c] for c in range(4) for row in model)),  # mat4_bytes: column-major
            u_axis_s=tuple(r0 * right[0] + r1 * right[1] + r2 * right[2] for r0, r1, r2, _ in model[:3]),
            u_axis_t=tuple(r0 * up[0] + r1 * up[1] + r2 * up[2] for r0, r1, r2, _ in model[:3]),
            u_cabin=cabin,
        )

        def glass_values() -> dict:
            values = view_values()
            values.update(
                u_film_lod=values["u_drop_lod"] + FILM_EXTRA_LOD,
                u_texel_m=self._texel_m() if self.resolution else 0.0,
                u_beads=_UNIT_D,
                u_blade=blades,
                u_water=_UNIT_A,
            )
            return values

        owned = self._glass_u
        owned.update_for("static", view_key, glass_values)
        owned.update(moving)
        angles = self.sim.blade_angles()
        owned.set("u_blade_angle", struct.pack(f"{len(angles)}f", *angles))
        self._water.color.use(_UNIT_A)
        copy.color.use(_UNIT_B)
        copy.depth.use(_UNIT_C)
        self._film[self._film_index].color.use(_UNIT_D)
        rc.hdr.fbo.use()
        ctx.enable(moderngl.DEPTH_TEST | moderngl.BLEND)
        rc.hdr.fbo.depth_mask = False
        ctx.blend_func = (moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA)
        self._glass_vao.render(moderngl.TRIANGLES)
        if self._drop_rows:
            self._draw_drops(rc, frame, view_key, view_values, moving)
        ctx.disable(moderngl.BLEND)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        rc.hdr.fbo.depth_mask = True

    def _copy_frame(self, rc):
        """The frame so far (colour, with mipmaps for the blurred views through water, and depth) copied into the
        effect's target by a draw: ``ctx.copy_framebuffer`` reads GL state back (moderngl restores the read and
        draw buffers around its blit), which makes the main thread wait for Mesa's driver thread to run every
        call queued before it (~200 ms of wall on llvmpipe). Returns the target. Leaves depth testing on, with
        the renderer's "<", as the glass pass expects."""
        ctx = self.ctx
        copy = self._ensure_frame_copy(rc.size)
        rc.hdr.color.use(_UNIT_A)
        rc.hdr.depth.use(_UNIT_B)
        self._depth_sampler.use(_UNIT_B)
        copy.fbo.use()
        ctx.enable(moderngl.DEPTH_TEST)  # (depth is written only while the test is on: "always" passes it)
        ctx.depth_func = "1"
        self._copy_vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.depth_func = "<"
        self._depth_sampler.clear(_UNIT_B)
        copy.color.build_mipmaps()
        return copy

    def _draw_drops(self, rc, frame, view_key: tuple, view_values, moving: dict) -> None:
        """The drops as lenses over the glass (premultiplied, blending and depth test as the glass pass set), with
        the glass pass's view (its key and values) and the car's uniforms (``moving``)."""
        prog = self.drop_prog
        rc.set_frame_uniforms(prog)
        lighting = frame.lighting
        exposure = float(lighting.exposure)
        pixel_rad = math.radians(frame.camera.fov_y_deg) / rc.size[1]
        owned = self._drop_u
        owned.update_for("static", view_key, lambda: {**view_values(), "u_pixel_rad": pixel_rad})
        owned.update(moving)
        owned.set("u_sky_light", tuple(float(c) * exposure for c in lighting.sky_zenith))
        self._drop_vao.render(moderngl.TRIANGLES, vertices=6, instances=self._drop_rows)

    def _blades_bytes(self) -> bytes:
        """The blades' pivots and radii (m) as the shaders' u_blade (vec4 each); kept while the blades are the same
        objects (they are frozen)."""
        blades = self.sim.blades
        if self._blades_memo is None or self._blades_memo[0] is not blades:
            values = [(*b.pivot, b.r_inner_m, b.r_outer_m) for b in blades]
            self._blades_memo = (blades, np.array(values, np.float32).tobytes())
        return self._blades_memo[1]

    def release(self) -> None:
        """Free the textures, buffers and vertex arrays, and the programs when the shader library is our own."""
        self._release_textures()
        self._early = self._uploaded = None
        gl_objects = [
            *self._coarse,
            self._mesh_vbo,
            self._mesh_ibo,
            *self._splat_bufs,
            self._glass_vao,
            self._drop_vao,
            *self._splat_vaos,
            self._film_vao,
            self._normals_vao,
            self._copy_vao,
            self._depth_sampler,
        ]
        for obj in gl_objects:
            obj.release()
        if self._frame_copy is not None:
            self._frame_copy.release()
            self._frame_copy = None
        if self._owns_shaders:  # a shared library's owner releases it: its programs serve every effect using it
            self.shaders.release()

    # --- label images (rain_core.labels) ---
    def render_label(self, name: str, rc, target) -> None:
        """Label image ``name`` of the frame last rendered: for "glass_water", the water on the glass as seen
        (the coverage of drops and film glass.frag blends, 0..1) as the fragment alpha into ``target.fbo``,
        depth-tested against its depth (the cabin hides the glass; not written). The caller (rain_core.labels)
        sets blending and colour mask; other names, outside the car or before the first water pass: nothing."""
        frame = rc.frame
        if name != "glass_water" or not self.resolution or not frame.camera.inside_car or frame.ego is None:
            return
        prog = self.shaders.program("windshield/glass.vert", "labels/glass_water.frag")
        rc.set_frame_uniforms(prog)
        model = frame.ego.model_matrix().copy()
        model[2, 3] -= rc.shift_z
        set_uniforms(prog, u_glass=(self.glass.width_bottom, self.glass.width_top, self.glass.height),
                     u_model=mat4_bytes(model), u_aperture_m=PUPIL_RADIUS_M, u_water=_UNIT_A)
        self._water.color.use(_UNIT_A)
        # Made per call and released: labels are asked for now and then, and release() need not know of it.
        vao = self.ctx.vertex_array(prog, [(self._mesh_vbo, "3f 12x 2f", "in_position", "in_uv")],  # normal unused
                                    index_buffer=self._mesh_ibo, index_element_size=4)
        target.fbo.use()
        rc.ctx.enable(moderngl.DEPTH_TEST)
        target.fbo.depth_mask = False
        try:
            vao.render(moderngl.TRIANGLES)
        finally:
            target.fbo.depth_mask = True
            vao.release()
