"""The effects' masks: rain streak coverage, glass water, spray opacity."""

from __future__ import annotations

import numpy as np

from rain_core.labels import CLASS_IDS, render_label_images
from rain_core.settings import set_value

SIZE = (80, 48)


def _rain_mask(make_scene, rate_mm_h: float) -> np.ndarray:
    scene = make_scene({"rain.rate_mm_h": rate_mm_h, "camera.mode": "chase", "traffic.count": 0}, SIZE,
                       effects=("rainfall",), seed=4)
    for _ in range(4):
        scene.step(1 / 30)
        frame = scene.render()
    return render_label_images(scene, frame, masks=("rain",)).masks["rain"]


def test_rain_mask_is_empty_without_rain_and_grows_with_the_rate(make_scene):
    assert not np.any(_rain_mask(make_scene, 0.0))
    shares, means = [], []
    for rate in (2.0, 10.0, 50.0):
        mask = _rain_mask(make_scene, rate)
        assert mask.dtype == np.float32 and mask.min() >= 0.0 and mask.max() <= 1.0
        shares.append(np.mean(mask > 0.01))
        means.append(float(mask.mean()))
    assert shares[0] > 0.0
    assert shares[0] < shares[1] < shares[2], shares
    assert means[0] < means[1] < means[2], means


def test_glass_water_only_in_the_drivers_seat(make_scene):
    scene = make_scene({"rain.rate_mm_h": 20.0, "camera.mode": "driver", "wipers.mode": "off", "traffic.count": 0},
                       SIZE, effects=("windshield",))
    for _ in range(15):
        scene.step(1 / 30)
        frame = scene.render()
    li = render_label_images(scene, frame, masks=("glass_water", "class"))
    glass = li.masks["glass_water"]
    assert glass.dtype == np.float32 and glass.max() <= 1.0
    assert glass.mean() > 0.02  # drops on the glass
    cabin = li.masks["class"] == CLASS_IDS["ego_cabin"]
    low = np.zeros_like(cabin)
    low[-SIZE[1] // 6:] = True
    assert np.any(cabin & low)
    assert np.all(glass[cabin & low] == 0.0)  # the dashboard hides the glass
    set_value(scene.settings, "camera.mode", "chase")  # the same wet glass, seen from behind the car
    scene.step(1 / 30)
    li = render_label_images(scene, scene.render(), masks=("glass_water",))
    assert not np.any(li.masks["glass_water"])


def test_spray_mask_follows_the_spray(make_scene):
    values = {"rain.rate_mm_h": 8.0, "rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 0.5,
              "camera.mode": "chase", "traffic.count": 8}
    masks = {}
    for on in (True, False):
        scene = make_scene(values, SIZE, effects=("road", "spray") if on else ("road",))
        for _ in range(20):
            scene.step(1 / 30)
            frame = scene.render()
        masks[on] = render_label_images(scene, frame, masks=("spray",)).masks["spray"]
    assert masks[True].max() > 0.2 and np.mean(masks[True] > 0.01) > 0.01
    assert not np.any(masks[False])
