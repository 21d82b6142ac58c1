"""Frustum culling of the world tiles (rain_core/gfx/scene_draw.py): a tile wholly outside a view is not drawn
there (from the driver's seat the tile behind the car), a tile that may touch the view is, the shadow pass keeps
the casters inside the sun's view (not only the camera's), and the picture and the shadow map are the ones drawn
without culling."""

from __future__ import annotations

import types

import numpy as np
import pytest

from rain_core import layout
from rain_core.bench.frame import heavy_rain_settings
from rain_core.camera import Camera
from rain_core.gfx.scene_draw import SceneDrawer, box_outside, box_outside_frustum, frustum_planes
from rain_core.scene import Scene

SIZE = (96, 54)


def _view_proj(forward=(0.0, 0.0, 1.0)) -> np.ndarray:
    camera = Camera(position=np.array([0.0, 1.5, 0.0]), forward=np.array(forward), fov_y_deg=60.0)
    return camera.projection_matrix(16 / 9) @ camera.view_matrix()


@pytest.mark.parametrize(("lo", "hi", "outside"), [
    ((-5, 0, 10), (5, 3, 20), False),  # ahead
    ((-5, 0, -20), (5, 3, -10), True),  # behind
    ((-5, 0, -10), (5, 3, 0.2), False),  # straddles the near plane
    ((-5, 0, -10), (5, 3, 0.01), True),  # ends just short of the near plane (0.05 m)
    ((30, 0, 10), (40, 3, 20), True),  # right of the 60°×16:9 view
    ((-5, 0, 2500), (5, 3, 2600), True),  # beyond the far plane (2000 m)
    ((-5, 0, 1990), (5, 3, 2600), False),  # crosses the far plane
])
def test_box_against_the_frustum(lo, hi, outside):
    assert box_outside_frustum(_view_proj(), lo, hi) is outside


def test_box_exactly_on_a_side_plane_is_kept():
    # a box whose right face lies on the left clip plane at z = 10 m (x = −z·tan(hfov/2)) still touches the view
    vp = _view_proj()
    half_w = np.tan(np.radians(30.0)) * 16 / 9 * 10.0
    assert not box_outside_frustum(vp, (-half_w - 1.0, 1.0, 10.0), (-half_w, 2.0, 10.0))
    assert box_outside_frustum(vp, (-half_w - 1.0, 1.0, 10.0), (-half_w - 0.01, 2.0, 10.0))


def _outside_by_corners(planes, lo, hi) -> bool:
    """The box test's oracle: every one of the box's eight corners beyond one plane (the farthest corner's sum
    is the largest of the eight, rounding being monotonic, so the answers agree exactly)."""
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    return any(max(a * x + b * y + c * z + d for x, y, z in corners) < -margin for a, b, c, d, margin in planes)


def test_tiles_in_view_is_box_outside_of_each_tile():
    """The three tiles in one pass over the planes (boxes_outside): for cameras along and around a period (tile
    seams included), looking every way, each tile's answer is the corner test's of its own box, as is
    box_outside's for each box alone."""
    rng = np.random.default_rng(7)
    (lx, ly, lz), (hx, hy, hz) = box = ([-60.0, -2.0, 0.0], [60.0, 45.0, layout.PERIOD_M])
    stub = types.SimpleNamespace(_world_box=box)
    seen = np.zeros((3, 2), int)
    for i in range(3000):
        z = rng.choice((0.0, layout.PERIOD_M)) + rng.uniform(-30.0, 30.0) if i % 3 == 0 else rng.uniform(-100.0, 1300.0)
        camera = Camera(position=np.array([rng.uniform(-8.0, 8.0), rng.uniform(0.5, 3.0), z]),
                        forward=rng.normal(size=3), fov_y_deg=rng.uniform(20.0, 100.0),
                        far_m=rng.choice((200.0, 2000.0)))
        vp = camera.projection_matrix(rng.uniform(0.5, 2.5)) @ camera.view_matrix()
        planes = frustum_planes(vp)
        tiles = [((lx, ly, lz + k * layout.PERIOD_M), (hx, hy, hz + k * layout.PERIOD_M)) for k in (-1, 0, 1)]
        want = tuple(not _outside_by_corners(planes, lo, hi) for lo, hi in tiles)
        assert SceneDrawer._tiles_in_view(stub, vp) == want
        assert tuple(not box_outside(planes, lo, hi) for lo, hi in tiles) == want
        for tile, on in enumerate(want):
            seen[tile, int(on)] += 1
    assert (seen > 100).all()  # every tile both kept and culled


def _frame(gl_ctx, monkeypatch, cull: bool, camera: str = "driver"):
    """World-tile draws per draw_items call (what was culled against: "view", "light" or None; count) over one
    frame at 20 m/s, the frame's image and its shadow map's depths."""
    scene = Scene(gl_ctx, SIZE, settings=heavy_rain_settings(2000, camera=camera), seed=1, gpu_timing=False)
    try:
        scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 20.0
        for _ in range(2):
            scene.step(1 / 30, None)
            scene.render()
        calls = []
        original = SceneDrawer.draw_items

        def draw_items(self, rc, include_cabin, cull=False):
            items = original(self, rc, include_cabin, cull if cull_on else False)
            against = "view" if cull is True else None if cull is False else "light"
            calls.append((against, sum(1 for mesh, _, _ in items if mesh is self._world)))
            return items

        cull_on = cull
        monkeypatch.setattr(SceneDrawer, "draw_items", draw_items)
        scene.step(1 / 30, None)
        scene.render()
        monkeypatch.undo()
        shadow = scene.renderer.shadow.depth.read()
        return calls, scene.image(), shadow
    finally:
        scene.release()


@pytest.mark.parametrize("camera", ["driver", "chase"])
def test_tile_behind_is_culled_and_the_picture_is_the_same(gl_ctx, monkeypatch, camera):
    calls, image, shadow = _frame(gl_ctx, monkeypatch, cull=True, camera=camera)
    uncut, reference, shadow_reference = _frame(gl_ctx, monkeypatch, cull=False, camera=camera)
    assert all(count == 3 for _, count in uncut)  # without culling every view draws three tiles
    # the main view and the reflection leave the tile behind the car out; the sun's view (160 m across, the
    # tiles 1,200 m long) keeps the one tile the car is on
    lit = [count for against, count in calls if against == "light"]  # asked when planned and when drawn
    assert lit and all(count == 1 for count in lit)
    culled = [count for against, count in calls if against == "view"]
    assert len(culled) >= 2 and all(count == 2 for count in culled)
    assert np.array_equal(image, reference)
    assert shadow == shadow_reference

