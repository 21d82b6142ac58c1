"""The spray effect (GL): feeds the emitter every frame, uploads the newly spawned parcels to two GPU rings and
draws them in the ``transparent`` stage."""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core import layout
from rain_core.effects.spray.emitter import SprayEmitter
from rain_core.effects.spray.optics import shader_defines
from rain_core.effects.spray.parcels import PARTICLE_ATTRIBUTES, PARTICLE_DTYPE, PARTICLE_FORMAT
from rain_core.effects.spray.wheels import WheelWater
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.targets import ColorView, depth_value_sampler
from rain_core.gfx.uniforms import owned_uniforms


class SprayEffect(Effect):
    """Wheel splash and spray for every vehicle (``rain_core.effects.spray``), drawn in the ``transparent`` stage.

    ``SprayEffect(ctx, settings=None, *, seed=0, shaders=None)``: settings are read per frame from
    ``frame.settings.spray`` (enabled, strength, budget) and ``camera.exposure_s`` (streak length); ``settings``
    here only sizes the first budget. ``emitter.film_depth_fn`` (x, z) → mm, if set, replaces the road's film
    (the weather's wet film is still added).

    After each frame: ``wheels`` (WheelWater per vehicle, ego first), :meth:`hydroplaning_risk`,
    :meth:`landed_in_water`, ``emitter.stats``. Publishes ``rc.shared.droplet_impacts`` for the ripples. The HDR
    depth is read on texture unit ``units.SPRAY_DEPTH``.
    """

    name = "spray"
    stages = ("upload", "transparent")  # upload: the new parcels into the GPU rings (update is CPU work alone)
    # Each frame's new parcels written as they come, drawn or not (left for the next drawn frame, their ranges
    # would pile up and be written at once there, a slot as often as the ring wrapped over it).
    state_stages = ("upload",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders=None):
        self.ctx = ctx
        self._shaders = shaders
        budget = settings.spray.budget if settings is not None else 12_000
        self.emitter = SprayEmitter(seed=seed, budget=budget)
        self._buffers: list[moderngl.Buffer | None] = [None, None]
        self._vaos: list[moderngl.VertexArray | None] = [None, None]
        self._capacity = [-1, -1]
        self._program = None
        self._motion = None  # (frame, camera, velocity, forward) made by update for the frame's draw
        self._color_fbo = ColorView(ctx)  # the HDR colour without its depth (the pass samples that depth)
        self._depth_sampler = depth_value_sampler(ctx)

    # --- queries for the app ------------------------------------------------------------------------------
    @property
    def wheels(self) -> list[WheelWater]:
        return self.emitter.wheels

    def hydroplaning_risk(self, vehicle=None) -> np.ndarray:
        """(4,) risk per wheel (0…1) of ``vehicle`` (default: the first, the ego) in the last frame."""
        for w in self.emitter.wheels:
            if vehicle is None or w.vehicle is vehicle:
                return w.hydroplaning_risk.copy()
        return np.zeros(4)

    @property
    def ego_hydroplaning_risk(self) -> float:
        """Largest per-wheel risk of the ego car in the last frame (0…1), for the panel's indicator."""
        return float(self.hydroplaning_risk().max())

    def landed_in_water(self) -> list[tuple[float, float, float]]:
        """(x m, z m, downward momentum kg·m/s) of the parcels that landed in standing water this frame."""
        return self.emitter.landed_in_water()

    # --- Effect -------------------------------------------------------------------------------------------
    @staticmethod
    def _section(frame):
        settings = getattr(frame, "settings", None)
        if settings is not None:  # (three asks a frame: the import below only for a frame without settings)
            return settings.spray
        from rain_core.settings import SpraySection

        return SpraySection()

    @staticmethod
    def _switched_on(sec) -> bool:
        return bool(sec.enabled and sec.budget > 0 and sec.strength > 0.0)

    def observe(self, frame) -> None:
        """The water model (and so the hydroplaning risk) is evaluated every frame, running or not; switched off,
        the parcels in flight are dropped and the emitter forgets the last time it saw."""
        self.emitter.observe_only(frame)
        if not self._switched_on(self._section(frame)):
            self.emitter.pause()

    def active(self, frame) -> bool:
        """Runs while wheels throw water or parcels are still in flight (and the effect is on with a budget)."""
        if not self._switched_on(self._section(frame)):
            return False
        return self.emitter.throwing() or self.emitter.alive_until() > self.emitter.clock(frame.time_s)

    def update(self, frame, rc) -> None:
        sec = self._section(frame)
        self.emitter.set_budget(sec.budget)
        if sec.strength != self.emitter.strength:  # (the setter checks the value: only when it changes)
            self.emitter.strength = sec.strength
        self.emitter.emit(frame)
        # Where the spray lands in standing water, the ripple effect (if running) presses dents.
        rc.shared.droplet_impacts = self.emitter.landed_impacts()
        # The pass's camera velocity and forward, made here, before the frame's draws: made in render, after the
        # scene's draws, the same few NumPy calls ran cold (~50 us instead of ~5, measured in-frame).
        self._motion = (frame, frame.camera, *self._camera_motion(frame, frame.camera))

    def _upload(self, rc) -> None:
        dirty = self.emitter.take_dirty()
        rings = self.emitter.rings
        for ring in range(2):
            data = rings[ring].data
            cap = rings[ring].capacity
            if self._capacity[ring] != cap:
                for obj in (self._vaos[ring], self._buffers[ring]):
                    if obj is not None:
                        obj.release()
                self._vaos[ring] = self._buffers[ring] = None
                if cap:
                    self._buffers[ring] = self.ctx.buffer(data.tobytes())
                    # Its VAO now, before the frame's draws: made at the first draw it waited ~18 ms for llvmpipe's
                    # driver thread to finish the draws queued before it.
                    self._vaos[ring] = self.ctx.vertex_array(
                        self._prog(rc), [(self._buffers[ring], PARTICLE_FORMAT, *PARTICLE_ATTRIBUTES)])
                self._capacity[ring] = cap
                continue
            buf = self._buffers[ring]
            rows = rings[ring].floats  # (the records' bytes as plain float rows: a cheaper memoryview)
            # Only the slots written since the last frame (one range, two where the ring wrapped): the new parcels.
            for start, count in dirty[ring]:
                buf.write(memoryview(rows[start:start + count]).cast("B"), offset=start * PARTICLE_DTYPE.itemsize)

    def _prog(self, rc) -> moderngl.Program:
        if self._program is None:
            lib = self._shaders or rc.shaders
            self._program = lib.program("spray/spray.vert", "spray/spray.frag", defines=shader_defines())
        return self._program

    def _hdr_color_fbo(self, rc) -> moderngl.Framebuffer:
        # The pass reads the scene's depth, so it writes through a framebuffer without that depth attached.
        return self._color_fbo.fbo(rc.hdr.color)

    @staticmethod
    def _camera_motion(frame, camera) -> tuple[tuple, tuple]:
        """(the ego's velocity, the camera's normalised forward) as float tuples, for u_camera_vel and
        u_cam_forward."""
        vel = tuple(frame.ego.velocity().tolist()) if frame.ego is not None else (0.0, 0.0, 0.0)
        # camera.basis()[2] (the normalised forward) without the right and up vectors it also makes. (Not cached
        # across frames: the driver's camera turns a little every frame.)
        # The dot stays NumPy's (BLAS may fuse it); its square root and the three divisions are IEEE's in floats too.
        fwd = np.asarray(camera.forward, dtype=np.float64)
        norm = math.sqrt(fwd.dot(fwd))
        fx, fy, fz = fwd.tolist()
        if norm > 0:
            fx, fy, fz = fx / norm, fy / norm, fz / norm
        return vel, (fx, fy, fz)

    def _set_uniforms(self, prog, rc, now: float) -> None:
        """The pass's own uniforms, through the program's OwnedUniforms: only those that changed since the last
        write are written (the clock, camera velocity and forward change every frame; the rest rarely, so they
        are looked at only when what they are made of changes)."""
        frame = rc.frame
        camera = frame.camera
        motion = self._motion  # made by update for this frame and camera (the frame's draw), else made now
        if motion is not None and motion[0] is frame and motion[1] is camera:
            vel, forward = motion[2], motion[3]
        else:
            vel, forward = self._camera_motion(frame, camera)
        owned = owned_uniforms(prog)
        owned.update({"u_clock": float(now), "u_shift_periods": float(round(rc.shift_z / layout.PERIOD_M)),
                      "u_camera_vel": vel, "u_cam_forward": forward})
        exposure_s = getattr(getattr(frame.settings, "camera", None), "exposure_s", 0.02)
        key = (exposure_s, rc.size[0], rc.size[1], camera.near_m, camera.far_m, camera.fov_y_deg)
        owned.update_for("static", key, lambda: {
            "u_exposure_s": float(exposure_s), "u_depth": units.SPRAY_DEPTH,
            "u_viewport": (float(rc.size[0]), float(rc.size[1])),
            "u_near": float(camera.near_m), "u_far": float(camera.far_m),
            "u_pixel_angle": 2.0 * math.tan(math.radians(camera.fov_y_deg) / 2.0) / rc.size[1],
        })

    def render(self, stage: str, rc) -> None:
        if stage == "upload":
            self._upload(rc)
            return
        if stage != "transparent":
            return
        frame = rc.frame
        now = self.emitter.clock(frame.time_s)
        if self.emitter.alive_until() <= now:
            return
        ctx = self.ctx
        prog = self._prog(rc)
        rc.set_frame_uniforms(prog)
        self._set_uniforms(prog, rc, now)
        self._depth_sampler.use(units.SPRAY_DEPTH)
        rc.hdr.depth.use(units.SPRAY_DEPTH)
        self._hdr_color_fbo(rc).use()
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE)
        for ring in (1, 0):  # mist behind, droplets over it (no sorting: both are soft and mostly thin)
            vao = self._vaos[ring]  # (made with its buffer, in _upload)
            if vao is not None and self.emitter.rings[ring].last_death() > now:
                vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.emitter.rings[ring].capacity)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)  # as the scene pass left it
        self._depth_sampler.clear(units.SPRAY_DEPTH)
        rc.hdr.fbo.use()

    def release(self) -> None:
        """Free the rings' buffers and VAOs, the colour view and the depth sampler. The program belongs to the
        shader library's cache (shared, released with its context)."""
        for obj in (*self._vaos, *self._buffers):
            if obj is not None:
                obj.release()
        self._vaos = [None, None]
        self._buffers = [None, None]
        self._capacity = [-1, -1]
        self._motion = None
        self._color_fbo.release()
        self._depth_sampler.release()

    # --- label images (rain_core.labels) ---
    def render_label(self, name: str, rc, target) -> None:
        """Label image ``name`` of the frame last rendered: for "spray", the parcels' opacity (the alpha the
        ``transparent`` pass blends with) as the fragment alpha into ``target.color_fbo``, hidden and softened by
        ``target.depth`` as the pass is by the scene's. The caller (rain_core.labels) sets blending and colour
        mask; other names, or nothing in flight: nothing drawn."""
        if name != "spray" or self._program is None:
            return
        frame = rc.frame
        now = self.emitter.clock(frame.time_s)
        if self.emitter.alive_until() <= now:
            return
        prog = self._program
        rc.set_frame_uniforms(prog)
        self._set_uniforms(prog, rc, now)
        self._depth_sampler.use(units.SPRAY_DEPTH)
        target.depth.use(units.SPRAY_DEPTH)
        target.color_fbo.use()
        rc.ctx.disable(moderngl.DEPTH_TEST)
        try:
            for ring in (1, 0):
                vao = self._vaos[ring]  # (made with its buffer, in _upload)
                if vao is not None and self.emitter.rings[ring].last_death() > now:
                    vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.emitter.rings[ring].capacity)
        finally:
            rc.ctx.enable(moderngl.DEPTH_TEST)
            self._depth_sampler.clear(units.SPRAY_DEPTH)
