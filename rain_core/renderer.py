"""The frame renderer: ordered passes into an offscreen HDR target, tone-mapped to sRGB.

Data flow (DESIGN §1): one ``Frame`` value goes to every effect. Each effect decides with ``active(frame)``
whether it updates and draws at all; the renderer records which passes ran and what each cost.

Stages, in order (an effect lists the ones it draws in):
  ``prepare``      offscreen work before the scene (simulation steps on the GPU, reflection maps)
  ``scene``        built in: sky, world tiles, vehicles, cabin — effects may only bind inputs (``bind_scene``)
  ``transparent``  blended into the HDR target with the scene's depth (rain streaks, spray)
  ``post``         full-screen HDR work (glow, fog shafts)
  ``overlay``      what sits in front of the eye (the windshield), reads a copy of the HDR frame
then ``tonemap`` to the display image.

The world is periodic along Z (``layout.PERIOD_M``). Everything sent to the GPU is in a *wrapped* frame:
world z minus ``shift_z``, a multiple of the period chosen so the camera sits in [0, PERIOD_M). That keeps
float32 positions precise however far the car has driven.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import moderngl
import numpy as np

from rain_core import layout
from rain_core.camera import Camera
from rain_core.gl import PassTimer, RenderTarget, ShaderLibrary, float_target
from rain_core.lighting import Lighting, lights_for_frame, pack_lights
from rain_core.mesh import VERTEX_ATTRIBUTES, VERTEX_FORMAT

# Sun shadows: one map around the camera, texel-snapped so edges do not crawl as the car moves.
SHADOW_SIZE = 2048  # px
SHADOW_HALF_M = 80.0  # m, half the side of the square the map covers
SHADOW_DEPTH_M = 500.0  # m, depth range along the sun's rays
SHADOW_UNIT = 2  # texture unit (the renderer's own: 0–3)

# Share of direct sun/lamp light that reaches the cabin interior (the roof and pillars shade most of it).
CABIN_DIRECT_LIGHT = 0.2

STAGES = ("prepare", "transparent", "post", "overlay")

GL_CLIP_DISTANCE0 = 0x3000  # not in moderngl's enable flags: toggled with ctx.enable_direct

# A clear day's aerial perspective: β ≈ 3.912 / 40 km (meteorological visibility 40 km).
CLEAR_AIR_EXTINCTION_PER_M = 3.912 / 40000.0


@dataclass
class Frame:
    """Everything the effects see for one frame. Units: s, m, m/s; rain in mm/h inside ``weather``."""

    time_s: float
    dt_s: float
    camera: Camera
    lighting: Lighting
    world: object  # rain_core.world.World
    ego: object | None = None  # rain_core.vehicles.Vehicle
    vehicles: list = field(default_factory=list)  # every vehicle, the ego included
    weather: object | None = None  # rain_core.weather.WeatherState
    settings: object | None = None  # rain_core.settings.Settings
    headlights_on: bool = False

    @property
    def rain_rate_mm_h(self) -> float:
        return float(getattr(self.weather, "rate_mm_h", 0.0)) if self.weather is not None else 0.0


@dataclass
class PassStat:
    name: str
    ran: bool
    cpu_ms: float = 0.0
    gpu_ms: float | None = None
    note: str = ""  # e.g. which backend an effect chose


class Effect:
    """Base class of an effect module. Override what you need; the defaults do nothing and cost nothing."""

    name = "effect"
    stages: tuple[str, ...] = ()

    def active(self, frame: Frame) -> bool:
        return False

    def update(self, frame: Frame, rc: RenderContext) -> None:
        """Advance the effect's simulation for this frame (CPU and/or GPU)."""

    def render(self, stage: str, rc: RenderContext) -> None:
        """Draw for ``stage`` into ``rc.hdr`` (or offscreen targets for ``prepare``)."""

    def bind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        """Set the scene shader's inputs this effect owns (called every frame while active)."""

    def unbind_scene(self, program: moderngl.Program, rc: RenderContext) -> None:
        """Reset those inputs to their neutral values (called when the effect is inactive)."""

    def describe(self) -> str:
        """A short state for the performance table (e.g. the backend a simulation chose)."""
        return ""

    def release(self) -> None:
        pass


