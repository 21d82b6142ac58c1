"""The ripple field's GL face: its height as a texture and its slopes and height (the normals pass) for the road's
water."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.gpu import WaveSolverGPU
from rain_core.gfx import units
from rain_core.gfx.frame import WaterNormals
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import float_target, fullscreen_triangle
from rain_core.gfx.uniforms import owned_uniforms


class RippleTextures:
    """``height_texture`` (R = height in m) and ``normal_texture`` (RGBA16F: slopes dh/dx, dh/dz in RG, height in m
    in B) of a ``RippleField``, both n×n with [iz, ix] = row, column, brought up to date on access when the field has
    changed (``field.version``). On the GPU backend the height texture is the solver's own state texture;
    otherwise the float32 height is uploaded. ``RippleTextures(ctx, field, shaders=None)``."""

    def __init__(self, ctx: moderngl.Context, field: RippleField, shaders: ShaderLibrary | None = None):
        self._owns_shaders = shaders is None  # a library of our own: ours to release
        self.shaders = shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        self.ctx = ctx
        self.field = field
        n = field.n
        # Four channels: RGBA16F is colour-renderable everywhere in GL 3.3 (RGB16F need not be).
        self._normals = float_target(ctx, (n, n), 4, "f2", filter_linear=True)
        self._prog = shaders.program("common/fullscreen.vert", "ripples/normals.frag")
        self._vao = fullscreen_triangle(ctx, self._prog)
        self._height_tex = None
        if not isinstance(field.solver, WaveSolverGPU):
            self._height_tex = ctx.texture((n, n), 1, dtype="f4")
            self._height_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            self._height_tex.repeat_x = self._height_tex.repeat_y = False
        self._version: int | None = None  # field.version the textures show (None: not drawn yet)
        self._uploaded: int | None = None  # field.version the height texture holds (NumPy solvers)
        self._uniforms = {"u_height": units.SCRATCH[0], "u_inv_2h": 0.5 / field.cell_m}
        self._uniform_pairs = tuple(self._uniforms.items())  # update_once: one identity test a frame

    def upload(self):
        """Write the NumPy solver's height into height_texture if the field changed since (``refresh`` does it too;
        the effect calls this before the frame's first draw: see gfx/effect.py's "upload"). No draw."""
        version = self.field.version
        if self._height_tex is not None and self._uploaded != version:
            # Written from the array itself (buffer protocol): no 4n²-byte copy through tobytes() every frame.
            self._height_tex.write(np.ascontiguousarray(self.field.solver.height, dtype=np.float32))
            self._uploaded = version

    def refresh(self):
        """Bring height_texture and normal_texture up to date (done on access)."""
        field = self.field
        if self._version == field.version:
            return
        if self._height_tex is not None:
            self.upload()
            height = self._height_tex
        else:
            height = field.solver.texture
        height.use(self._uniforms["u_height"])
        # Through the program's one owned-uniforms cache: the library's cached program may be shared with another
        # field's textures, and what this one wrote last is skipped (it never changes for one field).
        owned_uniforms(self._prog).update_once(self._uniform_pairs)
        self._normals.fbo.use()
        self._vao.render(vertices=3)
        self._version = field.version

    @property
    def height_texture(self):
        """Texture whose R channel is the height in m. On the GPU backend it is the solver's state texture, a
        different object after each step: fetch it every frame."""
        self.refresh()
        return self._height_tex if self._height_tex is not None else self.field.solver.texture

    @property
    def normal_texture(self):
        """RGBA16F texture of the slopes (dh/dx, dh/dz) of the height (dimensionless) in RG and the height (m)
        in B, linear filtering."""
        self.refresh()
        return self._normals.color

    def water_normals(self) -> WaterNormals:
        """What the road reads from ``rc.shared.water_normals``: the slope (RG) and height (B, m) texture, the world
        (x, z) in m of the centre of its texel 0, and the extent in m from the first texel centre to the last."""
        return WaterNormals(self.normal_texture, self.field.origin_xz, self.field.extent_m)

    def release(self):
        """Free the GL objects made here, and the program when the shader library is our own (the field is
        not ours)."""
        self._normals.release()
        self._vao.release()
        if self._height_tex is not None:
            self._height_tex.release()
        if self._owns_shaders:
            self.shaders.release()
