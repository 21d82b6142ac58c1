"""The light grid (rain_core/gfx/light_grid.py): the same pixels as visiting every light, no light left out of a
tile where it reaches a surface drawn there, and lights left out where they cannot reach."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.effects.atmosphere import pixel_distances
from rain_core.gfx.light_grid import TILE_PX
from rain_core.scene import Scene
from rain_core.settings import Settings

SIZE = (192, 108)


def _night_drive(gl_ctx, grid_px: int, frames: int = 4) -> Scene:
    """A night street in rain at 60 km/h (lamps and headlights: the frame's full 32 lights), ``frames`` frames."""
    settings = Settings()
    settings.time_of_day.hour = 22.0
    settings.rain.rate_mm_h = 8.0
    scene = Scene(gl_ctx, SIZE, settings=settings, seed=3, gpu_timing=False)
    scene.renderer.light_grid_px = grid_px
    scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 60 / 3.6
    for _ in range(frames):
        scene.step(1 / 30, None)
        scene.render()
    return scene


@pytest.fixture(scope="module")
def night(gl_ctx):
    with gl_ctx:  # made before the per-test fixture makes the shared context current
        scene = _night_drive(gl_ctx, TILE_PX)
    yield scene
    with gl_ctx:
        scene.release()


def test_the_grid_gives_the_pixels_of_every_light(gl_ctx, night):
    """The loops visit a tile's lights lowest first, as the loop over all of them did, and a light left out gives
    nothing there: the images are the same to the bit, the mirror views' grids included."""
    views = {size for size, _ in night.renderer.light_grid._grids}
    assert (SIZE in views) and len(views) >= 2  # the main view's grid and a mirror view's (the road's reflection)
    without = _night_drive(gl_ctx, 0)
    try:
        assert without.renderer.light_grid.masks() is None  # no grid was built
        np.testing.assert_array_equal(np.asarray(night.image()), np.asarray(without.image()))
    finally:
        without.release()


def test_no_tile_misses_a_light_that_reaches_what_it_shows(night):
    """For every pixel the scene drew (its depth after the frame, cars included), each light whose range sphere
    holds the pixel's surface point is in the pixel's tile."""
    renderer = night.renderer
    masks = renderer.light_grid.masks()
    rc = renderer.render_context(night.frame())
    count = rc.lights[3]
    assert count == 32
    pos = np.frombuffer(rc.lights[0], np.float32).reshape(-1, 4)[:count].astype(np.float64)
    depth = np.frombuffer(renderer.hdr.depth.read(alignment=1), np.float32).reshape(SIZE[1], SIZE[0])
    dist, dirs = pixel_distances(depth, rc.view_proj, rc.camera_position)
    drawn = depth < 1.0
    assert drawn.mean() > 0.5
    points = rc.camera_position + dirs[drawn] * dist[drawn, None]
    rows, cols = np.nonzero(drawn)
    tile_bits = masks[rows // TILE_PX, cols // TILE_PX]
    reached = 0
    for i in range(count):
        inside = np.linalg.norm(points - pos[i, :3], axis=-1) <= 0.999 * abs(pos[i, 3])
        reached += inside.sum()
        missing = inside & ((tile_bits >> np.uint32(i)) & 1 == 0)
        assert not missing.any(), f"light {i} reaches {missing.sum()} pixels whose tile leaves it out"
    assert reached > 0


def test_the_grid_leaves_out_lights_that_cannot_reach(night):
    """Lights behind the camera, beside the view or beyond the tile's depth are left out: tiles hold fewer than
    all 32 lights, and the near tiles (the car's hood and dashboard, bottom rows) fewer than the sky's."""
    masks = night.renderer.light_grid.masks()
    counts = np.vectorize(lambda m: bin(int(m)).count("1"))(masks)
    assert counts.max() <= 32
    assert counts.mean() < 28
    assert counts[0].mean() < counts[-1].mean()  # bottom row (the hood, near) against the top (sky: no depth bound)


def test_a_window_being_resized_keeps_a_few_grids(gl_ctx):
    """A new view size makes a grid; past KEPT_GRIDS the one used longest ago goes, and the newest is the view's."""
    from rain_core.gfx.light_grid import KEPT_GRIDS

    scene = _night_drive(gl_ctx, TILE_PX, frames=1)
    try:
        renderer = scene.renderer
        for width in range(200, 200 + 8 * 16, 16):
            renderer.resize((width, 108))
            scene.step(1 / 30, None)
            scene.render()
            assert len(renderer.light_grid._grids) <= KEPT_GRIDS
        assert renderer.light_grid.masks().shape == (-(-108 // TILE_PX), -(-(200 + 7 * 16) // TILE_PX))
    finally:
        scene.release()
