"""Lightning's GL side. The storm is weather (``storm.py``): the Scene asks it which flash lights a frame, lights
the cloud base through the frame's lighting, and hands the flash over as ``Frame.flash``. This effect adds the
flash to the frame's light list (a far point light: lit surfaces, wet roads and puddles, the rain streaks and the
spray catch it as they catch the lamps, and the atmosphere's light scattering spreads it in the rain) and draws
the bolt where it is in view (``shaders/lightning``).

Cost: the effect runs only while a flash is lit in the shutter — between flashes (most frames of a storm) and
without a storm it does nothing at all.
"""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core.effects.lightning.bolt import bolt_segments
from rain_core.effects.lightning.storm import BOLT_COLOR
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import Frame, RenderContext
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import owned_uniforms
from rain_core.lighting import LightSet

HALF_WIDTH_PX = 1.5  # the strip a sub-pixel channel is spread over (bolt.frag)


class LightningEffect(Effect):
    """Draws the flash of ``Frame.flash``: its light in the light list, its bolt.

    ``LightningEffect(ctx, settings=None, *, seed=0, shaders=None)``; the flashes themselves come from the
    scene's storm (seeded with the scene).
    """

    name = "lightning"
    stages = ("transparent",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders: ShaderLibrary | None = None):
        self.ctx = ctx
        self.settings = settings
        self._shaders = shaders
        self._storm = None  # the last frame's storm: the panel shows its thunder delay
        self._bolt_of: tuple | None = None  # (flash seed, wrap) whose bolt is in the buffer
        self._segment_count = 0
        self._vbo: moderngl.Buffer | None = None
        self._vao: moderngl.VertexArray | None = None
        self._prog: moderngl.Program | None = None

    def observe(self, frame: Frame) -> None:
        self._storm = getattr(frame, "storm", None)

    def active(self, frame) -> bool:
        return getattr(frame, "flash", None) is not None

    def describe(self) -> str:
        return self._storm.describe() if self._storm is not None else "no storm"

    def frame_lights(self, frame: Frame) -> LightSet:
        f = frame.flash
        return LightSet(f.light[None, :], np.array([[0.0, -1.0, 0.0]]), np.array([f.intensity_cd * f.transmittance]),
                        BOLT_COLOR[None, :], np.array([-1.0]), np.array([-1.0]), np.array([1.0e6]),
                        np.array([False]))

    def update(self, frame: Frame, rc: RenderContext) -> None:
        f = frame.flash
        key = (f.flash.seed, rc.shift_z)
        if self._bolt_of == key:
            return
        segments, weights = bolt_segments(f.top, f.ground, f.flash.seed)
        data = np.zeros((len(segments), 7), np.float32)
        data[:, 0:3] = rc.wrap(segments[:, 0])
        data[:, 3:6] = rc.wrap(segments[:, 1])
        data[:, 6] = weights
        if self._vbo is None or self._vbo.size < data.nbytes:
            self._release_buffers()
            self._vbo = self.ctx.buffer(reserve=max(data.nbytes, 7 * 4 * 1024))
        self._vbo.write(data.tobytes())
        self._segment_count = len(segments)
        self._bolt_of = key

    def render(self, stage: str, rc: RenderContext) -> None:
        f = rc.frame.flash
        if stage != "transparent" or f is None or self._segment_count == 0:
            return
        if self._prog is None:
            self._prog = (self._shaders or rc.shaders).program("lightning/bolt.vert", "lightning/bolt.frag")
        if self._vao is None:
            self._vao = self.ctx.vertex_array(self._prog, [(self._vbo, "3f 3f 1f /i", "a_p0", "a_p1", "a_weight")])
        prog = self._prog
        rc.set_frame_uniforms(prog)
        length = max(float(np.linalg.norm(f.top - f.ground)), 1.0)
        fov = math.radians(rc.frame.camera.fov_y_deg)
        owned_uniforms(prog).update({
            "u_viewport": (float(rc.size[0]), float(rc.size[1])), "u_half_width_px": HALF_WIDTH_PX,
            "u_line_cd_per_m": f.intensity_cd / length, "u_pixel_rad": 2.0 * math.tan(fov / 2.0) / rc.size[1],
            "u_bolt_color": tuple(float(c) for c in BOLT_COLOR)})
        ctx = self.ctx
        ctx.enable(moderngl.DEPTH_TEST)
        rc.hdr.fbo.depth_mask = False  # test against the scene's depth, never write it
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE
        self._vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self._segment_count)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        rc.hdr.fbo.depth_mask = True

    def _release_buffers(self) -> None:
        if self._vao is not None:
            self._vao.release()
            self._vao = None
        if self._vbo is not None:
            self._vbo.release()
            self._vbo = None
        self._bolt_of = None

    def release(self) -> None:
        self._release_buffers()
        self._prog = None  # owned by the (shared, caching) ShaderLibrary
