"""The rainbow pass: where it lights the frame (the bow's angles and colour order in a rendered image) and when it
is skipped entirely (night, high sun, no rain, the bow outside the view)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.lighting import lighting_for_hour
from rain_core.settings import Settings

SIZE = (240, 160)


def _antisolar_camera(hour: float, fov: float = 80.0, elevation_deg: float = 22.0):
    """Above the roofs, looking at the antisolar point's azimuth, raised so the bow's top is in view."""
    sun = lighting_for_hour(hour).sun_direction
    anti = -np.asarray(sun, dtype=np.float64)
    anti[1] = 0.0
    anti /= np.linalg.norm(anti)
    eye = np.array([-1.75, 40.0, 700.0])
    target = eye + anti * 100.0 + np.array([0.0, 100.0 * math.tan(math.radians(elevation_deg)), 0.0])
    return look_at(eye, target, fov_y_deg=fov, far_m=4000.0)


def _scene(gl_ctx, hour=17.0, rate=4.0, enabled=True):
    from rain_core.effects.rainbow import RainbowEffect
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = rate
    s.time_of_day.hour = hour
    s.rainbow.enabled = enabled
    scene = Scene(gl_ctx, SIZE, s, seed=1, effects=[RainbowEffect(gl_ctx)], gpu_timing=False)
    scene.step(1.0 / 30.0)
    return scene


def _render(gl_ctx, camera, **kw) -> tuple[np.ndarray, bool]:
    scene = _scene(gl_ctx, **kw)
    try:
        scene.render(camera)
        ran = any(p.name == "rainbow.post" and p.ran for p in scene.renderer.stats)
        return scene.image().astype(np.float64), ran
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def _pixel_angles_deg(camera, hour: float) -> np.ndarray:
    """θ (deg) of each pixel's ray from the antisolar point, (H, W), image rows top first."""
    w, h = SIZE
    r, u, f = camera.basis()
    t = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    xs = ((np.arange(w) + 0.5) / w * 2 - 1) * t * w / h
    ys = (1 - (np.arange(h) + 0.5) / h * 2) * t
    rays = f[None, None, :] + xs[None, :, None] * r[None, None, :] + ys[:, None, None] * u[None, None, :]
    rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
    anti = -np.asarray(lighting_for_hour(hour).sun_direction)
    return np.degrees(np.arccos(np.clip(rays @ anti, -1, 1)))


def test_bow_lies_at_the_rainbow_angles_with_red_outside(gl_ctx):
    cam = _antisolar_camera(17.0)
    with_bow, ran = _render(gl_ctx, cam)
    without, ran_off = _render(gl_ctx, cam, enabled=False)
    assert ran and not ran_off
    diff = with_bow - without
    theta = _pixel_angles_deg(cam, 17.0)
    lum = diff @ np.array([0.2126, 0.7152, 0.0722])
    primary = (theta > 40.5) & (theta < 42.8)
    band = (theta > 44.5) & (theta < 48.5)
    assert primary.sum() > 200 and band.sum() > 200
    assert lum[primary].mean() > 4.0 * max(lum[band].mean(), 0.05)
    assert lum[primary].mean() > 1.0  # visible: at least a level of 255 on average
    # Red's centroid lies outside blue's on the primary.
    ring = (theta > 39.5) & (theta < 43.5)
    red = np.clip(diff[..., 0], 0, None)[ring]
    blue = np.clip(diff[..., 2], 0, None)[ring]
    assert (theta[ring] * red).sum() / red.sum() > (theta[ring] * blue).sum() / blue.sum() + 0.2


@pytest.mark.parametrize("case", ["night", "noon", "dry", "facing the sun", "disabled"])
def test_no_bow_no_pass(gl_ctx, case):
    hour = {"night": 22.0, "noon": 12.0}.get(case, 17.0)
    cam = _antisolar_camera(hour)
    if case == "facing the sun":
        cam = look_at(cam.position, cam.position - (cam.forward * np.array([1, 0, 1])) * 100, fov_y_deg=60.0)
    _, ran = _render(gl_ctx, cam, hour=hour, rate=0.0 if case == "dry" else 4.0, enabled=case != "disabled")
    assert not ran


def test_bow_stays_on_the_departing_shower_then_goes(gl_ctx):
    from rain_core.effects.rainbow import RainbowEffect

    s = Settings()
    s.time_of_day.hour = 17.0
    s.rain.rate_mm_h = 4.0
    effect = RainbowEffect(gl_ctx)
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, SIZE, s, seed=1, effects=[effect], gpu_timing=False)
    cam = _antisolar_camera(17.0)
    try:
        scene.step(0.1)
        scene.render(cam)
        s.rain.rate_mm_h = 0.0
        for _ in range(100):  # 10 s later: the shower is 100 m off, still in front
            scene.step(0.1)
        scene.render(cam)
        assert effect.column is not None and effect.column.near_m == pytest.approx(100.0, abs=1.5)
        s.rainbow.shower_speed_m_s = 40.0
        for _ in range(2000):  # 500 s later, at 40 m/s, it is beyond sight
            scene.step(0.25)
        assert not effect.active(scene.frame(cam))
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()
