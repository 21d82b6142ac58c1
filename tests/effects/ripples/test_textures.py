"""The ripples' textures (issue 5): the field's slopes and height on the GPU, and the far puddles' ring map."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.effects.ripples.backend import make_field
from rain_core.effects.ripples.rain_tiles import RainRippleTexture
from rain_core.effects.ripples.textures import RippleTextures


@pytest.mark.parametrize("backend", ["numpy32", "gpu"])
def test_normal_texture_is_central_difference(gl_ctx, shaders, backend):
    field = make_field(gl_ctx, n=64, extent_m=6.3, backend=backend, shaders=shaders)
    textures = RippleTextures(gl_ctx, field, shaders)
    try:
        field.recenter(0.0, 0.0)
        field.solver.add_impulse(3.0, 3.1, 0.5, 2e-2)
        field.step(1 / 30)
        z = field.height.astype(np.float64)
        slopes = np.frombuffer(textures.normal_texture.read(), np.float16).reshape(64, 64, 4).astype(np.float64)
        dx = (z[1:-1, 2:] - z[1:-1, :-2]) / (2 * field.cell_m)
        dz = (z[2:, 1:-1] - z[:-2, 1:-1]) / (2 * field.cell_m)
        scale = max(np.abs(dx).max(), np.abs(dz).max())
        assert scale > 0
        assert np.max(np.abs(slopes[1:-1, 1:-1, 0] - dx)) < 2e-3 * scale
        assert np.max(np.abs(slopes[1:-1, 1:-1, 1] - dz)) < 2e-3 * scale
        # B: the height itself (m, half precision), for the road's water depth.
        assert np.max(np.abs(slopes[..., 2] - z)) < 2e-3 * np.abs(z).max()
        resource = textures.water_normals()
        assert resource.texture is textures.normal_texture
        assert resource.origin_xz_m == field.origin_xz and resource.extent_m == pytest.approx(6.3)
        h = np.frombuffer(textures.height_texture.read(), np.float32)
        h = h.reshape(64, 64, -1)[..., 0]
        np.testing.assert_allclose(h, z, atol=1e-7)
    finally:
        textures.release()
        field.release()


def test_rain_ripple_texture(gl_ctx, shaders):
    tile = RainRippleTexture(gl_ctx, size=64, shaders=shaders, seed=5)
    try:
        def slopes(t, rate):
            tile.render(t, rate)
            return np.frombuffer(tile.texture.read(), np.float16).reshape(64, 64, 2).astype(np.float64)

        assert np.all(slopes(1.0, 0.0) == 0.0)
        light, heavy = slopes(1.0, 1.0), slopes(1.0, 30.0)
        assert 0 < np.sqrt(np.mean(light ** 2)) < np.sqrt(np.mean(heavy ** 2))
        np.testing.assert_array_equal(slopes(1.0, 30.0), heavy)  # deterministic for a seed and time
        assert np.any(slopes(1.2, 30.0) != heavy)  # animated
        # Seamless: the step across the wrap is no larger than steps inside the tile.
        inside = np.max(np.abs(np.diff(heavy, axis=1)))
        assert np.max(np.abs(heavy[:, 0] - heavy[:, -1])) <= inside
        assert np.max(np.abs(heavy[0, :] - heavy[-1, :])) <= np.max(np.abs(np.diff(heavy, axis=0)))
        d_light, s_light = tile.parameters(1.0)
        d_heavy, s_heavy = tile.parameters(30.0)
        assert np.all(d_heavy > d_light) and s_heavy > s_light > 0
    finally:
        tile.release()


def test_rain_tile_is_redrawn_only_when_it_changes(gl_ctx, shaders):
    """The same (time, rate) again — a paused frame — costs no draw and no mipmaps, and the map stays the one drawn
    for it; another time or rate draws, and a flat map (no rain) is cleared once."""
    tile = RainRippleTexture(gl_ctx, size=32, shaders=shaders, seed=2)

    class Counting:
        def __init__(self, vao):
            self.vao, self.draws = vao, 0

        def render(self, *args, **kwargs):
            self.draws += 1
            return self.vao.render(*args, **kwargs)

        def release(self):
            self.vao.release()

    tile._vao = counting = Counting(tile._vao)
    try:
        def slopes():
            return np.frombuffer(tile.texture.read(), np.float16).copy()

        tile.render(2.0, 20.0)
        first = slopes()
        tile.render(2.0, 20.0)
        assert counting.draws == 1
        np.testing.assert_array_equal(slopes(), first)
        tile.render(2.1, 20.0)
        tile.render(2.1, 5.0)
        assert counting.draws == 3
        tile.render(2.0, 20.0)
        np.testing.assert_array_equal(slopes(), first)
        tile.render(2.2, 0.0)
        assert np.all(slopes() == 0.0) and counting.draws == 4
    finally:
        tile.release()
