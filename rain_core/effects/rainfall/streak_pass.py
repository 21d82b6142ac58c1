"""The streaks' two GL passes. ``shaders/rainfall/streak_record.vert`` is a transform-feedback pass (one vertex per
drop instance, nothing rasterised): it finds, culls and lights each drop once and writes its streak record into a
buffer that stays on the GPU. ``shaders/rainfall/streak.vert`` then draws one instanced quad per record. Drawn as
quads at once, a drop's work ran at each of its quad's 4 corners: a quarter of the heavy invocations now (the
streak pass 2.1–2.8× faster on llvmpipe; docs/architecture.md)."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import owned_uniforms

# A drop's streak record (streak_record.vert's outputs, streak.vert's per-instance inputs): head and tail (px from
# the view centre, clip z, clip w; w = 0 for a culled drop), half extents (px), colour and opacity.
RECORD_VARYINGS = ("r_head", "r_tail", "r_half", "r_color")
RECORD_FORMAT = "4f 4f 2f 4f/i"
RECORD_BYTES = 4 * (4 + 4 + 2 + 4)


class StreakPass:
    """The record and quad programs (``record_prog`` holds every drop uniform; the caller writes them, and binds
    the drop table, roof maps and frame blocks, before ``write``) and the records' buffer, one per drop instance.
    ``StreakPass(ctx, shaders, defines)``: ``defines`` the drop shaders' (LAYERS)."""

    def __init__(self, ctx: moderngl.Context, shaders: ShaderLibrary, defines: dict):
        self.ctx = ctx
        self.record_prog = shaders.program("rainfall/streak_record.vert", defines=defines, varyings=RECORD_VARYINGS)
        self.quad_prog = shaders.program("rainfall/streak.vert", "rainfall/streak.frag")
        self._record_vao = ctx.vertex_array(self.record_prog, [])
        self.records: moderngl.Buffer | None = None  # RECORD_BYTES per drop instance (reserve)
        self._quad_vao: moderngl.VertexArray | None = None

    def reserve(self, capacity: int) -> moderngl.Buffer:
        """The records' buffer for ``capacity`` drop instances (made again when it changes), with the quads'
        vertex array. Call it before the frame's first draw: a vertex array reading a buffer, made after, waits
        for the draws queued before it."""
        size = max(1, capacity) * RECORD_BYTES
        if self.records is None or self.records.size != size:
            self._release_records()
            self.records = self.ctx.buffer(reserve=size)
            self._quad_vao = self.ctx.vertex_array(self.quad_prog,
                                                   [(self.records, RECORD_FORMAT, *RECORD_VARYINGS)])
        return self.records

    def write(self, capacity: int) -> moderngl.Buffer:
        """Write the records of the first ``capacity`` drop instances (record_prog's uniforms as the caller set
        them); returns their buffer."""
        records = self.reserve(capacity)
        self._record_vao.transform(records, moderngl.POINTS, vertices=capacity)
        return records

    def draw(self, capacity: int, size: tuple[int, int]) -> None:
        """The quads of the records ``write`` wrote, into the bound framebuffer of ``size`` px with the caller's
        blending and depth state."""
        owned_uniforms(self.quad_prog).update_for(
            "viewport", size, lambda: {"u_viewport": (float(size[0]), float(size[1]))})
        self._quad_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=capacity)

    def read(self, capacity: int) -> np.ndarray:
        """The records ``write`` wrote, (capacity, 14) float32 (RECORD_VARYINGS' floats in order)."""
        data = np.frombuffer(self.records.read(), np.float32).reshape(-1, RECORD_BYTES // 4)
        return data[:capacity].copy()

    def _release_records(self) -> None:
        for obj in (self._quad_vao, self.records):
            if obj is not None:
                obj.release()
        self.records = self._quad_vao = None

    def release(self) -> None:
        """Free the buffer and the vertex arrays (the programs belong to the shader library)."""
        self._release_records()
        self._record_vao.release()
