"""Far puddles: a tiled, animated normal map of raindrop rings (``shaders/ripples/rain_tile.frag``) for the
standing water beyond the simulated window."""

from __future__ import annotations

import math

import moderngl
import numpy as np

from rain_core import checks, physics
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import float_target, fullscreen_triangle
from rain_core.gfx.uniforms import owned_uniforms

RAIN_TILE_CYCLE_S = 0.6  # s, life of one ring
RAIN_TILE_VISIBLE_D_MM = 1.0  # mm: drops from this diameter up make a ring visible from a car
RAIN_TILE_SLOPE_PER_MM = 0.5  # peak ring slope per mm of mean drop diameter


class RainRippleTexture:
    """A tiling, animated map of raindrop rings on standing water: RG16F slopes (dh/dx, dh/dz) over a square
    tile of ``tile_m`` metres, repeat-wrapped with mipmaps, for puddles beyond the simulated window. Rings get
    denser and stronger with the rain rate; without rain the map is flat.

    ``RainRippleTexture(ctx, size=256, tile_m=1.0, layers=4, seed=0)``; ``render(time_s, rate_mm_h)``
    redraws ``texture`` for that time (s) and rate (mm/h)."""

    def __init__(self, ctx, size: int = 256, tile_m: float = 1.0, layers: int = 4, seed: int = 0, shaders=None):
        if isinstance(size, bool) or not isinstance(size, int | np.integer) or not 8 <= size <= 4096:
            raise ValueError(f"size must be an int in [8, 4096] texels, got {size!r}")
        if not 1 <= int(layers) <= 8:
            raise ValueError(f"layers must be in [1, 8], got {layers!r}")
        self.ctx = ctx
        self.size = int(size)
        self.tile_m = checks.number("tile_m", tile_m, 1e-3, 1e3, "m")
        self.layers = int(layers)
        self.seed = int(seed) & 0xFFFFFFFF
        self._owns_shaders = shaders is None  # a library of our own: ours to release
        self.shaders = shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        self.target = float_target(ctx, (self.size, self.size), 2, "f2", filter_linear=True)
        tex = self.target.color
        tex.repeat_x = tex.repeat_y = True
        self.target.fbo.clear(0.0, 0.0, 0.0, 0.0)
        tex.build_mipmaps()
        tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        self._prog = shaders.program("common/fullscreen.vert", "ripples/rain_tile.frag")
        self._vao = fullscreen_triangle(ctx, self._prog)
        # Written before each draw through the program's one owned-uniforms cache (the library's cached program
        # may be shared with another tile): a value equal to the last one written there is skipped.
        self._constants = {"u_size": (float(self.size), float(self.size)), "u_cycle_s": RAIN_TILE_CYCLE_S,
                           "u_layers": self.layers, "u_seed": self.seed}
        self._constant_pairs = tuple(self._constants.items())
        self._uniforms_for: tuple[float, dict] | None = None  # (rate, its uniforms): the rate rarely changes
        self._drawn = (0.0, 0.0, ())  # what the map holds now (time, strength, densities): flat after the clear

    @property
    def texture(self):
        """The RG16F slope texture (dh/dx, dh/dz over the tile, dimensionless), repeat-wrapped."""
        return self.target.color

    def cells_per_side(self, layer: int) -> int:
        """Cells per tile side of a layer (matches shaders/ripples/rain_tile.frag)."""
        return 5 + 3 * layer

    def parameters(self, rate_mm_h: float) -> tuple[np.ndarray, float]:
        """(density per layer, peak slope) for a rate in mm/h. Rings per m² per s = the flux of drops of at
        least RAIN_TILE_VISIBLE_D_MM (flux × their number fraction, rain_core.physics), shared over the layers;
        a cell hosts a ring in a cycle with probability 1 − e^(−expected rings). The peak slope grows with the
        mean drop diameter 1/Λ(R) (bigger drops, stronger rings)."""
        rate = checks.number("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        density = np.zeros(self.layers)
        if rate == 0.0:
            return density, 0.0
        visible = 1.0 - float(physics.drop_diameter_cdf(RAIN_TILE_VISIBLE_D_MM, rate))
        rings_m2_s = float(physics.flux_horizontal_per_m2_s(rate)) * visible
        for layer in range(self.layers):
            cell_m2 = (self.tile_m / self.cells_per_side(layer)) ** 2
            density[layer] = -math.expm1(-rings_m2_s * cell_m2 * RAIN_TILE_CYCLE_S / self.layers)
        mean_d_mm = 1.0 / float(physics.mp_slope_per_mm(rate))
        return density, RAIN_TILE_SLOPE_PER_MM * mean_d_mm

    def render(self, time_s: float, rate_mm_h: float):
        """Draw the rings at time_s (s) for rate_mm_h (mm/h); a flat map without rain."""
        t = checks.number("time_s", time_s, 0.0, math.inf, "s")
        rate = checks.number("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        if self._uniforms_for is None or self._uniforms_for[0] != rate:
            # The drop-size law behind them costs more than the draw's CPU side: evaluated once per rate.
            density, strength = self.parameters(rate)
            self._uniforms_for = (rate, {"u_strength": strength,
                                         "u_density": tuple(density) + (0.0,) * (8 - self.layers)})
        uniforms = self._uniforms_for[1]
        # The map is a function of (time, strength, densities): the same again (a paused frame, a flat map) is
        # neither redrawn nor re-mipmapped.
        drawn = (t, uniforms["u_strength"], uniforms["u_density"])
        if uniforms["u_strength"] == 0.0:
            drawn = (0.0, 0.0, ())  # flat at any time
        if drawn == self._drawn:
            return
        self._drawn = drawn
        fbo = self.target.fbo
        if uniforms["u_strength"] == 0.0:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        else:
            owned = owned_uniforms(self._prog)
            owned.update_once(self._constant_pairs)  # one identity test while no other tile wrote its own
            owned.update(uniforms)
            owned.set("u_time", t)
            fbo.use()
            self._vao.render(vertices=3)
        self.texture.build_mipmaps()

    def release(self):
        """Free the GL objects made here, and the program when the shader library is our own."""
        self.target.release()
        self._vao.release()
        if self._owns_shaders:
            self.shaders.release()

