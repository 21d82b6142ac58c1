"""The light grid: which of the frame's lights may reach each screen tile of a view (the main one, the mirrors').

Every lit fragment used to visit all the frame's lights (24 at noon, 32 at night: lamps and headlights), three
times in the scene shader (the surface, the road's water highlights, the signs) and once more for the glints on
the windshield. A light beyond its range gives nothing (``light_at`` in ``shaders/common/lighting.glsl``), but
the loop still pays for it, and a GPU or llvmpipe pays for the slowest fragment of a group. After a view's depth
pre-pass one small draw (``shaders/core/light_grid.frag``, a texel per tile of ``TILE_PX`` pixels) keeps, per
tile, the lights whose range sphere reaches into the tile's frustum up to the pre-pass's farthest depth there;
the loops then visit only those (``shaders/common/light_grid.glsl``), lowest first as before, so the pixels are
the same. No CPU work beyond the draw: the lights and the camera are the frame block's.
"""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.gfx import units
from rain_core.gfx.targets import depth_value_sampler
from rain_core.gfx.uniforms import owned_uniforms

TILE_PX = 16  # pixels per tile side: 80 × 45 tiles at 1280 × 720
KEPT_GRIDS = 4  # grids kept, one per view size (the main view, the road's reflection, the door mirrors): a
# window being resized makes a new size every frame, and the one used longest ago goes


class LightGrid:
    """The views' grids (R32UI, a bit per light): ``build`` makes one for a view after its pre-pass and binds
    it; ``masks`` reads the last one back."""

    def __init__(self, ctx: moderngl.Context, shaders):
        self.ctx = ctx
        self.prog = shaders.program("common/fullscreen.vert", "core/light_grid.frag")
        self._vao = ctx.vertex_array(self.prog, [])
        self._owned = owned_uniforms(self.prog)
        self.prog["u_depth"].value = units.LIGHT_GRID_DEPTH
        self._depth_sampler = depth_value_sampler(ctx)
        self._grids: dict = {}  # (view size, tile px) → (texture, framebuffer)
        self._last: moderngl.Texture | None = None  # the grid built last

    @staticmethod
    def read_by(*programs: moderngl.Program) -> None:
        """Point the programs' ``u_light_grid`` (common/light_grid.glsl) at the grid's unit, once when made."""
        for prog in programs:
            prog["u_light_grid"].value = units.LIGHT_GRID

    def _target(self, size: tuple[int, int], tile_px: int) -> tuple:
        """(texture, framebuffer) of the grid of a view ``size`` pixels large (kept per size, the last
        ``KEPT_GRIDS`` used: the main view and the mirror views alternate)."""
        key = (size, tile_px)
        grid = self._grids.pop(key, None)
        if grid is None:
            if len(self._grids) >= KEPT_GRIDS:  # the one used longest ago (the dict is in order of use)
                texture, fbo = self._grids.pop(next(iter(self._grids)))
                fbo.release()
                texture.release()
            tiles = (-(-size[0] // tile_px), -(-size[1] // tile_px))
            texture = self.ctx.texture(tiles, 1, dtype="u4")
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            grid = (texture, self.ctx.framebuffer(color_attachments=[texture]))
        self._grids[key] = grid  # last: the most recently used
        return grid

    def build(self, rc, depth: moderngl.Texture) -> None:
        """Sort ``rc``'s lights into its view's tiles of ``rc.light_grid_px`` pixels, bounded by ``depth`` (the
        view's depth after the scene's pre-pass, which bound ``rc``'s frame block; its size is the view's), and
        bind the grid on ``units.LIGHT_GRID``. Leaves the grid's framebuffer bound: the caller binds its own
        again."""
        texture, fbo = self._target(depth.size, rc.light_grid_px)
        camera = rc.frame.camera
        rc.set_frame_uniforms(self.prog, bind=False)  # the pre-pass just bound this view's block
        self._owned.set("u_near_far", (float(camera.near_m), float(camera.far_m)))
        self._depth_sampler.use(units.LIGHT_GRID_DEPTH)  # (its own unit: left bound, nothing else reads there)
        depth.use(units.LIGHT_GRID_DEPTH)
        fbo.use()
        self._vao.render(moderngl.TRIANGLES, vertices=3)
        texture.use(units.LIGHT_GRID)
        self._last = texture

    def masks(self) -> np.ndarray | None:
        """The grid ``build`` made last, read back (it stalls: for tests and debugging): (tile rows, tile columns)
        uint32, bottom row first; bit i set where light i may reach. None before the first ``build``."""
        texture = self._last
        if texture is None:
            return None
        return np.frombuffer(texture.read(), np.uint32).reshape(texture.size[1], texture.size[0]).copy()

    def release(self) -> None:
        for texture, fbo in self._grids.values():
            fbo.release()
            texture.release()
        self._grids.clear()
        self._last = None
        self._vao.release()
        self._depth_sampler.release()
