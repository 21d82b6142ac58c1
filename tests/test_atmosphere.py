"""Atmosphere (issue 9): extinction from the rain, contrast law, skip when clear, glow and light scattering
against their NumPy references. Renders are tiny (≤ 160×90) worlds built here, so each test sees one thing."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from rain_core import atmosphere as atm
from rain_core import physics
from rain_core.camera import look_at
from rain_core.lighting import Light, lighting_for_hour, pack_lights
from rain_core.mesh import MAT_CONCRETE, MAT_EMISSIVE, concat, from_trimesh
from rain_core.renderer import CLEAR_AIR_EXTINCTION_PER_M, Frame, Renderer
from rain_core.settings import AtmosphereSection, Settings
from rain_core.world import StreetLamp

LUMA = np.array([0.2126, 0.7152, 0.0722])


@pytest.fixture(autouse=True)
def _clean_gl(gl_ctx):
    """Each test leaves no GL error behind, and a live framebuffer bound (the session shares one context)."""
    assert gl_ctx.error == "GL_NO_ERROR"
    yield
    assert gl_ctx.error == "GL_NO_ERROR"


def _box(center, extents, albedo, material=MAT_CONCRETE):
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return from_trimesh(mesh, np.asarray(albedo, np.float32), 0.9, 0.0, material)


def _world(parts, lamps=()):
    return SimpleNamespace(vertices=concat(parts), lamps=list(lamps))


def _frame(camera, world, settings, rate, hour):
    lighting = lighting_for_hour(hour, atm.sky_overcast(settings.atmosphere, rate))
    return Frame(0.0, 0.0, camera, lighting, world, weather=SimpleNamespace(rate_mm_h=rate), settings=settings)


def _renderer(ctx, shaders, world, size, effect=True):
    effects = [atm.Atmosphere(ctx, shaders)] if effect else []
    return Renderer(ctx, size, world, effects=effects, shaders=shaders, gpu_timing=False)


def _release(*renderers):
    """Release renderers and bind the default framebuffer: a released framebuffer left bound would make every
    later framebuffer creation on the shared context fail with GL_INVALID_OPERATION."""
    for r in renderers:
        r.release()
    renderers[0].ctx.detect_framebuffer(0).use()


def _bottom_first(renderer):
    """HDR colour and depth of the last frame, bottom row first (as GL stores them)."""
    w, h = renderer.size
    depth = np.frombuffer(renderer.hdr.depth.read(alignment=1), dtype=np.float32).reshape(h, w)
    return renderer.hdr_image()[::-1].astype(np.float64), depth


# --- the model --------------------------------------------------------------------------------------------


def test_extinction_follows_weber_and_visibility_is_the_5_percent_distance():
    rates = np.array([0.5, 2.0, 10.0, 50.0])
    beta = np.array([atm.extinction_per_m(r) for r in rates])
    np.testing.assert_allclose(beta - CLEAR_AIR_EXTINCTION_PER_M, 0.312e-3 * rates**0.67, rtol=1e-12)
    assert atm.extinction_per_m(10.0, fog_scale=2.0, haze_per_km=3.0) == pytest.approx(
        CLEAR_AIR_EXTINCTION_PER_M + 2 * 0.312e-3 * 10**0.67 + 3e-3)
    vis = atm.visibility_m(beta)
    np.testing.assert_allclose(atm.transmittance(beta, vis), 0.05, rtol=1e-12)
    assert np.all(np.diff(vis) < 0)
    # 10 mm/h: β ≈ 1.56 /km → about 1.9 km of visibility.
    assert 1800 < atm.visibility_m(atm.extinction_per_m(10.0)) < 2000


def test_rain_grey_is_a_gradual_function_of_the_rate():
    r = np.linspace(0.0, 100.0, 100001)
    o = atm.rain_overcast(r)
    assert o[0] == 0.0 and np.all(np.diff(o) > 0) and np.all(o < 1.0)
    assert np.max(np.diff(o)) < 1e-3  # no switch anywhere: at most 0.001 per 0.001 mm/h
    assert atm.rain_overcast(2.0) == pytest.approx(2.0 / 3.5)
    sec = AtmosphereSection()
    assert atm.sky_overcast(sec, 10.0) == atm.rain_overcast(10.0)
    assert atm.sky_overcast(AtmosphereSection(sky_darkening=0.25), 10.0) == 0.25
    assert atm.sky_overcast(AtmosphereSection(enabled=False), 10.0) == 0.0
    with pytest.raises(ValueError):
        atm.rain_overcast(-1.0)


def test_fog_colour_greys_with_the_rain_and_the_sun_side_glows():
    lighting = lighting_for_hour(12.0)  # the Scene would grey this too; the airlight greys on its own
    sec = AtmosphereSection()

    def saturation(c):
        return (c.max() - c.min()) / c.max()

    sats = [saturation(atm.atmosphere_state(sec, r, lighting).airlight) for r in (0.5, 2.0, 10.0, 50.0)]
    assert np.all(np.diff(sats) < 0)
    state = atm.atmosphere_state(sec, 10.0, lighting)
    towards = atm.airlight(state, state.sun_direction)
    away = atm.airlight(state, -state.sun_direction)
    assert towards @ LUMA > 3 * (away @ LUMA)
    mu = np.linspace(-1, 1, 200001)
    assert np.trapezoid(atm.phase_rain(mu), mu) * 2 * math.pi == pytest.approx(1.0, abs=1e-6)
    assert atm.phase_rain(-1.0) == pytest.approx(1 / 18.8, rel=0.01)  # lidar ratio of water drops


def test_active_only_with_rain_or_haze(gl_ctx):
    eff = atm.Atmosphere(gl_ctx)

    def frame(rate, **kw):
        return SimpleNamespace(rain_rate_mm_h=rate, settings=Settings(atmosphere=AtmosphereSection(**kw)))

    assert not eff.active(frame(0.0))
    assert eff.active(frame(0.1))
    assert eff.active(frame(0.0, haze_per_km=2.0))
    assert not eff.active(frame(10.0, enabled=False))
    assert not eff.active(frame(10.0, fog_scale=0.0))
    eff.release()


# --- rendered -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("rate", [2.0, 10.0, 30.0])
def test_contrast_of_a_dark_building_falls_as_exp_minus_beta_d(gl_ctx, shaders, rate):
    """(L_obj − L_sky)/L_sky of a dark box against the horizon, from the HDR frame, vs C0·exp(−β·d)."""
    size = (160, 90)
    settings = Settings()
    settings.atmosphere.light_scattering = 0.0
    beta = atm.extinction_per_m(rate)
    eye = np.array([0.0, 10.0, 600.0])
    camera = look_at(eye, eye + np.array([0.0, 0.0, -1.0]), fov_y_deg=30.0, far_m=5000.0)
    for d in (150.0, 500.0, 1000.0):  # < one 1200 m tile: the box's periodic copies stay hidden
        # A 1 m thick slab whose face towards the eye is d metres away.
        world = _world([_box(eye - np.array([0.0, 0.0, d + 0.5]), (0.25 * d, 0.25 * d, 1.0), (0.03, 0.03, 0.03))])
        frame = _frame(camera, world, settings, rate, 12.0)
        fogged = _renderer(gl_ctx, shaders, world, size)
        fogged.render(frame)
        img = fogged.hdr_image() @ LUMA
        plain = _renderer(gl_ctx, shaders, world, size, effect=False)
        plain.extinction_per_m = 0.0  # no atmosphere at all: the box's own radiance L0
        plain.render(frame)
        l0 = np.median((plain.hdr_image() @ LUMA)[43:48, 78:83])
        l_obj = np.median(img[43:48, 78:83])
        l_sky = np.median(np.concatenate([img[43:48, 38:41], img[43:48, 120:123]]))
        contrast = (l_obj - l_sky) / l_sky
        expected = (l0 - l_sky) / l_sky * math.exp(-beta * d)
        assert contrast == pytest.approx(expected, rel=0.10), (rate, d, contrast, expected)
        _release(fogged, plain)


def test_no_rain_no_haze_skips_the_pass_and_a_rate_drop_returns_to_clear_air(gl_ctx, shaders):
    size = (96, 54)
    world = _world([_box((0.0, 5.0, 500.0), (20.0, 10.0, 20.0), (0.3, 0.3, 0.3))],
                   [StreetLamp(np.array([0.0, 7.0, 560.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3))])
    camera = look_at((3.0, 1.5, 600.0), (0.0, 4.0, 500.0), fov_y_deg=60.0)
    settings = Settings()
    plain = _renderer(gl_ctx, shaders, world, size, effect=False)
    plain.render(_frame(camera, world, settings, 0.0, 22.0))
    clear = plain.hdr_image()
    r = _renderer(gl_ctx, shaders, world, size)
    r.render(_frame(camera, world, settings, 0.0, 22.0))
    assert [(s.name, s.ran) for s in r.stats if s.name.startswith("atmosphere")] == [("atmosphere", False)]
    np.testing.assert_array_equal(r.hdr_image(), clear)
    r.render(_frame(camera, world, settings, 20.0, 22.0))
    ran = {s.name for s in r.stats if s.ran}
    assert {"atmosphere.update", "atmosphere.post"} <= ran
    rainy = r.hdr_image()
    assert np.all(np.isfinite(rainy)) and np.abs(rainy - clear).max() > 0.01
    r.render(_frame(camera, world, settings, 0.0, 22.0))
    np.testing.assert_array_equal(r.hdr_image(), clear)
    assert r.extinction_per_m == CLEAR_AIR_EXTINCTION_PER_M and r.airlight is None
    _release(r, plain)


def _glow_scene(gl_ctx, shaders, rate, glow, resolution=1.0):
    """A small bright emissive patch 30 m ahead of a dark wall at 60 m, at night: returns (before, after,
    weight w, σ px, k) with colours bottom row first."""
    size = (128, 72)
    world = _world([_box((0.0, 1.5, 540.0), (60.0, 40.0, 1.0), (0.05, 0.05, 0.05)),
                    _box((0.0, 1.5, 570.0), (0.4, 0.4, 0.4), (2.0, 2.0, 2.0), MAT_EMISSIVE)])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 1.5, 500.0), fov_y_deg=40.0)
    out = []
    for g in (0.0, glow):
        settings = Settings()
        settings.atmosphere.glow = g
        settings.atmosphere.glow_resolution = resolution
        settings.atmosphere.light_scattering = 0.0
        r = _renderer(gl_ctx, shaders, world, size)
        frame = _frame(camera, world, settings, rate, 22.0)
        r.render(frame)
        color, depth = _bottom_first(r)
        effect = r.effects[0]
        rc = r.render_context(frame)
        dist, dirs = atm.pixel_distances(depth, rc.view_proj, rc.camera_position)
        w = 1.0 - np.exp(-effect.state.medium_per_m * dist)
        out.append((color, w, effect.glow_sigma_px, effect.state.glow_strength))
        _release(r)
    (before, w, sigma, _), (after, _, _, k) = out
    return before, after, w, sigma, k


def test_glow_matches_the_numpy_reference_and_only_moves_light(gl_ctx, shaders):
    before, after, w, sigma, k = _glow_scene(gl_ctx, shaders, 30.0, 2.0)
    reference = atm.glow_reference(before, w, k, sigma)
    halo = (reference - before) @ LUMA
    err = (after - reference) @ LUMA
    assert np.abs(halo).max() > 0.05  # the halo is there
    assert np.abs(err).max() < 0.02 * np.abs(halo).max()
    assert (after @ LUMA).sum() == pytest.approx((before @ LUMA).sum(), rel=0.01)


def test_halo_grows_in_size_and_strength_with_the_rain(gl_ctx, shaders):
    profiles = {}
    for rate in (3.0, 50.0):
        before, after, _, sigma, _ = _glow_scene(gl_ctx, shaders, rate, 1.0, resolution=0.25)
        halo = (after - before) @ LUMA
        cy, cx = np.unravel_index(np.argmax(before @ LUMA), halo.shape)
        profiles[rate] = (halo[cy, cx + 6], halo[cy, cx + 12], sigma)
    assert atm.glow_sigma_rad(atm.medium_extinction_per_m(50.0)) > 2 * atm.glow_sigma_rad(
        atm.medium_extinction_per_m(3.0))
    assert profiles[50.0][0] > 3 * profiles[3.0][0] > 0
    assert profiles[50.0][1] > 10 * max(profiles[3.0][1], 1e-6)


def test_light_scattering_matches_single_scattering_reference(gl_ctx, shaders):
    """A down-lit street lamp, a sideways lamp and a low-beam headlight cone against the dense quadrature."""
    size = (96, 64)
    world = _world([_box((0.0, -50.0, -3000.0), (1.0, 1.0, 1.0), (0.1, 0.1, 0.1))])
    lights = [
        Light(np.array([2.0, 6.0, 580.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3),
              math.cos(math.radians(75)), math.cos(math.radians(55)), 70.0),
        Light(np.array([-4.0, 3.0, 575.0]), np.array([1.0, 0.0, 0.0]), 3000.0, np.array([1.0, 0.8, 0.6]),
              math.cos(math.radians(75)), math.cos(math.radians(55)), 70.0),
        Light(np.array([1.0, 0.7, 590.0]), np.array([0.0, -0.026, -1.0]) / np.linalg.norm([0.0, -0.026, -1.0]),
              20000.0, np.array([1.0, 0.96, 0.88]), math.cos(math.radians(30)), math.cos(math.radians(12)),
              150.0, low_beam=True),
    ]
    camera = look_at((-3.0, 2.0, 604.0), (1.0, 2.5, 570.0), fov_y_deg=60.0)
    rate = 20.0
    images = []
    for scale in (0.0, 1.0):
        settings = Settings()
        settings.atmosphere.glow = 0.0
        settings.atmosphere.light_scattering = scale
        r = _renderer(gl_ctx, shaders, world, size)
        original = r.render_context

        def with_lights(frame, *args, _original=original, **kwargs):
            rc = _original(frame, *args, **kwargs)
            rc.lights = pack_lights(lights)  # our lights, no vehicles needed
            return rc

        r.render_context = with_lights
        frame = _frame(camera, world, settings, rate, 22.0)
        r.render(frame)
        images.append(_bottom_first(r)[0])
        state, rc = r.effects[0].state, r.render_context(frame)
        _release(r)
    shader = (images[1] - images[0])[1::3, 1::3]  # every third pixel: the reference is dense and slow
    _, dirs = atm.pixel_distances(np.ones(size[::-1]), rc.view_proj, rc.camera_position)
    ref = sum(atm.light_inscatter_reference(rc.camera_position, dirs[1::3, 1::3], atm.SCATTER_MAX_M, light,
                                            state.extinction_per_m, state.scatter_per_m, n=4000)
              for light in lights) * frame.lighting.exposure
    y_ref, y_gl = ref @ LUMA, shader @ LUMA
    lit = y_ref > 0.01 * y_ref.max()
    assert lit.mean() > 0.1  # the cones cover a good part of the frame …
    assert (~lit).mean() > 0.05  # … but not all of it (the headlight cone is clipped)
    rel = np.abs(y_gl[lit] - y_ref[lit]) / y_ref[lit]
    assert np.median(rel) < 0.04 and np.percentile(rel, 98) < 0.10
    assert np.abs(y_gl[~lit]).max() < 0.02 * y_ref.max()


def test_extinction_matches_physics_module():
    np.testing.assert_allclose(atm.rain_extinction_per_m([1.0, 8.0]) * 1e3,
                               physics.rain_extinction_per_km(np.array([1.0, 8.0])))


@pytest.mark.parametrize("hour", [12.0, 22.0])
def test_extreme_rain_and_fog_stay_finite(gl_ctx, shaders, hour):
    world = _world([_box((0.0, 5.0, 560.0), (20.0, 10.0, 2.0), (0.3, 0.3, 0.3))],
                   [StreetLamp(np.array([0.0, 7.0, 590.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3))])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 4.0, 500.0), fov_y_deg=60.0)
    settings = Settings()
    settings.atmosphere.haze_per_km = 60.0
    settings.atmosphere.glow = 4.0
    settings.atmosphere.light_scattering = 4.0
    settings.atmosphere.glow_resolution = 0.0625
    r = _renderer(gl_ctx, shaders, world, (64, 36))
    r.render(_frame(camera, world, settings, physics.R_MAX_MM_H, hour))
    img = r.hdr_image()
    assert np.all(np.isfinite(img)) and img.min() >= 0.0
    _release(r)
