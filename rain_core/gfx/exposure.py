"""Automatic exposure on the GPU: meter the pre-exposed HDR frame, adapt the eye, hand the tone map its stops.

Three small passes after the overlay, before the tone map, none of which the CPU waits for:
  meter   the frame → a 64×32 RG32F texture of (weight × log2 L, weight), then its mip chain: the top texel is
          the centre-weighted mean of log2 luminance (``rain_core.exposure.metered_log2_luminance``);
  adapt   1×1: last frame's correction moves towards the meter's target (``rain_core.exposure.adapt``);
  (tone map) multiplies the frame by 2^correction.
The correction lives in two 1×1 R32F textures used in turn, so nothing is read back; ``read_ev`` does read it,
for tests and dataset labels only (it stalls). With ``camera.auto_exposure`` off the passes do not run and the
tone map applies the compensation alone.
"""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.exposure import METER_SIZE
from rain_core.gfx import units
from rain_core.gfx.uniforms import owned_uniforms


class AutoExposure:
    """The eye's adaptation state and its passes. ``reset()`` forgets the history: the next frame takes the
    meter's target at once (a new scene, a cut)."""

    def __init__(self, ctx: moderngl.Context, shaders):
        self.ctx = ctx
        w, h = METER_SIZE
        self.top_level = int(np.log2(max(w, h)))
        self.meter_tex = ctx.texture(METER_SIZE, 2, dtype="f4")
        self.meter_tex.build_mipmaps(0, self.top_level)
        self.meter_tex.filter = (moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST)
        self.meter_fbo = ctx.framebuffer(color_attachments=[self.meter_tex])
        self.state = [ctx.texture((1, 1), 1, dtype="f4") for _ in range(2)]
        for tex in self.state:
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.state_fbo = [ctx.framebuffer(color_attachments=[tex]) for tex in self.state]
        self.current = 0  # index of the state texture holding the latest correction
        self.meter_prog = shaders.program("common/fullscreen.vert", "exposure/meter.frag")
        self.adapt_prog = shaders.program("common/fullscreen.vert", "exposure/adapt.frag")
        self._meter_vao = ctx.vertex_array(self.meter_prog, [])
        self._adapt_vao = ctx.vertex_array(self.adapt_prog, [])
        self.meter_prog["u_meter_size"].value = (float(w), float(h))
        self._reset = True

    def reset(self) -> None:
        self._reset = True

    @property
    def texture(self) -> moderngl.Texture:
        """The 1×1 R32F texture holding the latest correction (stops)."""
        return self.state[self.current]

    def update(self, hdr: moderngl.Texture, dt_s: float, tau_s: float, compensation_ev: float) -> None:
        """Meter ``hdr`` (the pre-exposed frame) and adapt for ``dt_s`` (s) with time constant ``tau_s`` (s)."""
        ctx = self.ctx
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.BLEND)
        self.meter_fbo.use()
        hdr.use(units.SCRATCH[0])
        # These programs' uniforms are written by this class alone, through OwnedUniforms: the units never
        # change and the adaptation's inputs rarely do, so most frames write none of them.
        owned_uniforms(self.meter_prog).set("u_hdr", units.SCRATCH[0])
        self._meter_vao.render(moderngl.TRIANGLES, vertices=3)
        self.meter_tex.build_mipmaps(0, self.top_level)

        nxt = 1 - self.current
        self.state_fbo[nxt].use()
        self.meter_tex.use(units.SCRATCH[0])
        self.state[self.current].use(units.SCRATCH[1])
        key = (self.top_level, float(dt_s), float(tau_s), float(compensation_ev), self._reset)
        owned_uniforms(self.adapt_prog).update_for("adapt", key, lambda: {
            "u_meter": units.SCRATCH[0], "u_previous": units.SCRATCH[1], "u_top": key[0], "u_dt_s": key[1],
            "u_tau_s": key[2], "u_compensation_ev": key[3], "u_reset": key[4]})
        self._adapt_vao.render(moderngl.TRIANGLES, vertices=3)
        self.current = nxt
        self._reset = False

    def read_ev(self) -> float:
        """The latest correction in stops (reads the GPU back: for tests and labels, not per frame)."""
        return float(np.frombuffer(self.texture.read(), dtype=np.float32)[0])

    def read_meter(self) -> float:
        """The last metered mean log2 luminance (pre-exposed), from the meter's top level (reads back)."""
        m = np.frombuffer(self.meter_tex.read(level=self.top_level), dtype=np.float32)
        return float(m[0] / m[1])

    def release(self) -> None:
        self.ctx.detect_framebuffer(0).use()
        for obj in (*self.state_fbo, *self.state, self.meter_fbo, self.meter_tex, self._meter_vao, self._adapt_vao):
            obj.release()
