"""Render targets: float colour (+ depth) framebuffers, ping-pong pairs, colour-only views."""

from __future__ import annotations

from dataclasses import dataclass

import moderngl


@dataclass
class RenderTarget:
    """A framebuffer with one colour texture and an optional depth texture."""

    fbo: moderngl.Framebuffer
    color: moderngl.Texture
    depth: moderngl.Texture | None

    @property
    def size(self) -> tuple[int, int]:
        return self.color.size

    def release(self):
        # Releasing the bound framebuffer leaves a dead name bound: later framebuffers then fail with
        # GL_INVALID_OPERATION. Bind the default one first.
        self.fbo.ctx.detect_framebuffer(0).use()
        for obj in (self.fbo, self.color, self.depth):
            if obj is not None:
                obj.release()


def depth_value_sampler(ctx: moderngl.Context) -> moderngl.Sampler:
    """A sampler that reads a depth texture's values (a depth texture compares by default), texel by texel and
    clamped: for passes that read the scene's depth (soft particles, fog, the windshield's copy of the frame)."""
    return ctx.sampler(compare_func="", filter=(moderngl.NEAREST, moderngl.NEAREST), repeat_x=False, repeat_y=False)


def float_target(ctx: moderngl.Context, size: tuple[int, int], components: int = 4, dtype: str = "f2",
                 depth: bool = False, filter_linear: bool = True) -> RenderTarget:
    """A float colour target (``f2`` half or ``f4`` full precision), clamped at the edges."""
    color = ctx.texture(size, components, dtype=dtype)
    flt = moderngl.LINEAR if filter_linear else moderngl.NEAREST
    color.filter = (flt, flt)
    color.repeat_x = color.repeat_y = False
    depth_tex = ctx.depth_texture(size) if depth else None
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth_tex)
    return RenderTarget(fbo, color, depth_tex)


class PingPong:
    """Two float targets of one size that swap roles: read ``src``, write ``dst``, then ``swap()``."""

    def __init__(self, ctx: moderngl.Context, size: tuple[int, int], components: int = 2, dtype: str = "f4",
                 filter_linear: bool = False):
        self.targets = [float_target(ctx, size, components, dtype, filter_linear=filter_linear) for _ in range(2)]
        self._index = 0

    @property
    def src(self) -> RenderTarget:
        return self.targets[self._index]

    @property
    def dst(self) -> RenderTarget:
        return self.targets[1 - self._index]

    def swap(self):
        self._index = 1 - self._index

    def release(self):
        for target in self.targets:
            target.release()


class ColorView:
    """A framebuffer onto another target's colour texture without its depth, so a pass can sample that depth
    while it draws. Rebuilt when the texture *object* changes (after a resize): GL names are reused by drivers,
    so comparing ``.glo`` could keep drawing into a deleted texture."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._texture = None
        self._fbo: moderngl.Framebuffer | None = None

    def fbo(self, texture: moderngl.Texture) -> moderngl.Framebuffer:
        if texture is not self._texture or self._fbo is None:
            self.release()
            self._texture = texture
            self._fbo = self.ctx.framebuffer(color_attachments=[texture])
        return self._fbo

    def release(self) -> None:
        if self._fbo is not None:
            self.ctx.detect_framebuffer(0).use()
            self._fbo.release()
        self._fbo = self._texture = None


def fullscreen_triangle(ctx: moderngl.Context, program: moderngl.Program) -> moderngl.VertexArray:
    """A VAO that draws one triangle covering the viewport (vertex shader uses gl_VertexID)."""
    return ctx.vertex_array(program, [])
