"""Sun shadows: one depth map around the camera, texel-snapped so edges do not crawl as the car moves."""

from __future__ import annotations

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


def sun_is_up(lighting) -> bool:
    return lighting.sun_direction[1] > 0.0 and float(np.max(lighting.sun_illuminance)) > 0.0


class ShadowMap:
    """``render(rc, draw_list)`` draws the depth of what ``draw_list`` yields — (mesh, model, share) with a
    ``depth_vao`` per mesh — seen from the sun, and returns the scene shader's uniforms for it."""

    def __init__(self, ctx: moderngl.Context, shaders: ShaderLibrary):
        self.ctx = ctx
        self.program = shaders.program("core/shadow.vert", "core/shadow.frag")
        self.depth = ctx.depth_texture((SHADOW_SIZE, SHADOW_SIZE))
        self.depth.compare_func = "<="
        self.depth.filter = (moderngl.LINEAR, moderngl.LINEAR)  # hardware 2×2 PCF per tap
        self.depth.repeat_x = self.depth.repeat_y = False
        self.fbo = ctx.framebuffer(depth_attachment=self.depth)

    def bind(self) -> None:
        self.depth.use(units.SHADOW_MAP)

    def render(self, rc: RenderContext, draw_list) -> dict:
        ctx = self.ctx
        sun = np.asarray(rc.frame.lighting.sun_direction, dtype=np.float64)
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
        proj[2, 3] = -1.0  # z_view in [−depth, 0] → NDC [1, −1]: nearest to the sun at −1
        light_view_proj = proj @ view
        self.fbo.use()
        self.fbo.clear(depth=1.0)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.BLEND)
        self.program["u_light_view_proj"].write(mat4_bytes(light_view_proj))
        for mesh, model, _share in draw_list:
            self.program["u_model"].write(mat4_bytes(model))
            mesh.depth_vao.render(moderngl.TRIANGLES, vertices=mesh.count)
        to_texture = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
        return {"u_shadow_matrix": mat4_bytes(to_texture @ light_view_proj), "u_shadow_map": units.SHADOW_MAP,
                "u_shadow_params": (1.0, 1.0 / SHADOW_SIZE, 0.06 / SHADOW_DEPTH_M)}

    def release(self) -> None:
        self.fbo.release()
        self.depth.release()
