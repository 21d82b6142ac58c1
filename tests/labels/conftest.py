"""Helpers for the label tests: small scenes with pinned weather, and the rays of a frame's pixels."""

from __future__ import annotations

import numpy as np
import pytest

EFFECTS = ("road", "ripples", "rainfall", "spray", "windshield", "atmosphere")
CHEAP = {"quality.ripple_grid": 64, "quality.windshield_resolution": 128, "quality.particle_budget": 20_000,
         "spray.budget": 3000, "windshield.drop_budget": 1000}


@pytest.fixture
def make_scene(gl_ctx):
    """make_scene(values, size=(64, 40), effects=(...)) → a Scene with those settings; released after the test."""
    from rain_core.labels import release_labels
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    made = []

    def make(values: dict, size=(64, 40), effects=EFFECTS, seed: int = 1):
        settings = Settings()
        for key, value in {**CHEAP, **{f"{e}.enabled": e in effects for e in EFFECTS}, **values}.items():
            set_value(settings, key, value)
        scene = Scene(gl_ctx, size, settings, seed=seed, gpu_timing=False)
        made.append(scene)
        return scene

    yield make
    for scene in made:
        release_labels(scene)
        scene.release()


@pytest.fixture
def pixel_rays():
    """pixel_rays(camera, size): unit world directions of the pixel centres (tests import no conftest)."""
    return _pixel_rays


def _pixel_rays(camera, size) -> np.ndarray:
    """Unit world directions (H, W, 3) through the pixel centres, top row first (the camera's own projection)."""
    w, h = size
    right, up, fwd = camera.basis()
    t = np.tan(np.radians(camera.fov_y_deg) / 2.0)
    x = ((np.arange(w) + 0.5) / w * 2.0 - 1.0) * t * (w / h)
    y = (1.0 - (np.arange(h) + 0.5) / h * 2.0) * t
    d = x[None, :, None] * right + y[:, None, None] * up + fwd
    return d / np.linalg.norm(d, axis=-1, keepdims=True)
