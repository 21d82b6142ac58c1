"""The GL side of the rainfall: ``RainfallEffect`` sets the few uniforms ``RainfallSim`` computes per frame, draws
the environment a drop shows (``units.RAINFALL_ENV``), then the streaks in two passes (a transform-feedback pass
writes each drop instance's streak record on the GPU, then one instanced quad per record) and one billboard per
splash slot; nothing per drop is uploaded (package docstring). Static inputs, uploaded once: the
drop table (``units.RAINFALL_DROPS``), the roof maps (``units.RAINFALL_OCCLUDER``, ``RAINFALL_OCCLUDER_COARSE``)
and the road's height map for the splash kinds (``units.RAINFALL_ROAD_HEIGHT``)."""

from __future__ import annotations

import functools
import math
import struct
from array import array

import moderngl
import numpy as np

from rain_core import layout
from rain_core.effects.rainfall.box_uniforms import box_floats, box_shape_pairs, splash_box_pairs
from rain_core.effects.rainfall.boxes import Boxes, wrap_near
from rain_core.effects.rainfall.constants import (
    ALPHA_MAX,
    GROUND_Y_M,
    LAYER_SCALES,
    PERIOD_M,
    SPLASH_CROWN_HEIGHT_PER_D,
    SPLASH_LAYER,
    SPLASH_PERIOD_S,
    SPREAD_ALPHA,
    STRETCH_MAX,
    WIDTH_FLOOR_PX,
    WIDTH_MAX_PX,
)
from rain_core.effects.rainfall.drops import TURB_EPS, time_split
from rain_core.effects.rainfall.optics import optics_uniforms
from rain_core.effects.rainfall.rain_block import (
    RAIN_FRAME_BINDING,
    RAIN_FRAME_BYTES,
    pack_rain_frame,
    rain_frame_from_uniforms,
)
from rain_core.effects.rainfall.shape import SHAPE_DIAMETERS_MM, drop_shape_factors
from rain_core.effects.rainfall.sim import SPLASH_V_M_S, RainfallSim, RainInput, RainUpdate, box_offsets, splash_clock
from rain_core.effects.rainfall.streak_pass import StreakPass
from rain_core.effects.rainfall.streaks import StreakCamera
from rain_core.effects.rainfall.vehicle_fate import vehicle_pose_floats, vehicle_shape_pairs, vehicle_uniforms
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import owned_uniforms, set_uniforms

ENV_SIZE = (64, 32)  # texels of the drop's environment map (equirectangular, rainfall/env.frag)
OPEN_M = -1e4  # m, the roof height the shader reads where the maps say −inf (open sky)
PROBE_WIDTH = 1024  # texels per row of the debug drop probe (read_drops)


@functools.cache
def _light_struct(count: int) -> struct.Struct:
    return struct.Struct(f"={4 * count}f")


# The frame values rainfall/env.frag reads (common/sky.glsl, common/atmosphere.glsl) that rc.uniforms may hold; the
# rest of what it reads comes from the frame's Lighting.
_ENV_INPUTS = ("u_sun_dir", "u_sun_illum", "u_sky_zenith", "u_sky_horizon", "u_ground_albedo", "u_extinction_per_m",
               "u_airlight", "u_medium_extinction_per_m", "u_airlight_sun", "u_airlight_sun_dir", "u_phase_g",
               "u_phase_back_g", "u_phase_back_weight")


def _bind_rain_frame_block(prog) -> None:
    """Point prog's RainFrame block at RAIN_FRAME_BINDING (a program's setting: once per program)."""
    block = prog.get("RainFrame", None)
    if block is not None:
        block.binding = RAIN_FRAME_BINDING


def _f32(values) -> bytes:
    return np.ascontiguousarray(values, dtype=np.float32).tobytes()


