"""The GL side of the rainfall: ``RainfallEffect`` uploads what ``RainfallSim`` spawned and retired into a drop
state texture (``units.RAINFALL_STATE``), draws the environment a drop shows (``units.RAINFALL_ENV``), then one
instanced streak quad per drop slot and one billboard per splash slot (package docstring)."""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core.effects.rainfall.boxes import Boxes, wrap_near
from rain_core.effects.rainfall.constants import (
    ALPHA_MAX,
    LAYER_SCALES,
    PERIOD_M,
    SPLASH_CROWN_HEIGHT_PER_D,
    TIME_PERIOD_S,
    WIDTH_FLOOR_PX,
    WIDTH_MAX_PX,
)
from rain_core.effects.rainfall.shape import SHAPE_DIAMETERS_MM, drop_shape_factors
from rain_core.effects.rainfall.sim import RainfallSim, RainInput, RainUpdate
from rain_core.effects.rainfall.streaks import StreakCamera
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import set_uniform, set_uniforms

# GPU layout: three RGBA32F texels per drop, DROPS_PER_ROW drops per texture row.
DROPS_PER_ROW = 1024
TEXELS_PER_DROP = 3
ENV_SIZE = (64, 32)  # texels of the drop's environment map (equirectangular, rainfall/env.frag)

_SCATTER_DTYPE = np.dtype([("texel", "<i4"), ("value", "<f4", (4,))])


class RainfallEffect(Effect):
    """Falling rain: streaks in the camera-following container and impact splashes (package docstring).

    ctx: moderngl context; settings: the Settings used when a frame carries none; seed: seeds the drops; shaders:
    a ShaderLibrary (default: a new one, whose programs this effect then owns and releases). Draws in the
    ``transparent`` stage; the drop state is bound to ``units.RAINFALL_STATE``, the environment to
    ``units.RAINFALL_ENV``.
    Reads frame.settings.rainfall (enabled, density_scale, streak_brightness, splashes, container_m),
    quality.particle_budget, camera.exposure_s and camera.mode (driver/chase: the camera moves with the ego car;
    free: its velocity is the finite difference of its positions)."""

    name = "rainfall"
    stages = ("transparent",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders: ShaderLibrary | None = None):
        from rain_core.settings import Settings

        self.ctx = ctx
        self._owns_shaders = shaders is None  # a library of our own: ours to release
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
        area, width = drop_shape_factors(SHAPE_DIAMETERS_MM)
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

    def _enabled(self, frame) -> bool:
        s = self._settings(frame)
        return bool(s.rainfall.enabled) and s.quality.particle_budget > 0

    def observe(self, frame) -> None:
        """Switched off (or no budget): forget every drop and the camera's last position, so switching back on
        refills the container at once instead of replaying the time spent off."""
        if not self._enabled(frame):
            if self.sim is not None and self.sim.t_prev is not None:
                self.sim.reset()
            self._prev_cam = None

    def active(self, frame) -> bool:
        if not self._enabled(frame):
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
            set_uniform(self.scatter_prog, "u_size", self._state_tex.size)
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
            "u_brightness": float(s.rainfall.streak_brightness), "u_rain_env": units.RAINFALL_ENV,
            "u_light_pos": lights[0], "u_light_dir": lights[1], "u_light_color": lights[2],
            "u_light_count": lights[3],
        }
        self._env_tex.use(units.RAINFALL_ENV)
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
                set_uniforms(prog, common)
                set_uniforms(prog, {
                    "u_state": units.RAINFALL_STATE, "u_drops_per_row": DROPS_PER_ROW,
                    "u_cam_vel": tuple(self.camera_velocity_m_s), "u_exposure_s": float(s.camera.exposure_s),
                    "u_near": float(rc.frame.camera.near_m), "u_box_lo": boxes.lo - shift,
                    "u_box_hi": boxes.hi - shift, "u_box_fade": boxes.fade, "u_layer_nu": boxes.nu,
                    "u_shape_area": self._shape_area, "u_shape_width": self._shape_width,
                    "u_width_floor_px": WIDTH_FLOOR_PX, "u_width_max_px": WIDTH_MAX_PX, "u_alpha_max": ALPHA_MAX,
                })
                self._state_tex.use(units.RAINFALL_STATE)
                self._streak_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=count)
            if s.rainfall.splashes and self.sim.splashes_live(rc.frame.time_s):
                prog = self.splash_prog
                rc.set_frame_uniforms(prog)
                set_uniforms(prog, common, u_crown_per_d=SPLASH_CROWN_HEIGHT_PER_D, u_splash_alpha_max=ALPHA_MAX)
                self._splash_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.sim.splash_capacity)
        finally:
            rc.hdr.fbo.depth_mask = True
            ctx.disable(moderngl.BLEND)
            ctx.blend_func = moderngl.DEFAULT_BLENDING

    def release(self) -> None:
        """Free the buffers, textures and vertex arrays, and the programs when the shader library is our own (a
        shared library's owner releases it: its programs serve every effect that asks for them)."""
        self._release_buffers()
        for obj in (self._streak_vao, self._env_vao, self._env_fbo, self._env_tex):
            obj.release()
        if self._owns_shaders:
            self.shaders.release()

