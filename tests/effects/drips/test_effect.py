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


def test_visible_ranges_follow_the_sites():
    """The sites' z list (for bisect) is made again when the sites change: the ranges are np.searchsorted's."""
    from types import SimpleNamespace

    from rain_core import layout
    from rain_core.effects.drips import DripsEffect

    effect = DripsEffect(None, seed=1)

    def expected(z, camera_z, reach):
        base = np.floor(camera_z / layout.PERIOD_M) * layout.PERIOD_M
        out = []
        for offset in (-layout.PERIOD_M, 0.0, layout.PERIOD_M):
            a, b = np.searchsorted(z, [camera_z - reach - base - offset, camera_z + reach - base - offset])
            if b > a:
                out.append((int(a), int(b - a), base + offset))
        return out

    for z in (np.array([1.0, 5.0, 300.0, 1195.0]), np.array([2.0, 250.0, 310.0, 320.0, 900.0])):
        effect.sites = SimpleNamespace(z=z)
        for camera_z in (0.0, 305.0, 1199.0, -400.0):
            assert effect._visible_ranges(camera_z, 60.0) == expected(z, camera_z, 60.0)


def test_range_uniforms_are_the_last_draws(gl_ctx):
    """u_first and u_z_offset are written only where they differ from the last draw's: after two ranges, one
    range with the first's values must still be written."""
    from rain_core import layout

    scene, effect = _scene(gl_ctx)
    cam = look_at(EYE, TARGET, fov_y_deg=60.0)
    plans = [[(0, 4, 0.0), (8, 4, 1200.0)], [(0, 4, 0.0)], [(8, 4, 1200.0)], [(8, 4, 1200.0)], [(3, 2, -1200.0)]]
    try:
        for plan in plans:
            effect._visible_ranges = lambda camera_z, reach_m, plan=plan: list(plan)
            scene.step(1 / 30)
            scene.render(cam)
            first, _, z_base = plan[-1]
            assert effect._prog["u_first"].value == first
            shift_z = np.floor(EYE[2] / layout.PERIOD_M) * layout.PERIOD_M  # the renderer's
            assert effect._prog["u_z_offset"].value == np.float32(z_base - shift_z)
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def test_sites_depend_on_the_seed_not_on_what_ran_before():
    """Scenes share their world (rain_core.world.shared): the drip sites found for it are kept per seed, so a
    scene's sites (and pixels) are the same whichever seed an earlier scene of the process asked for first."""
    from rain_core.effects.drips.edges import find_drip_sites
    from rain_core.effects.drips.effect import _SITES, drip_sites_of
    from rain_core.world.shared import shared_world

    world = shared_world(1)
    m = world.occluder_map
    fresh = {seed: find_drip_sites(m.grid, m.x0_m, m.cell_m, seed) for seed in (0, 1)}
    assert not np.array_equal(fresh[0].phase, fresh[1].phase)  # the seed matters: the test can tell them apart
    _SITES.clear()
    for seed in (1, 0, 1):
        sites = drip_sites_of(world, seed)
        assert np.array_equal(sites.phase, fresh[seed].phase) and np.array_equal(sites.x, fresh[seed].x)
