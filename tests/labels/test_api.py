"""The label API: what comes back, what is asked, and that labels leave the frame and cost nothing unused."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.labels import MASK_NAMES, LabelImages, render_label_images
from rain_core.labels.renderer import _LABELLERS

SIZE = (48, 32)


def test_shapes_types_and_the_frame_untouched(make_scene):
    scene = make_scene({"rain.rate_mm_h": 10.0, "rain.wetness": 1.0, "camera.mode": "driver"}, SIZE)
    for _ in range(3):
        scene.step(1 / 30)
        frame = scene.render()
    assert scene.renderer not in _LABELLERS  # never asked: nothing made
    before = scene.image()
    li = render_label_images(scene, frame)
    assert isinstance(li, LabelImages) and li.size == SIZE
    assert np.array_equal(scene.image(), before)  # the displayed frame is not touched
    assert li.depth_m.shape == (SIZE[1], SIZE[0]) and li.depth_m.dtype == np.float32
    assert set(li.masks) == set(MASK_NAMES)
    for name in ("rain", "glass_water", "spray"):
        assert li.masks[name].dtype == np.float32 and li.masks[name].shape == li.depth_m.shape, name
    for name in ("road_water", "class"):
        assert li.masks[name].dtype == np.uint8 and li.masks[name].shape == li.depth_m.shape, name
    assert set(np.unique(li.masks["road_water"])) <= {0, 1, 2, 3, 255}
    assert set(np.unique(li.masks["class"])) <= set(li.class_ids.values())
    assert li.masks["glass_water"].max() > 0.0  # rain on the glass in the driver's seat
    # A second frame reuses the passes and gives the same answer for the same frame.
    again = render_label_images(scene, frame)
    assert np.array_equal(again.depth_m, li.depth_m) and np.array_equal(again.masks["class"], li.masks["class"])


def test_only_the_masks_asked_for(make_scene):
    scene = make_scene({"rain.rate_mm_h": 5.0}, SIZE, effects=("rainfall",))
    scene.step(1 / 30)
    frame = scene.render()
    assert set(render_label_images(scene, frame, masks=("class",)).masks) == {"class"}
    assert set(render_label_images(scene, frame, masks="rain").masks) == {"rain"}
    with pytest.raises(ValueError, match="masks: unknown name.*allowed: rain"):
        render_label_images(scene, frame, masks=("rain", "fog"))
