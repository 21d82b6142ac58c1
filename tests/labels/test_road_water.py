"""Road water ids: the road effect's regions (dry, wet, drenched, puddle) on a pinned puddle scene."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.effects.road import RoadEffect, road_regions
from rain_core.labels import CLASS_IDS, ROAD_WATER_IDS, render_label_images

SIZE = (96, 64)
PUDDLES = {"traffic.count": 0, "rain.rate_mm_h": 0.0, "rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 1.0,
           "road.puddle_amount": 0.8, "road.puddle_seed": 7}


def _labels(make_scene, pixel_rays, values):
    scene = make_scene(values, SIZE, effects=("road",))
    scene.step(1 / 30)
    camera = look_at((0.5, 9.0, 160.0), (0.5, 0.0, 146.0), fov_y_deg=60.0)  # looking down the road from 9 m
    frame = scene.render(camera)
    li = render_label_images(scene, frame, masks=("road_water", "class"))
    point = camera.position + pixel_rays(camera, SIZE) * li.depth_m[..., None]
    return scene, frame, li, point


def test_road_water_matches_the_road_regions(make_scene, pixel_rays):
    scene, frame, li, point = _labels(make_scene, pixel_rays, PUDDLES)
    ids = li.masks["road_water"]
    road = np.isin(li.masks["class"], (CLASS_IDS["road"], CLASS_IDS["marking"]))
    assert road.mean() > 0.3
    assert np.all(ids[~road] == ROAD_WATER_IDS["not_road"])
    w, c, p = RoadEffect.levels(frame)
    assert (w, c, p) == (1.0, 1.0, 1.0)  # the pins reached the frame
    expected = road_regions(point[..., 0][road], point[..., 2][road], w, c, p, 0.8, 7, scene.world)
    got = ids[road]
    agree = np.mean(got == expected)
    assert agree > 0.97, agree  # region edges fall between texels differently in GL's filtering
    for name in ("wet", "drenched", "puddle"):
        share = np.mean(got == ROAD_WATER_IDS[name])
        assert share > 0.02, name
        assert abs(share - np.mean(expected == ROAD_WATER_IDS[name])) < 0.02, name


@pytest.mark.parametrize("values, region", [({"rain.wetness": 0.0, "rain.cracks": 0.0, "rain.puddles": 0.0}, "dry"),
                                            ({"rain.wetness": 1.0, "rain.cracks": 0.0, "rain.puddles": 0.0}, "wet")])
def test_a_dry_road_is_dry_and_a_film_only_road_is_wet(make_scene, pixel_rays, values, region):
    _, _, li, _ = _labels(make_scene, pixel_rays, {**PUDDLES, **values})
    road = li.masks["road_water"] != ROAD_WATER_IDS["not_road"]
    assert road.mean() > 0.3
    # No roof over this stretch (the bridge is at z = 300 m), so one region over the whole road.
    assert np.all(li.masks["road_water"][road] == ROAD_WATER_IDS[region])


def test_road_water_matches_the_road_debug_view(make_scene, pixel_rays):
    """The road effect's own debug view colours the regions on screen: the ids name the same colour."""
    from rain_core.effects.road import REGION_COLORS

    scene, frame, li, _ = _labels(make_scene, pixel_rays, {**PUDDLES, "road.debug_regions": True})
    hdr = scene.renderer.hdr_image()
    ids = li.masks["road_water"]
    road = li.masks["class"] == CLASS_IDS["road"]  # markings too, but their edges blend with the asphalt's
    palette = np.asarray(REGION_COLORS)
    chroma = hdr / np.maximum(hdr.sum(axis=-1, keepdims=True), 1e-9)
    shown = np.argmin(np.linalg.norm(chroma[..., None, :] - (palette / palette.sum(1, keepdims=True)), axis=-1),
                      axis=-1)
    agree = np.mean(shown[road] == ids[road])
    assert agree > 0.97, agree
    assert len(np.unique(ids[road])) >= 3
