"""The flash in a rendered frame: the sky and the street brighten, the bolt shows where it is in view, the pass is
skipped between flashes, and the dataset labels carry the flash."""

from __future__ import annotations

import numpy as np

from rain_core.camera import look_at
from rain_core.effects.lightning.schedule import FlashSchedule
from rain_core.settings import Settings

SIZE = (200, 120)
SEED = 145  # its storm strikes 620 m away 3.2 s in (10 flashes/min): a short run sees a near flash


def _scene(gl_ctx, enabled=True):
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = 20.0
    s.time_of_day.hour = 22.0
    s.lightning.flashes_per_min = 10.0
    s.lightning.enabled = enabled
    # One frame is rendered, the flash's: an eye with no history would take its exposure from the flash itself.
    # The flash is measured against the night's exposure (rendering continuously, the eye's τ of 1.5 s does not
    # follow a 1 ms stroke).
    s.camera.auto_exposure = False
    return Scene(gl_ctx, SIZE, s, seed=SEED, gpu_timing=False)


def _near_flash(seed=SEED):
    """The first flash of the test storm that strikes within 1.5 km (farther ones fade in the rain)."""
    schedule = FlashSchedule(10.0, 8000.0, seed)
    return next(f for b in range(10) for f in schedule.block(b) if f.distance_m < 1500.0)


def _render_at(gl_ctx, t, enabled=True, face_bolt=True):
    scene = _scene(gl_ctx, enabled)
    try:
        while scene.time_s < t - 1e-9:
            scene.step(min(1 / 30, t - scene.time_s))
        flash = _near_flash(scene.seed)
        eye = np.array([-1.75, 40.0, 600.0])
        bearing = np.array([np.cos(flash.bearing_rad), 0.0, np.sin(flash.bearing_rad)])
        direction = bearing if face_bolt else -bearing
        camera = look_at(eye, eye + direction * 100.0 + np.array([0.0, 12.0, 0.0]), fov_y_deg=70.0)
        frame = scene.render(camera)
        ran = any(p.name == "lightning.transparent" and p.ran for p in scene.renderer.stats)
        return scene.image().astype(np.float64), ran, frame
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def test_flash_lights_the_sky_and_draws_the_bolt(gl_ctx):
    start = _near_flash().start_s
    lit, ran, frame = _render_at(gl_ctx, start + 0.02)
    dark, ran_off, _ = _render_at(gl_ctx, start + 0.02, enabled=False)
    assert ran and not ran_off and frame.flash is not None
    assert lit.mean() > 1.5 * dark.mean() + 2.0  # the whole frame brightens: the cloud base is lit
    # The bolt: a thin line of pixels far brighter than the lit sky around it, in the upper frame.
    luma = lit @ np.array([0.2126, 0.7152, 0.0722])
    upper = luma[: SIZE[1] // 2]
    assert (upper > np.percentile(upper, 50) + 60).sum() >= 10


def test_no_flash_no_pass(gl_ctx):
    start = _near_flash().start_s
    _, ran, frame = _render_at(gl_ctx, start - 0.5)
    assert not ran and frame.flash is None


def test_labels_carry_the_flash(gl_ctx):
    from rain_core import Session

    s = Settings()
    s.rain.rate_mm_h = 20.0
    s.lightning.flashes_per_min = 10.0
    s.quality.particle_budget = 2000  # the labels are under test, not the streaks: keep the 100 frames cheap
    start = _near_flash().start_s
    with Session(size=(64, 40), seed=SEED, camera="chase", settings=s, ctx=gl_ctx) as sim:
        steps = int(start * 30) + 1
        values = []
        for i in range(steps + 3):
            sim.step(1 / 30)
            if i == 0 or i >= steps - 3:  # labels before anything happened, then around the flash only
                lab = sim.capture().labels
                values.append((lab["lightning_lux"], lab["lightning_sky_cd_m2"]))
    assert values[0] == (0.0, 0.0)
    assert max(v[1] for v in values) > 0.1 and max(v[0] for v in values) > 0.0
