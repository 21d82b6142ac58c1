"""Drips in rendered frames: under the bridge in the rain, still there after the rain while the deck drains,
gone once it has, and nothing at all on a dry day. Landing drops reach the ripples."""

from __future__ import annotations

import numpy as np

from rain_core.camera import look_at
from rain_core.settings import Settings

SIZE = (200, 120)
EYE = np.array([-3.5, 1.6, 313.0])  # under the bridge's south edge, looking north under the deck
TARGET = np.array([0.0, 3.5, 300.0])


def _scene(gl_ctx, rate=8.0):
    from rain_core.effects.drips import DripsEffect
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = rate
    s.time_of_day.hour = 15.0
    effect = DripsEffect(gl_ctx, seed=1)
    return Scene(gl_ctx, SIZE, s, seed=1, effects=[effect], gpu_timing=False), effect


def _drawn(scene) -> bool:
    return any(p.name == "drips.transparent" and p.ran for p in scene.renderer.stats)


def test_drips_under_the_bridge_in_rain_and_after_it(gl_ctx):
    scene, effect = _scene(gl_ctx)
    cam = look_at(EYE, TARGET, fov_y_deg=60.0)
    try:
        scene.step(1 / 30)
        scene.render(cam)
        wet = scene.renderer.hdr_image().copy()
        assert _drawn(scene) and effect.landed > 0  # drops land on the road: the ripples get them
        scene.settings.drips.enabled = False
        scene.render(cam)
        assert not _drawn(scene)
        plain = scene.renderer.hdr_image()
        changed = np.abs(wet - plain).sum(-1) > 1e-3
        assert changed.mean() > 0.002  # streams off both edges of the deck
        scene.settings.drips.enabled = True
        scene.settings.rain.rate_mm_h = 0.0
        for _ in range(120):  # 30 s after the rain: the deck still drains
            scene.step(0.25)
        scene.render(cam)
        assert _drawn(scene)
        effect.roofs.step(1e5, 0.0)  # a long dry while later every roof has drained
        assert not effect.active(scene.frame(cam))
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def test_dry_day_costs_nothing(gl_ctx):
    scene, effect = _scene(gl_ctx, rate=0.0)
    try:
        scene.step(1 / 30)
        scene.render(look_at(EYE, TARGET, fov_y_deg=60.0))
        assert effect.roofs is None and effect.sites is None and not _drawn(scene)
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()
