"""Sun shadows: one depth map around the camera, texel-snapped so edges do not crawl as the car moves."""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core.gfx import units
from rain_core.gfx.frame import RenderContext
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import mat4_bytes

SHADOW_SIZE = 2048  # px
SHADOW_HALF_M = 80.0  # m, half the side of the square the map covers
SHADOW_DEPTH_M = 500.0  # m, depth range along the sun's rays

# The scene shader's shadow inputs while the sun is down (no map is sampled).
NO_SHADOW = {"u_shadow_params": (0.0, 0.0, 0.0), "u_shadow_map": units.SHADOW_MAP}


# The light's orthographic projection: view z in [−depth, 0] → NDC [1, −1] (nearest to the sun at −1).
_LIGHT_PROJ = np.diag([1.0 / SHADOW_HALF_M, 1.0 / SHADOW_HALF_M, -2.0 / SHADOW_DEPTH_M, 1.0])
_LIGHT_PROJ[2, 3] = -1.0
_LIGHT_PROJ.flags.writeable = False
_TO_TEXTURE = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])  # NDC → [0, 1]
_TO_TEXTURE.flags.writeable = False


def sun_is_up(lighting) -> bool:
    # ndarray.max, not np.max's Python-level wrapper: asked every frame
    return lighting.sun_direction[1] > 0.0 and float(np.asarray(lighting.sun_illuminance).max()) > 0.0


class ShadowMap:
    """``render(rc, draw_list)`` draws the depth of what ``draw_list`` yields — (mesh, model, share) with a
    ``depth_vao`` per mesh, model a 4×4 matrix or its ``mat4_bytes`` — seen from the sun, and returns the scene
    shader's uniforms for it."""

    def __init__(self, ctx: moderngl.Context, shaders: ShaderLibrary):
        self.ctx = ctx
        self.program = shaders.program("core/shadow.vert", "core/shadow.frag")
        self.depth = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
        self.depth.compare_func = "<="
        self.depth.filter = (moderngl.LINEAR, moderngl.LINEAR)  # hardware 2×2 PCF per tap
        self.depth.repeat_x = self.depth.repeat_y = False
        self.fbo = ctx.framebuffer(depth_attachment=self.depth)
        self._axes_key = None
        self._axes_value = None
        self._light_of = None  # (render context, its camera, the light's view-projection, its bytes, uniforms)

    def bind(self) -> None:
        self.depth.use(units.SHADOW_MAP)

    def _axes(self, sun: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The light view's x and y axes for the sun direction (kept while the sun does not move)."""
        key = tuple(sun)
        if self._axes_key != key:
            up = np.array([0.0, 0.0, 1.0]) if abs(sun[1]) > 0.99 else np.array([0.0, 1.0, 0.0])
            lx = np.cross(up, sun)
            lx /= np.linalg.norm(lx)
            self._axes_key, self._axes_value = key, (lx, np.cross(sun, lx))
        return self._axes_value

    def light_view_proj(self, rc: RenderContext) -> np.ndarray:
        """The sun's view-projection (world in the wrapped frame → the map's clip space) for ``rc``'s camera, made
        once per context: the renderer culls the casters against it before ``render`` draws them."""
        cached = self._light_of
        if cached is not None and cached[0] is rc and cached[1] is rc.frame.camera:
            return cached[2]
        sun = np.asarray(rc.frame.lighting.sun_direction, dtype=np.float64)
        forward = np.asarray(rc.frame.camera.forward, dtype=np.float64)  # as Camera.basis normalises it
        # math.sqrt of the dot product: np.linalg.norm's own formula for a vector, without its wrapper
        norm = math.sqrt(forward.dot(forward))
        f = forward / norm if norm > 0 else forward
        ahead = np.array([f[0], 0.0, f[2]])
        ahead /= max(math.sqrt(ahead.dot(ahead)), 1e-9)
        center = rc.camera_position + ahead * SHADOW_HALF_M * 0.6
        lx, ly = self._axes(sun)
        texel = 2.0 * SHADOW_HALF_M / SHADOW_SIZE
        for axis in (lx, ly):  # snap the centre to whole texels across the light's view
            c = float(center @ axis)
            center = center + (round(c / texel) * texel - c) * axis
        eye = center + sun * SHADOW_DEPTH_M * 0.5
        view = np.eye(4)
        view[0, :3], view[1, :3], view[2, :3] = lx, ly, sun
        view[:3, 3] = -view[:3, :3] @ eye
        light_view_proj = _LIGHT_PROJ @ view
        light_view_proj.flags.writeable = False
        # Both products and their bytes at once, before any GL call: made after the draws, the second product cost
        # ~40 µs more (BLAS's code cold) than made right after the first.
        uniforms = {"u_shadow_matrix": mat4_bytes(_TO_TEXTURE @ light_view_proj), "u_shadow_map": units.SHADOW_MAP,
                    "u_shadow_params": (1.0, 1.0 / SHADOW_SIZE, 0.06 / SHADOW_DEPTH_M)}
        self._light_of = (rc, rc.frame.camera, light_view_proj, mat4_bytes(light_view_proj), uniforms)
        return light_view_proj

    def frame_uniforms(self, rc: RenderContext) -> dict:
        """The scene shader's shadow inputs for ``rc`` (the map ``render`` draws for it): known before it is drawn,
        so the renderer packs the frame block ahead of the draws."""
        self.light_view_proj(rc)
        return self._light_of[4]

    def render(self, rc: RenderContext, draw_list) -> dict:
        """Draw the depths of ``draw_list`` for ``rc``; returns ``frame_uniforms(rc)``."""
        ctx = self.ctx
        self.light_view_proj(rc)
        light_bytes, uniforms = self._light_of[3:]
        self.fbo.use()
        self.fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.BLEND)
        self.program["u_light_view_proj"].write(light_bytes)
        model_u = self.program["u_model"]
        for mesh, model, _share in draw_list:
            model_u.write(model if isinstance(model, bytes) else mat4_bytes(model))
            mesh.depth_vao.render(moderngl.TRIANGLES, vertices=mesh.count)
        return uniforms

    def release(self) -> None:
        self.fbo.release()
        self.depth.release()
