"""The light grid: which of the frame's lights may reach each screen tile of the main view.

Every lit fragment used to visit all the frame's lights (24 at noon, 32 at night: lamps and headlights), three
times in the scene shader (the surface, the road's water highlights, the signs) and once more for the glints on
the windshield. A light beyond its range gives nothing (``light_at`` in ``shaders/common/lighting.glsl``), but
the loop still pays for it, and a GPU or llvmpipe pays for the slowest fragment of a group. Before the scene pass
one small draw (``shaders/core/light_grid.frag``, a texel per tile of ``TILE_PX`` pixels) keeps, per tile, the
lights whose range sphere reaches into the tile's frustum, bounded by the farthest depth of the scene's depth
pre-pass there; the loops then visit only those
(``shaders/common/light_grid.glsl``), lowest first as before, so the pixels are the same. No CPU work beyond the
draw: the lights and the camera are the frame block's.
"""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.gfx import units
from rain_core.gfx.targets import depth_value_sampler
from rain_core.gfx.uniforms import owned_uniforms

TILE_PX = 16  # pixels per tile side: 80 × 45 tiles at 1280 × 720


class LightGrid:
    """The grid texture (R32UI, a bit per light) of the view ``build`` was last given."""

    def __init__(self, ctx: moderngl.Context, shaders):
        self.ctx = ctx
        self.prog = shaders.program("common/fullscreen.vert", "core/light_grid.frag")
        self._vao = ctx.vertex_array(self.prog, [])
        self._owned = owned_uniforms(self.prog)
        self._depth_sampler = depth_value_sampler(ctx)
        self._grid: tuple | None = None  # ((view size, tile px), texture, framebuffer)

    def _target(self, size: tuple[int, int], tile_px: int) -> tuple:
        if self._grid is None or self._grid[0] != (size, tile_px):
            self._release_grid()
            tiles = (-(-size[0] // tile_px), -(-size[1] // tile_px))
            texture = self.ctx.texture(tiles, 1, dtype="u4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._grid = ((size, tile_px), texture, self.ctx.framebuffer(color_attachments=[texture]))
        return self._grid

    def build(self, rc, depth: moderngl.Texture) -> None:
        """Sort ``rc``'s lights into its view's tiles of ``rc.light_grid_px`` pixels, bounded by ``depth`` (the
        view's depth after the scene's pre-pass), and bind the grid on ``units.LIGHT_GRID``. Leaves the grid's
        framebuffer bound: the caller binds its own again."""
        _, texture, fbo = self._target(rc.size, rc.light_grid_px)
        camera = rc.frame.camera
        rc.set_frame_uniforms(self.prog)
        self._owned.set("u_near_far", (float(camera.near_m), float(camera.far_m)))
        self._owned.set("u_depth", units.SCRATCH[0])
        self._depth_sampler.use(units.SCRATCH[0])
        depth.use(units.SCRATCH[0])
        fbo.use()
        self._vao.render(moderngl.TRIANGLES, vertices=3)
        self._depth_sampler.clear(units.SCRATCH[0])
        texture.use(units.LIGHT_GRID)

    def masks(self) -> np.ndarray | None:
        """The last grid read back (it stalls: for tests and debugging): (tile rows, tile columns) uint32, bottom
        row first; bit i set where light i may reach. None before the first ``build``."""
        if self._grid is None:
            return None
        texture = self._grid[1]
        return np.frombuffer(texture.read(), np.uint32).reshape(texture.size[1], texture.size[0]).copy()

    def _release_grid(self) -> None:
        if self._grid is not None:
            self._grid[2].release()
            self._grid[1].release()
            self._grid = None

    def release(self) -> None:
        self._release_grid()
        self._vao.release()
        self._depth_sampler.release()