@dataclass
class RenderContext:
    """What a pass needs to draw: GL objects, the frame, camera matrices in the wrapped frame."""

    ctx: moderngl.Context
    shaders: ShaderLibrary
    frame: Frame
    hdr: RenderTarget
    size: tuple[int, int]
    shift_z: float
    view: np.ndarray
    projection: np.ndarray
    lights: tuple  # packed (pos, dir, color, count) for common/lighting.glsl
    renderer: Renderer
    # What one effect publishes for others this frame (e.g. "water_normals" from ripples for the road), so
    # effects share data through the frame instead of importing each other. Filled during update().
    resources: dict = field(default_factory=dict)

    @property
    def view_proj(self) -> np.ndarray:
        return self.projection @ self.view

    @property
    def camera_position(self) -> np.ndarray:
        """Camera position (m) in the wrapped frame."""
        return np.asarray(self.frame.camera.position, dtype=np.float64) - np.array([0.0, 0.0, self.shift_z])

    def wrap(self, world_points) -> np.ndarray:
        """World positions (…, 3) m → the wrapped frame the GPU uses."""
        out = np.array(world_points, dtype=np.float64, copy=True)
        out[..., 2] -= self.shift_z
        return out

    def set_frame_uniforms(self, program: moderngl.Program) -> None:
        """Camera, exposure, sun/sky, lights and atmosphere uniforms, where the program has them."""
        lighting = self.frame.lighting
        values = {
            "u_view_proj": _mat(self.view_proj),
            "u_camera_pos": tuple(self.camera_position),
            "u_exposure": lighting.exposure,
            "u_time": self.frame.time_s,
            "u_night": lighting.night_factor,
            "u_sun_dir": tuple(lighting.sun_direction),
            "u_sun_illum": tuple(lighting.sun_illuminance),
            "u_sky_zenith": tuple(lighting.sky_zenith),
            "u_sky_horizon": tuple(lighting.sky_horizon),
            "u_ground_albedo": lighting.ground_albedo,
            "u_extinction_per_m": self.renderer.extinction_per_m,
            "u_airlight": tuple(self.renderer.airlight if self.renderer.airlight is not None
                                else lighting.sky_horizon),
            "u_light_count": self.lights[3],
            **self.renderer.medium_uniforms,
            **self.renderer.shadow_uniforms,
        }
        for name, value in values.items():
            if name in program:
                if isinstance(value, bytes):
                    program[name].write(value)
                else:
                    program[name].value = value
        for name, data in zip(("u_light_pos", "u_light_dir", "u_light_color"), self.lights[:3], strict=True):
            if name in program:
                program[name].write(data)


@dataclass
class GpuMesh:
    """A VERTEX_DTYPE mesh on the GPU: one VAO for the lit scene shader, one for the shadow depth pass."""

    vao: moderngl.VertexArray
    depth_vao: moderngl.VertexArray
    count: int
    vbo: moderngl.Buffer

    def release(self) -> None:
        for obj in (self.vao, self.depth_vao, self.vbo):
            obj.release()


def _mat(m: np.ndarray) -> bytes:
    """Row-major numpy 4×4 → the column-major bytes GLSL expects."""
    return np.ascontiguousarray(np.asarray(m, dtype=np.float32).T).tobytes()


