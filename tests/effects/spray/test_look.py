"""How spray looks (issue 14): water drops scatter the light around them and never glow, and droplets show as
streaks, not as smooth white puffs (shaders/spray/spray.frag, spray/shading.glsl)."""

import math

import numpy as np
import pytest

from rain_core.effects.spray.optics import radiance_bound

SIZE = (320, 180)
LUMA = np.array([0.2126, 0.7152, 0.0722])


def _with_and_without_spray(truck_scene, hour):
    """HDR frames (pre-exposed) of the same instant with the spray pass and without it, and the frame."""
    scene, _ = truck_scene(hour=hour, puddle_mm=1.5)
    scene.renderer.resize(SIZE)
    for _ in range(12):
        scene.step(1 / 30)
        scene.render()
    with_spray = scene.renderer.hdr_image()
    scene.settings.spray.enabled = False
    scene.render()  # same time: everything else draws the same
    without = scene.renderer.hdr_image()
    frame = scene.frame()
    scene.release()
    return with_spray, without, frame


def _lines_of_sight(camera, size) -> np.ndarray:
    """Unit directions (33, 33, 3) from the eye through a grid of points covering the frame."""
    r, u, f = camera.basis()
    th = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    x, y = np.meshgrid(np.linspace(-1, 1, 33) * th * size[0] / size[1], np.linspace(-1, 1, 33) * th)
    d = f + x[..., None] * r + y[..., None] * u
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return d


@pytest.mark.parametrize("hour", [12.0, 17.5])
def test_spray_is_never_brighter_than_the_light_it_scatters(truck_scene, hour):
    a, b, frame = _with_and_without_spray(truck_scene, hour)
    light = frame.lighting
    # The most forward scattering any spray in the frame can show: mu = dot(light travel, parcel → eye).
    mu_max = float(np.clip((_lines_of_sight(frame.camera, SIZE) @ np.asarray(light.sun_direction)).max(), -1.0, 1.0))
    bound = radiance_bound(light.sky_zenith, light.sky_horizon, light.sun_illuminance, light.sun_direction,
                           light.ground_albedo, mu_max=mu_max, airlight=light.sky_horizon) * light.exposure
    spray = np.abs(a - b).max(axis=-1) > 1e-4 * float(b.mean())
    assert spray.mean() > 0.05  # the lorry throws spray across a good part of the frame
    # Blended over the frame, a pixel lies between the spray's radiance and what was behind it.
    allowed = np.maximum(bound, b) * 1.02 + 1e-6
    over = (a > allowed) & spray[..., None]
    assert not over.any(), f"{over.any(axis=-1).sum()} spray pixels brighter than the sky and sun allow"


def test_droplets_are_streaks_not_smooth_puffs(truck_scene):
    a, b, _ = _with_and_without_spray(truck_scene, 12.0)
    d = (a - b) @ LUMA
    spray = np.abs(d) > 1e-4 * float((b @ LUMA).mean())
    lap = np.abs(4 * d[1:-1, 1:-1] - d[:-2, 1:-1] - d[2:, 1:-1] - d[1:-1, :-2] - d[1:-1, 2:])
    detail = lap[spray[1:-1, 1:-1]].mean() / np.abs(d[spray]).mean()
    # Smooth Gaussian puffs (the old look) gave 0.57 here; pixel-wide streaks give about 1.
    assert detail > 0.8