class RainfallEffect(Effect):
    """Falling rain: streaks in the camera-following container and impact splashes (package docstring).

    ctx: moderngl context; settings: the Settings used when a frame carries none; seed: seeds the drops; shaders:
    a ShaderLibrary (default: a new one, whose programs this effect then owns and releases). Draws in the
    ``transparent`` stage; binds the drop table, the roof maps and the road heights to their ``units.RAINFALL_*``
    units (module docstring), the environment to ``units.RAINFALL_ENV``.
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
        self.streaks = StreakPass(ctx, self.shaders, layers)  # each drop's record once, then its quad
        self.record_prog = self.streaks.record_prog  # the drop uniforms
        self.streak_prog = self.streaks.quad_prog
        self.splash_prog = self.shaders.program("rainfall/splash.vert", "rainfall/splash.frag", defines=layers)
        self.env_prog = self.shaders.program("common/fullscreen.vert", "rainfall/env.frag")
        self._env_vao = ctx.vertex_array(self.env_prog, [])
        self._env_tex = ctx.texture(ENV_SIZE, 4, dtype="f2")
        self._env_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._env_tex.repeat_x, self._env_tex.repeat_y = True, False
        self._env_fbo = ctx.framebuffer(color_attachments=[self._env_tex])
        self._optics_set = False  # the drop optics' quadrature (optics.py): constant, written once
        self._env_key: tuple | None = None  # what the environment map was last drawn for (_draw_environment)
        self._splash_vao = ctx.vertex_array(self.splash_prog, [])
        # The per-frame block (rain_block.py), this effect's own buffer: written when its bytes change, bound at
        # each draw (another rainfall effect on the context binds its own there).
        self._frame_buffer = ctx.buffer(reserve=RAIN_FRAME_BYTES)
        self._frame_data: bytes | None = None
        for prog in (self.record_prog, self.splash_prog):
            _bind_rain_frame_block(prog)
        self.sim: RainfallSim | None = None
        self._world = None
        self._table_tex = None
        self._table_version = None
        self._static_tex: dict[str, moderngl.Texture] = {}
        self._occ_geom: dict[str, tuple] = {}
        self._road_extent = (1.0, 1.0)
        self._probe = None
        self._prev_cam: tuple[np.ndarray, float] | None = None
        self.camera_velocity_m_s = np.zeros(3)
        self.last_update: RainUpdate | None = None
        self._prepared: tuple | None = None  # (rc, its lights, the update, _frame_values) made in update
        self._constants: tuple | None = None  # (its key, the uniforms that rarely change: _constant_pairs)
        self._plain: tuple | None = None  # (constants, frame pairs, both in one tuple): _plain_pairs
        area, width = drop_shape_factors(SHAPE_DIAMETERS_MM)
        self._shape_area = area.astype(np.float32)
        self._shape_width = width.astype(np.float32)

    # --- settings and resources ---

    def describe(self) -> str:
        upd = self.last_update
        if upd is None:
            return ""
        return f"{upd.drawn_expected:,.0f} of {self.sim.capacity:,} streaks drawn, {upd.rate_mm_h:.2f} mm/h"

    def _settings(self, frame):
        return frame.settings if frame.settings is not None else self.settings

    def _ensure(self, capacity: int, world) -> None:
        if self.sim is None or self.sim.capacity != capacity or self._world is not world:
            self.sim = RainfallSim(capacity, seed=self.seed, world=world)
            self._table_version = None
        if self._world is not world or not self._static_tex:
            self._world = world
            self._upload_world(world)
            self._constants = None  # the roof maps' and the road's geometry are among them

    def _texture(self, name: str, grid: np.ndarray, linear: bool = False) -> None:
        old = self._static_tex.pop(name, None)
        if old is not None:
            old.release()
        data = np.ascontiguousarray(grid, dtype=np.float32)
        tex = self.ctx.texture((data.shape[1], data.shape[0]), 1, data.tobytes(), dtype="f4")
        tex.filter = (moderngl.LINEAR, moderngl.LINEAR) if linear else (moderngl.NEAREST, moderngl.NEAREST)
        tex.repeat_x, tex.repeat_y = False, True
        self._static_tex[name] = tex

    def _upload_world(self, world) -> None:
        """The roof maps and the road's height map, once per world (a 1×1 open map without one)."""
        if world is not None and hasattr(world, "occluder_map"):
            for name, occ in (("fine", world.occluder_map), ("coarse", world.occluder_map_coarse)):
                self._texture(name, np.where(np.isfinite(occ.grid), occ.grid, OPEN_M))
                nz, nx = occ.grid.shape
                self._occ_geom[name] = (float(occ.x0_m), float(occ.cell_m), float(nx), float(nz))
        else:
            for name in ("fine", "coarse"):
                self._texture(name, np.full((1, 1), OPEN_M))
                self._occ_geom[name] = (0.0, PERIOD_M, 0.0, 1.0)  # no columns: open everywhere
        if world is not None and hasattr(world, "road_heightmap"):
            self._texture("road", world.road_heightmap, linear=True)
            self._road_extent = tuple(float(v) for v in world.heightmap_extent_m)
        else:
            self._texture("road", np.ones((1, 1)), linear=True)
            self._road_extent = (1.0, 1.0)

    def _sync_table(self) -> None:
        if self._table_version == self.sim.table_version:
            return
        table = self.sim.table
        if self._table_tex is not None:
            self._table_tex.release()
        self._table_tex = self.ctx.texture((table.shape[1], table.shape[0]), 4,
                                           np.ascontiguousarray(table, np.float32).tobytes(), dtype="f4")
        self._table_tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._table_version = self.sim.table_version

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
                self.last_update = None
            self._prev_cam = None

    def active(self, frame) -> bool:
        if not self._enabled(frame):
            return False
        if frame.rain_rate_mm_h > 0.0:
            return True
        sim = self.sim
        return sim is not None and sim.rate_eff > 0.0  # stateless: no drop outlives the rate ramp

    def camera_velocity(self, frame) -> np.ndarray:
        """Velocity (m/s, world) of the camera: the ego car's at the camera point (with its yaw rate) for the
        driver and chase cameras, else the finite difference of the camera's positions over time."""
        s = self._settings(frame)
        ego = frame.ego
        if ego is not None and s.camera.mode in ("driver", "chase", "glass"):
            # In scalars: the camera's offset from the car (z wrapped as wrap_near does; Python's round, like
            # np.round, rounds halves to even), then the yaw rate's share at that offset.
            cam, car = frame.camera.position, ego.position
            rel_x = float(cam[0]) - float(car[0])
            rel_z = float(cam[2]) - float(car[2])
            rel_z -= PERIOD_M * round(rel_z / PERIOD_M)
            vx, vy, vz = ego.velocity().tolist()  # float64 (3,): the same floats as float() of each
            omega = float(getattr(ego, "yaw_rate_rad_s", 0.0))
            return np.array((vx + omega * rel_z, vy, vz - omega * rel_x))
        pos = np.asarray(frame.camera.position, dtype=np.float64)
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
        # Every value here was checked where it entered (camera, weather, settings): no per-frame re-check.
        inp = RainInput.unchecked(
            time_s=float(frame.time_s), camera_position=np.asarray(frame.camera.position, dtype=np.float64),
            camera_forward=np.asarray(frame.camera.forward, dtype=np.float64), camera_velocity=v_cam,
            rate_mm_h=float(frame.rain_rate_mm_h), wind_m_s=wind, container_m=float(s.rainfall.container_m),
            density_scale=float(s.rainfall.density_scale), splashes=bool(s.rainfall.splashes),
            wetness=float(getattr(weather, "wetness", 0.0)), puddles=float(getattr(weather, "puddles", 0.0)),
            vehicles=tuple(frame.vehicles))
        upd = self.sim.advance(inp)
        self._sync_table()
        if self.sim.capacity:
            self.streaks.reserve(self.sim.capacity)  # before the frame's first draw (StreakPass.reserve)
        self.camera_velocity_m_s = v_cam
        if frame.time_s > (self._prev_cam[1] if self._prev_cam is not None else -math.inf):
            self._prev_cam = (np.asarray(frame.camera.position, dtype=np.float64).copy(), frame.time_s)
        self.last_update = upd
        self._prepared = None
        if upd.rate_mm_h > 0.0 and getattr(rc, "lights", None) is not None and getattr(rc, "drawn", True):
            # The transparent pass's lights and uniforms, made now: this context draws it, and here the CPU is
            # not shared with the rasteriser still drawing the passes before (llvmpipe: ~3x the time there).
            self._prepared = (rc, rc.lights, upd, self._frame_values(upd, rc, s, self._lights(rc, upd.boxes)))

    def streak_camera(self, rc) -> StreakCamera:
        """The camera as the streak shader sees it this frame (for the NumPy twin)."""
        s = self._settings(rc.frame)
        return StreakCamera(rc.view_proj, rc.camera_position, rc.shift_z, self.camera_velocity_m_s,
                            s.camera.exposure_s, rc.size, rc.frame.camera.near_m)

    def _lights(self, rc, boxes: Boxes) -> tuple:
        """rc.lights without the lights whose range cannot reach the outer box (wrapped frame); rc.lights itself
        when every light reaches it (nothing to repack). The three buffers have one size (lighting.pack_lights)."""
        pos_b, dir_b, col_b, count = rc.lights
        if count == 0:
            return rc.lights
        size = len(pos_b)
        lx, ly, lz = boxes.lo[-1].tolist()
        hx, hy, hz = boxes.hi[-1].tolist()
        shift_z = float(rc.shift_z)
        lz, hz = lz - shift_z, hz - shift_z
        # In floats (a few dozen lights; NumPy's many small calls cost more, cold, after the other passes): the
        # gap from the box in float64, its squared length summed as NumPy's einsum sums three terms ((x, z) then
        # y), against w² rounded to float32 as NumPy's float32 product (w < 0: a low beam).
        # Each gap as max(lo - x, x - hi, 0.0) gives it (lo < hi), in branches: the builtin max was half the loop.
        vals = _light_struct(count).unpack_from(pos_b)
        ranges = array("f", [w * w for w in vals[3::4]])
        it = iter(vals)
        keep = []
        for i, r2, x, y, z, _w in zip(range(count), ranges, it, it, it, it, strict=True):
            gx = lx - x if x < lx else (x - hx if x > hx else 0.0)
            gy = ly - y if y < ly else (y - hy if y > hy else 0.0)
            gz = lz - z if z < lz else (z - hz if z > hz else 0.0)
            if gx * gx + gz * gz + gy * gy < r2:
                keep.append(i)
        n = len(keep)
        if n == count:
            return rc.lights
        pad = bytes(size - 16 * n)
        if n == 0 or keep[-1] == n - 1:  # the nearest n (pack_nearest sorts by distance): a prefix of each buffer
            return pos_b[:16 * n] + pad, dir_b[:16 * n] + pad, col_b[:16 * n] + pad, n
        # The kept lights' 16 bytes each, in order, then the zero padding (what a gather into zeros gave).
        return (b"".join([pos_b[16 * i: 16 * i + 16] for i in keep]) + pad,
                b"".join([dir_b[16 * i: 16 * i + 16] for i in keep]) + pad,
                b"".join([col_b[16 * i: 16 * i + 16] for i in keep]) + pad, n)

    def _draw_environment(self, rc) -> None:
        """Draw what a drop shows into the environment map, unless nothing it reads changed since it was drawn:
        the lighting (one immutable object while the hour and the overcast stay) and the medium's uniforms."""
        inputs = rc.uniforms
        key = (rc.frame.lighting, tuple(inputs.get(name) for name in _ENV_INPUTS))
        last = self._env_key
        if last is not None and last[0] is key[0] and last[1] == key[1]:
            return
        self._env_key = key
        rc.set_frame_uniforms(self.env_prog)
        if not self._optics_set:
            set_uniforms(self.env_prog, optics_uniforms())
            self._optics_set = True
        self.ctx.disable(moderngl.BLEND | moderngl.DEPTH_TEST)
        self._env_fbo.use()
        self._env_vao.render(moderngl.TRIANGLES, vertices=3)
        rc.hdr.fbo.use()

    def drop_uniforms(self, upd: RainUpdate, shift_z: float, around_z: float) -> dict:
        """The uniforms of rainfall/drops.glsl for one frame (boxes in the frame shifted by shift_z; vehicles
        wrapped near around_z). Everything is a small number: time and offsets are reduced in float64 here."""
        sim = self.sim
        boxes = upd.boxes
        whole, frac, epoch = time_split(upd.time_s)
        off, turb, yoff = box_offsets(boxes, upd.wind_integral_m)
        off[:, 1] = yoff
        lo = boxes.lo - [0.0, 0.0, shift_z]
        out = {
            "u_seed_key": int(sim.key), "u_layer_start": np.asarray(upd.starts[:-1], np.int32).tobytes(),
            "u_drop_table": units.RAINFALL_DROPS, "u_time_whole": whole, "u_time_frac": frac, "u_epoch": epoch,
            "u_box_lo": lo, "u_box_ext": boxes.ext, "u_box_off": off, "u_box_turb": turb,
            "u_box_fade": boxes.fade, "u_box_fade_bottom": boxes.fade_bottom, "u_layer_rho": upd.density,
            "u_wind": tuple(float(v) for v in upd.wind_m_s), "u_turb_eps": TURB_EPS,
            "u_thin": (upd.thin_a, upd.thin_b, upd.thin_c),
            "u_occ_fine": units.RAINFALL_OCCLUDER, "u_occ_coarse": units.RAINFALL_OCCLUDER_COARSE,
            "u_occ_fine_geom": self._occ_geom["fine"], "u_occ_coarse_geom": self._occ_geom["coarse"],
            "u_period_world": PERIOD_M, "u_ground_y": GROUND_Y_M,
        }
        out.update(vehicle_uniforms(list(upd.vehicles), shift_z, around_z))
        return out

    def _bind_static(self) -> None:
        self._table_tex.use(units.RAINFALL_DROPS)
        self._static_tex["fine"].use(units.RAINFALL_OCCLUDER)
        self._static_tex["coarse"].use(units.RAINFALL_OCCLUDER_COARSE)
        self._static_tex["road"].use(units.RAINFALL_ROAD_HEIGHT)

    def splash_uniforms(self, upd: RainUpdate, shift_z: float) -> dict:
        boxes = upd.boxes
        lo_w, ext = boxes.lo[SPLASH_LAYER], boxes.ext[SPLASH_LAYER]
        count, tau = splash_clock(upd.time_s)
        return {
            "u_splash_key": int(self.sim.splash_key), "u_splash_count": count, "u_splash_tau": tau,
            "u_splash_period": SPLASH_PERIOD_S, "u_splash_accept": upd.splash_accept,
            "u_splash_weight": upd.splash_weight, "u_splash_lam": upd.splash_lam,
            "u_splash_lo": tuple(lo_w - [0.0, 0.0, shift_z]), "u_splash_ext": tuple(ext),
            "u_splash_off": tuple(np.mod(-lo_w, ext)), "u_splash_v": SPLASH_V_M_S.astype(np.float32),
            "u_wetness": upd.wetness, "u_puddles": upd.puddles, "u_road_height": units.RAINFALL_ROAD_HEIGHT,
            "u_road_extent": self._road_extent,
            "u_road_geom": (layout.ROAD_HALF_WIDTH_M, layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M
                            + layout.SIDEWALK_WIDTH_M, layout.KERB_HEIGHT_M),
            "u_crown_per_d": SPLASH_CROWN_HEIGHT_PER_D, "u_splash_alpha_max": ALPHA_MAX,
        }

    def _constant_pairs(self, upd: RainUpdate) -> tuple:
        """(name, value) of every uniform that changes only with the sim (seed, layout), the world or never, for
        both programs (a name a program lacks is skipped); rebuilt when the sim's layout, the boxes' fade (the
        container size) or the world changed."""
        sim = self.sim
        key = (sim, sim.table_version, upd.boxes.fade)
        cached = self._constants
        if cached is not None and all(a is b for a, b in zip(cached[0], key, strict=True)):
            return cached[1]
        road_geom = (layout.ROAD_HALF_WIDTH_M, layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M
                     + layout.SIDEWALK_WIDTH_M, layout.KERB_HEIGHT_M)
        pairs = (
            ("u_seed_key", int(sim.key)), ("u_layer_start", np.asarray(upd.starts[:-1], np.int32).tobytes()),
            ("u_drop_table", units.RAINFALL_DROPS), ("u_box_fade", _f32(upd.boxes.fade)),
            ("u_layer_rho", _f32(upd.density)), ("u_turb_eps", TURB_EPS),
            ("u_occ_fine", units.RAINFALL_OCCLUDER), ("u_occ_coarse", units.RAINFALL_OCCLUDER_COARSE),
            ("u_occ_fine_geom", self._occ_geom["fine"]), ("u_occ_coarse_geom", self._occ_geom["coarse"]),
            ("u_period_world", PERIOD_M), ("u_ground_y", GROUND_Y_M), ("u_rain_env", units.RAINFALL_ENV),
            ("u_shape_area", _f32(self._shape_area)), ("u_shape_width", _f32(self._shape_width)),
            ("u_width_floor_px", WIDTH_FLOOR_PX), ("u_width_max_px", WIDTH_MAX_PX), ("u_alpha_max", ALPHA_MAX),
            ("u_alpha_spread", SPREAD_ALPHA), ("u_stretch_max", STRETCH_MAX),
            ("u_splash_key", int(sim.splash_key)), ("u_splash_period", SPLASH_PERIOD_S),
            ("u_splash_v", _f32(SPLASH_V_M_S)), ("u_road_height", units.RAINFALL_ROAD_HEIGHT),
            ("u_road_extent", self._road_extent), ("u_road_geom", road_geom),
            ("u_crown_per_d", SPLASH_CROWN_HEIGHT_PER_D), ("u_splash_alpha_max", ALPHA_MAX),
        )
        self._constants = (key, pairs)
        return pairs

    def _frame_values(self, upd: RainUpdate, rc, s, lights: tuple) -> tuple[list, bytes]:
        """(pairs, block) for both programs: (name, value) of the plain uniforms that may change between frames
        (float32 bytes, numbers or tuples of floats; written where they changed), and the RainFrame block's bytes
        (what changes every frame: drop_uniforms', splash_uniforms', the streaks' camera velocity and ``lights``,
        _lights' list)."""
        size = rc.size
        shift_z = rc.shift_z
        lo, ext, off, turb = box_floats(upd.boxes, upd.wind_integral_m, shift_z)
        pairs = [
            ("u_viewport", (float(size[0]), float(size[1]))),
            ("u_focal_px", float(rc.projection[1, 1]) * size[1] / 2.0),
            ("u_brightness", float(s.rainfall.streak_brightness)),
            ("u_thin", (upd.thin_a, upd.thin_b, upd.thin_c)),
            *box_shape_pairs(upd.boxes, ext), *vehicle_shape_pairs(upd.vehicles),
        ]
        (_, splash_lo), splash_ext, (_, splash_off) = splash_box_pairs(upd.boxes, SPLASH_LAYER, shift_z)
        pairs.append(splash_ext)  # the splash program's (the streak program lacks it: skipped)
        count, tau = splash_clock(upd.time_s)
        block = pack_rain_frame(lo, off, turb, vehicle_pose_floats(upd.vehicles, shift_z, float(rc.camera_position[2])),
                                upd.wind_m_s.tolist(), time_split(upd.time_s), splash_lo, count, splash_off, tau,
                                self.camera_velocity_m_s.tolist(), lights)
        return pairs, block

    def _plain_pairs(self, upd: RainUpdate, frame_pairs: list) -> tuple:
        """_constant_pairs and the frame's plain pairs (_frame_values) in one tuple, the same object while both
        hold the same values: they rarely change between frames, and OwnedUniforms.update_once then skips each
        program's ~36 comparisons with one identity test."""
        constants = self._constant_pairs(upd)
        last = self._plain
        if last is not None and last[0] is constants and (last[1] is frame_pairs or last[1] == frame_pairs):
            return last[2]
        plain = constants + tuple(frame_pairs)
        self._plain = (constants, frame_pairs, plain)
        return plain

    def _use_frame_block(self, data: bytes) -> None:
        """Bind the RainFrame buffer holding ``data`` (written only when it differs from what it holds)."""
        if data != self._frame_data:
            self._frame_buffer.write(data)
            self._frame_data = data
        self._frame_buffer.bind_to_uniform_block(RAIN_FRAME_BINDING)

    def _streak_pairs(self, rc, s) -> tuple:
        return (("u_exposure_s", float(s.camera.exposure_s)), ("u_near", float(rc.frame.camera.near_m)))

    def _use(self, prog, rc, upd: RainUpdate, frame_pairs, own_pairs, bind: bool = True) -> None:
        """Bind the frame's uniforms to prog and write this effect's where they changed (OwnedUniforms). The
        lights are RainFrame's (drop.glsl): the frame's list is in neither the program's frame block nor its
        plain uniforms."""
        rc.set_frame_uniforms(prog, bind=bind)
        cache = owned_uniforms(prog)
        cache.update_once(self._plain_pairs(upd, frame_pairs))
        cache.update_pairs(own_pairs)

    def render(self, stage: str, rc) -> None:
        upd = self.last_update
        if stage != "transparent" or self.sim is None or upd is None or upd.rate_mm_h <= 0.0:
            return
        s = self._settings(rc.frame)
        ctx = rc.ctx
        ready, self._prepared = self._prepared, None  # used once: no context kept alive past its frame
        if ready is not None and ready[0] is rc and ready[1] is rc.lights and ready[2] is upd:
            frame_pairs, block = ready[3]
        else:  # another context than update's (a test, a probe)
            frame_pairs, block = self._frame_values(upd, rc, s, self._lights(rc, upd.boxes))
        self._draw_environment(rc)
        self._env_tex.use(units.RAINFALL_ENV)
        self._bind_static()
        self._use_frame_block(block)
        ctx.enable(moderngl.BLEND | moderngl.DEPTH_TEST)  # one call for both flags
        ctx.blend_func = (moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE)
        ctx.disable(moderngl.CULL_FACE)
        rc.hdr.fbo.depth_mask = False
        bound = False  # whether the streaks' draw bound this context's frame block
        try:
            if self.sim.capacity and upd.drawn_expected > 0.0:
                self._draw_streaks(rc, upd, frame_pairs, s)
                bound = True
            if s.rainfall.splashes and upd.splashes and upd.splash_accept > 0.0:
                own = (("u_splash_accept", upd.splash_accept), ("u_splash_weight", upd.splash_weight),
                       ("u_splash_lam", upd.splash_lam), ("u_wetness", upd.wetness), ("u_puddles", upd.puddles))
                self._use(self.splash_prog, rc, upd, frame_pairs, own, bind=not bound)
                self._splash_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.sim.splash_capacity)
        finally:
            rc.hdr.fbo.depth_mask = True
            ctx.disable(moderngl.BLEND)
            ctx.blend_func = moderngl.DEFAULT_BLENDING

    def _bind_own_frame(self, rc, upd: RainUpdate, s) -> list:
        """Bind this effect's per-frame block, drop environment, table and roof maps for a view other than the
        update's (a label image, a probe); returns the frame's plain uniform pairs (_frame_values)."""
        frame_pairs, block = self._frame_values(upd, rc, s, self._lights(rc, upd.boxes))
        self._use_frame_block(block)
        self._env_tex.use(units.RAINFALL_ENV)  # colour only for a label, but never another pass's texture there
        self._bind_static()
        return frame_pairs

    def _write_records(self, rc, upd: RainUpdate, frame_pairs, s) -> None:
        """Every drop instance's streak record for rc's view (StreakPass.write, its uniforms written here)."""
        self._use(self.record_prog, rc, upd, frame_pairs, self._streak_pairs(rc, s))
        self.streaks.write(self.sim.capacity)

    def _draw_streaks(self, rc, upd: RainUpdate, frame_pairs, s) -> None:
        """The streak records for rc's view, then their quads into the bound framebuffer with the caller's
        blending and depth state."""
        self._write_records(rc, upd, frame_pairs, s)
        self.streaks.draw(self.sim.capacity, rc.size)

    def read_streaks(self, rc) -> np.ndarray:
        """Test probe: every drop instance's streak record as the GPU writes it for rc's view at the last update,
        (capacity, 14) float32 (streak_pass.RECORD_VARYINGS: head, tail, half extents, colour; head w = 0:
        culled)."""
        upd = self.last_update
        s = self._settings(rc.frame)
        self._write_records(rc, upd, self._bind_own_frame(rc, upd, s), s)
        return self.streaks.read(self.sim.capacity)

    def read_drops(self, shift_z: float = 0.0, around_z: float = 0.0) -> np.ndarray:
        """Test probe: every instance's (x, y, z in the frame shifted by shift_z, flags) as the GPU computes it
        for the last update (flags: 1 drawn by the thinning, 2 occluded), (capacity, 4) float32."""
        upd = self.last_update
        n = self.sim.capacity
        rows = max(1, -(-n // PROBE_WIDTH))
        if self._probe is None:
            self._probe = self.shaders.program("rainfall/debug_drops.vert", "rainfall/debug_drops.frag",
                                               defines={"LAYERS": len(LAYER_SCALES)})
            _bind_rain_frame_block(self._probe)
        tex = self.ctx.texture((PROBE_WIDTH, rows), 4, dtype="f4")
        fbo = self.ctx.framebuffer(color_attachments=[tex])
        vao = self.ctx.vertex_array(self._probe, [])
        try:
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            self.ctx.disable(moderngl.BLEND)
            self.ctx.disable(moderngl.DEPTH_TEST)
            values = self.drop_uniforms(upd, shift_z, around_z)
            set_uniforms(self._probe, values)
            self._use_frame_block(rain_frame_from_uniforms(values))
            set_uniforms(self._probe, u_probe_width=PROBE_WIDTH, u_probe_size=(float(PROBE_WIDTH), float(rows)))
            self._bind_static()
            vao.render(moderngl.POINTS, vertices=n)
            data = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).reshape(rows * PROBE_WIDTH, 4)
        finally:
            self.ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
            vao.release()
            fbo.release()
            tex.release()
        return data[:n].copy()

    def release(self) -> None:
        """Free the textures and vertex arrays, and the programs when the shader library is our own (a shared
        library's owner releases it: its programs serve every effect that asks for them)."""
        for obj in (self._table_tex, *self._static_tex.values()):
            if obj is not None:
                obj.release()
        self._static_tex = {}
        self._table_tex = None
        self.streaks.release()
        for obj in (self._splash_vao, self._env_vao, self._env_fbo, self._env_tex,
                    self._frame_buffer):
            obj.release()
        if self._owns_shaders:
            self.shaders.release()

    # --- label images (rain_core.labels) ---
    def render_label(self, name: str, rc, target) -> None:
        """Label image ``name`` of the frame last updated: for "rain", the streaks' opacity (the alpha the
        ``transparent`` pass blends with) as the fragment alpha into ``target.fbo``, depth-tested against its
        depth (not written). The caller (rain_core.labels) sets blending and colour mask; other names: nothing."""
        upd = self.last_update
        if name != "rain" or self.sim is None or upd is None or upd.rate_mm_h <= 0.0:
            return
        if not self.sim.capacity or upd.drawn_expected <= 0.0:
            return
        s = self._settings(rc.frame)
        frame_pairs = self._bind_own_frame(rc, upd, s)
        target.fbo.use()
        rc.ctx.enable(moderngl.DEPTH_TEST)
        rc.ctx.disable(moderngl.CULL_FACE)
        target.fbo.depth_mask = False
        try:
            self._draw_streaks(rc, upd, frame_pairs, s)
        finally:
            target.fbo.depth_mask = True