class Renderer:
    """Draws frames of the street into an HDR target and tone-maps them.

    ``render(frame)`` runs the passes; ``image()`` returns the last frame as uint8 (H, W, 3) sRGB, top row first;
    ``present(fbo, size)`` draws it into a window's framebuffer. ``stats`` lists the passes of the last frame.
    """

    def __init__(self, ctx: moderngl.Context, size: tuple[int, int], world, effects=(),
                 shaders: ShaderLibrary | None = None, gpu_timing: bool = True):
        width, height = (int(v) for v in size)
        if width <= 0 or height <= 0:
            raise ValueError(f"render size must be positive, got {size!r}")
        self.ctx = ctx
        self.size = (width, height)
        self.world = world
        self.shaders = shaders or ShaderLibrary(ctx)
        self.effects = list(effects)
        self.gpu_timing = gpu_timing
        self.extinction_per_m = CLEAR_AIR_EXTINCTION_PER_M
        self.airlight: np.ndarray | None = None  # None: the horizon sky
        # Further atmosphere.glsl uniforms (the rain medium's sun airlight and phase), set by the atmosphere
        # effect and written into every program that declares them.
        self.medium_uniforms: dict = {}
        self.stats: list[PassStat] = []
        self.timing_source = "none"

        self._make_targets()

        self.scene_prog = self.shaders.program("core/scene.vert", "core/scene.frag")
        self.shadow_prog = self.shaders.program("core/shadow.vert", "core/shadow.frag")
        self.shadow_depth = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
        self.shadow_depth.compare_func = "<="
        self.shadow_depth.filter = (moderngl.LINEAR, moderngl.LINEAR)  # hardware 2×2 PCF per tap
        self.shadow_depth.repeat_x = self.shadow_depth.repeat_y = False
        self.shadow_fbo = ctx.framebuffer(depth_attachment=self.shadow_depth)
        self.shadow_uniforms: dict = {"u_shadow_params": (0.0, 0.0, 0.0), "u_shadow_map": SHADOW_UNIT}
        self.sky_prog = self.shaders.program("common/fullscreen.vert", "core/sky.frag")
        self.tonemap_prog = self.shaders.program("common/fullscreen.vert", "core/tonemap.frag")
        self.blit_prog = self.shaders.program("common/fullscreen.vert", "core/blit.frag")
        self._sky_vao = ctx.vertex_array(self.sky_prog, [])
        self._tonemap_vao = ctx.vertex_array(self.tonemap_prog, [])
        self._blit_vao = ctx.vertex_array(self.blit_prog, [])
        self._world_vao = self._vao(world.vertices)
        # id(vehicle) → (vehicle, mesh): holding the vehicle keeps its id from being reused by a new one.
        self._vehicle_vaos: dict[int, tuple[object, GpuMesh]] = {}
        self._cabin: list[tuple[GpuMesh, float]] | None = None
        self._timers: dict[str, PassTimer] = {}

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

    # --- geometry -------------------------------------------------------------------------------------------
    def _vao(self, vertices: np.ndarray) -> GpuMesh:
        vbo = self.ctx.buffer(np.ascontiguousarray(vertices).tobytes())
        vao = self.ctx.vertex_array(self.scene_prog, [(vbo, VERTEX_FORMAT, *VERTEX_ATTRIBUTES)])
        depth_vao = self.ctx.vertex_array(self.shadow_prog, [(vbo, "3f 36x", "in_position")])
        return GpuMesh(vao, depth_vao, len(vertices), vbo)

    def _vehicle_vao(self, vehicle) -> GpuMesh:
        key = id(vehicle)
        if key not in self._vehicle_vaos:
            from rain_core.car_mesh import vehicle_mesh

            color = getattr(vehicle, "color", (0.5, 0.05, 0.04))
            mesh = self._vao(vehicle_mesh(vehicle.spec, np.asarray(color, np.float32)))
            self._vehicle_vaos[key] = (vehicle, mesh)
        return self._vehicle_vaos[key][1]

    def _forget_vehicles(self, vehicles) -> None:
        """Release the meshes of vehicles that left the scene (e.g. the traffic count changed)."""
        present = {id(v) for v in vehicles}
        for key in [k for k in self._vehicle_vaos if k not in present]:
            self._vehicle_vaos.pop(key)[1].release()

    def _cabin_vaos(self, ego):
        """The cabin as (mesh, direct-light share): painted outside parts (hood, mirrors) get full direct light,
        the interior the share its roof lets in."""
        if self._cabin is None:
            from rain_core.car_mesh import cabin_mesh
            from rain_core.mesh import MAT_CAR_PAINT

            vertices = cabin_mesh(ego.spec)
            outside = np.round(vertices["params"][:, 2]) == MAT_CAR_PAINT
            self._cabin = [(self._vao(part), share) for part, share in
                           ((vertices[outside], 1.0), (vertices[~outside], CABIN_DIRECT_LIGHT)) if len(part)]
        return self._cabin

    # --- passes ---------------------------------------------------------------------------------------------
    def _timed(self, name: str, fn) -> None:
        timer = self._timers.get(name)
        if timer is None:
            timer = self._timers[name] = PassTimer(self.ctx, gpu=self.gpu_timing)
            self.timing_source = timer.gpu_source
        cpu_ms, gpu_ms = timer.measure(fn)
        self.stats.append(PassStat(name, True, cpu_ms, gpu_ms))

    def render_context(self, frame: Frame, fbo_target: RenderTarget | None = None) -> RenderContext:
        camera = frame.camera
        shift_z = math.floor(float(camera.position[2]) / layout.PERIOD_M) * layout.PERIOD_M
        view = camera.view_matrix(shift=(0.0, 0.0, shift_z))
        proj = camera.projection_matrix(self.size[0] / self.size[1])
        lights = lights_for_frame(getattr(self.world, "lamps", []), frame.vehicles, camera.position,
                                  frame.lighting, shift_z, layout.PERIOD_M, frame.headlights_on)
        return RenderContext(self.ctx, self.shaders, frame, fbo_target or self.hdr, self.size, shift_z, view, proj,
                             pack_lights(lights), self)

    def draw_scene(self, rc: RenderContext, active_effects, include_sky: bool = True,
                   clip_plane: tuple[float, float, float, float] | None = None) -> None:
        """Sky, world tiles, vehicles and (inside the car) the cabin, into the bound framebuffer.

        Effects reuse this for auxiliary views (e.g. a mirrored camera for reflections)."""
        ctx = self.ctx
        ctx.disable(moderngl.BLEND)
        if include_sky:
            ctx.disable(moderngl.DEPTH_TEST)
            rc.set_frame_uniforms(self.sky_prog)
            self.sky_prog["u_inv_view_proj"].write(_mat(np.linalg.inv(rc.view_proj)))
            self._sky_vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.enable(moderngl.DEPTH_TEST)
        prog = self.scene_prog
        self.shadow_depth.use(SHADOW_UNIT)  # re-bound per draw: a GPU simulation may have used the unit
        rc.set_frame_uniforms(prog)
        # Clip plane (reflection passes): keep dot((x, y, z, 1), plane) >= 0, wrapped-frame world positions.
        prog["u_clip_plane"].value = (0.0, 0.0, 0.0, 1.0) if clip_plane is None else tuple(map(float, clip_plane))
        if clip_plane is not None:
            ctx.enable_direct(GL_CLIP_DISTANCE0)
        for effect in self.effects:
            if effect in active_effects:
                effect.bind_scene(prog, rc)
            else:
                effect.unbind_scene(prog, rc)
        for mesh, model, share in self._draw_list(rc, include_cabin=True):
            prog["u_model"].write(_mat(model))
            prog["u_direct_scale"].value = share
            mesh.vao.render(moderngl.TRIANGLES, vertices=mesh.count)
        prog["u_direct_scale"].value = 1.0
        if clip_plane is not None:
            ctx.disable_direct(GL_CLIP_DISTANCE0)

    def _draw_list(self, rc: RenderContext, include_cabin: bool):
        """(mesh, model matrix in the wrapped frame, direct-light share) of everything opaque in the frame."""
        frame = rc.frame
        cam_z = rc.camera_position[2]
        for k in (-1, 0, 1):
            offset = k * layout.PERIOD_M
            if abs(cam_z - (offset + layout.PERIOD_M / 2)) > layout.PERIOD_M * 1.5:
                continue
            model = np.eye(4)
            model[2, 3] = offset
            yield self._world_vao, model, 1.0
        inside = frame.camera.inside_car
        for vehicle in frame.vehicles:
            if inside and include_cabin and vehicle is frame.ego:
                continue
            model = vehicle.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            yield self._vehicle_vao(vehicle), model, 1.0
        if inside and include_cabin and frame.ego is not None:
            model = frame.ego.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            for mesh, share in self._cabin_vaos(frame.ego):
                yield mesh, model, share

    def _shadow_pass(self, rc: RenderContext) -> None:
        """Depth of the world and the vehicles seen from the sun, over a square around the camera."""
        ctx = self.ctx
        light = rc.frame.lighting
        sun = np.asarray(light.sun_direction, dtype=np.float64)
        r, u, f = rc.frame.camera.basis()
        ahead = np.array([f[0], 0.0, f[2]])
        ahead /= max(np.linalg.norm(ahead), 1e-9)
        center = rc.camera_position + ahead * SHADOW_HALF_M * 0.6
        up = np.array([0.0, 0.0, 1.0]) if abs(sun[1]) > 0.99 else np.array([0.0, 1.0, 0.0])
        lx = np.cross(up, sun)
        lx /= np.linalg.norm(lx)
        ly = np.cross(sun, lx)
        texel = 2.0 * SHADOW_HALF_M / SHADOW_SIZE
        for axis in (lx, ly):  # snap the centre to whole texels across the light's view
            c = float(center @ axis)
            center = center + (round(c / texel) * texel - c) * axis
        eye = center + sun * SHADOW_DEPTH_M * 0.5
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = lx, ly, sun
        view[:3, 3] = -view[:3, :3] @ eye
        proj = np.diag([1.0 / SHADOW_HALF_M, 1.0 / SHADOW_HALF_M, -2.0 / SHADOW_DEPTH_M, 1.0])
        proj[2, 3] = -1.0  # z_view in [−depth, 0] → NDC [1, −1]... nearest to the sun at −1
        light_view_proj = proj @ view
        self.shadow_fbo.use()
        self.shadow_fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.BLEND)
        self.shadow_prog["u_light_view_proj"].write(_mat(light_view_proj))
        for mesh, model, _share in self._draw_list(rc, include_cabin=False):
            self.shadow_prog["u_model"].write(_mat(model))
            mesh.depth_vao.render(moderngl.TRIANGLES, vertices=mesh.count)
        to_texture = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
        self.shadow_uniforms = {"u_shadow_matrix": _mat(to_texture @ light_view_proj), "u_shadow_map": SHADOW_UNIT,
                                "u_shadow_params": (1.0, 1.0 / SHADOW_SIZE, 0.06 / SHADOW_DEPTH_M)}

    def render(self, frame: Frame) -> None:
        """Run every pass of one frame into the HDR target and tone-map it."""
        ctx = self.ctx
        self.stats = []
        self._forget_vehicles(frame.vehicles)
        rc = self.render_context(frame)
        active = []
        for effect in self.effects:
            if effect.active(frame):
                active.append(effect)
            else:
                self.stats.append(PassStat(effect.name, False))
        for effect in active:
            self._timed(f"{effect.name}.update", lambda e=effect: e.update(frame, rc))
            self.stats[-1].note = effect.describe()
        if frame.lighting.sun_direction[1] > 0.0 and float(np.max(frame.lighting.sun_illuminance)) > 0.0:
            self._timed("shadow", lambda: self._shadow_pass(rc))
        else:  # the sun is down: nothing casts a sun shadow
            self.shadow_uniforms = {"u_shadow_params": (0.0, 0.0, 0.0), "u_shadow_map": SHADOW_UNIT}
            self.stats.append(PassStat("shadow", False))
        for effect in active:
            if "prepare" in effect.stages:
                self._timed(f"{effect.name}.prepare", lambda e=effect: e.render("prepare", rc))

        def scene():
            self.hdr.fbo.use()
            self.hdr.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
            ctx.disable(moderngl.CULL_FACE)  # meshes are not all consistently wound; shading flips back faces
            self.draw_scene(rc, active)

        self._timed("scene", scene)
        for stage in STAGES[1:]:
            for effect in active:
                if stage in effect.stages:
                    def draw(e=effect, s=stage):
                        self.hdr.fbo.use()
                        e.render(s, rc)
                    self._timed(f"{effect.name}.{stage}", draw)

        def tonemap():
            ctx.disable(moderngl.DEPTH_TEST)
            ctx.disable(moderngl.BLEND)
            self.ldr.use()
            self.hdr.color.use(0)
            self.tonemap_prog["u_hdr"].value = 0
            self._tonemap_vao.render(moderngl.TRIANGLES, vertices=3)

        self._timed("tonemap", tonemap)

    def image(self) -> np.ndarray:
        """The last tone-mapped frame, uint8 (H, W, 3) sRGB, top row first."""
        data = self.ldr.read(components=3, alignment=1)
        img = np.frombuffer(data, dtype=np.uint8).reshape(self.size[1], self.size[0], 3)
        return np.ascontiguousarray(img[::-1])

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
        self.ldr_color.use(0)
        self.blit_prog["u_image"].value = 0
        self._blit_vao.render(moderngl.TRIANGLES, vertices=3)

    def pass_table(self) -> list[tuple[str, bool, float, float | None, str]]:
        """(pass, ran, CPU ms, GPU ms or None, note) for each pass of the last frame."""
        return [(s.name, s.ran, s.cpu_ms, s.gpu_ms, s.note) for s in self.stats]

    def release(self) -> None:
        for effect in self.effects:
            effect.release()
        self.hdr.release()
        self.ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
        self.ldr.release()
        self.ldr_color.release()
        self.shadow_fbo.release()
        self.shadow_depth.release()
        meshes = [self._world_vao, *(m for _, m in self._vehicle_vaos.values()),
                  *(m for m, _ in (self._cabin or []))]
        for mesh in meshes:
            mesh.release()
        self._vehicle_vaos.clear()
        self._cabin = None
        for obj in (self._sky_vao, self._tonemap_vao, self._blit_vao):
            obj.release()


def frame_time_ms(stats: list[PassStat]) -> float:
    """Sum of the measured pass times (GPU where known, else CPU), ms."""
    return sum((s.gpu_ms if s.gpu_ms is not None else s.cpu_ms) for s in stats if s.ran)

