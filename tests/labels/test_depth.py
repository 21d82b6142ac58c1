"""Depth: ray length (not z) to the first opaque surface, against the camera geometry and the scene's own depth."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.labels import CLASS_IDS, render_label_images

SIZE = (64, 40)


def _flat_road_view(make_scene, effects=()):
    scene = make_scene({"traffic.count": 0, "rain.rate_mm_h": 0.0}, SIZE, effects=effects)
    scene.step(1 / 30)
    # Over the lanes, far from the ego car (z = 600 m), the bridge (300 m) and the station (700 m).
    camera = look_at((1.0, 1.5, 150.0), (1.0, 0.0, 140.0), fov_y_deg=60.0)
    return scene, scene.render(camera), camera


def test_depth_on_a_flat_road_matches_the_camera_geometry(make_scene, pixel_rays):
    scene, frame, camera = _flat_road_view(make_scene)
    li = render_label_images(scene, frame, masks=("class",))
    rays = pixel_rays(camera, SIZE)
    on_road = np.isin(li.masks["class"], (CLASS_IDS["road"], CLASS_IDS["marking"]))
    assert on_road[SIZE[1] // 2 + 2:].mean() > 0.6  # the lower half is mostly road
    expected = camera.position[1] / -rays[..., 1]  # ray length to the plane y = 0
    err = np.abs(li.depth_m[on_road] / expected[on_road] - 1.0)
    assert err.max() < 0.01, err.max()  # markings stand 4 mm proud: 0.3 % at most from 1.5 m
    # A depth buffer's z would be shorter off the axis by cos(angle to the axis): the corners show it.
    fwd = camera.basis()[2]
    off_axis = rays @ fwd < 0.9
    assert np.any(off_axis & on_road)
    assert np.all(li.depth_m[on_road & off_axis] > 1.05 * (expected * (rays @ fwd))[on_road & off_axis])


@pytest.mark.parametrize("view", ["free", "driver", "chase"])
def test_sky_is_inf_and_depth_agrees_with_the_scene_depth_buffer(make_scene, pixel_rays, view):
    if view == "free":
        scene, frame, camera = _flat_road_view(make_scene, effects=("road",))
    else:  # the cabin (driver) or the ego car (chase), and traffic
        scene = make_scene({"traffic.count": 8, "camera.mode": view, "rain.rate_mm_h": 5.0}, SIZE,
                           effects=("road", "windshield"), seed=2)
        for _ in range(10):
            scene.step(1 / 30)
            frame = scene.render()
        camera = frame.camera
    li = render_label_images(scene, frame, masks=("class",))
    sky = li.masks["class"] == CLASS_IDS["sky"]
    assert sky.any() and np.all(np.isinf(li.depth_m[sky])) and np.all(np.isfinite(li.depth_m[~sky]))
    # The renderer's own depth buffer (the frame as shown), linearised to ray length: the label pass draws the
    # same meshes with the same matrices.
    w, h = SIZE
    d = np.frombuffer(scene.renderer.hdr.depth.read(alignment=1), np.float32).reshape(h, w)[::-1]
    n, f = camera.near_m, camera.far_m
    z_view = 2.0 * n * f / (f + n - (2.0 * d - 1.0) * (f - n))
    ray_len = np.where(d < 1.0, z_view / (pixel_rays(camera, SIZE) @ camera.basis()[2]), np.inf)
    near = ~sky & (li.depth_m < 200.0)  # 24-bit depth loses precision far away
    assert near.mean() > 0.4
    assert np.array_equal(np.isinf(ray_len), sky)  # depth 1 (cleared) exactly where the labels say sky
    np.testing.assert_allclose(li.depth_m[near], ray_len[near], rtol=0.005)
