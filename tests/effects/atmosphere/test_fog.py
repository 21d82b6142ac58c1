"""Atmosphere effect (issue 9): when it runs, what it hands the renderer, the contrast law in rendered frames,
and the return to clear air."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import physics
from rain_core.camera import look_at
from rain_core.effects import atmosphere as atm
from rain_core.gfx import frame_block
from rain_core.gfx.renderer import clear_air_uniforms
from rain_core.lighting import lighting_for_hour
from rain_core.settings import AtmosphereSection, Settings
from rain_core.world import StreetLamp

LUMA = np.array([0.2126, 0.7152, 0.0722])


def test_active_only_with_rain_or_haze(gl_ctx):
    eff = atm.AtmosphereEffect(gl_ctx)

    def frame(rate, **kw):
        return SimpleNamespace(rain_rate_mm_h=rate, settings=Settings(atmosphere=AtmosphereSection(**kw)))

    assert not eff.active(frame(0.0))
    assert eff.active(frame(0.1))
    assert eff.active(frame(0.0, haze_per_km=2.0))
    assert not eff.active(frame(10.0, enabled=False))
    assert not eff.active(frame(10.0, fog_scale=0.0))
    eff.release()


def test_frame_uniforms_are_the_model_over_the_clear_air(gl_ctx):
    """The effect hands the renderer the frame's medium (and changes nothing doing so); the clear air's keys are
    all overridden, so nothing of the clear air leaks into a rainy frame."""
    eff = atm.AtmosphereEffect(gl_ctx)
    lighting = lighting_for_hour(12.0, 0.5)
    frame = SimpleNamespace(rain_rate_mm_h=10.0, settings=Settings(), lighting=lighting,
                            world=SimpleNamespace(lamps=[]))
    state = atm.atmosphere_state(frame.settings.atmosphere, 10.0, lighting)
    values = eff.frame_uniforms(frame)
    assert eff.state is None  # pure: the state is the update's
    assert set(clear_air_uniforms(lighting)) <= set(values)
    assert values["u_extinction_per_m"] == state.extinction_per_m == atm.extinction_per_m(10.0)
    assert values["u_medium_extinction_per_m"] == state.medium_per_m
    np.testing.assert_array_equal(values["u_airlight"], state.airlight)
    np.testing.assert_array_equal(values["u_airlight_sun"], state.airlight_sun)
    np.testing.assert_array_equal(values["u_airlight_sun_dir"], state.sun_direction)
    assert (values["u_phase_g"], values["u_phase_back_g"], values["u_phase_back_weight"]) == (
        atm.PHASE_G, atm.PHASE_BACK_G, atm.PHASE_BACK_WEIGHT)
    eff.release()


@pytest.mark.parametrize("rate", [2.0, 10.0, 30.0])
def test_contrast_of_a_dark_building_falls_as_exp_minus_beta_d(gl_ctx, shaders, kit, rate):
    """(L_obj − L_sky)/L_sky of a dark box against the horizon, from the HDR frame, vs C0·exp(−β·d)."""
    size = (160, 90)
    settings = Settings()
    settings.atmosphere.light_scattering = 0.0
    beta = atm.extinction_per_m(rate)
    eye = np.array([0.0, 10.0, 600.0])
    camera = look_at(eye, eye + np.array([0.0, 0.0, -1.0]), fov_y_deg=30.0, far_m=5000.0)
    for d in (150.0, 500.0, 1000.0):  # < one 1200 m tile: the box's periodic copies stay hidden
        # A 1 m thick slab whose face towards the eye is d metres away.
        world = kit.world([kit.box(eye - np.array([0.0, 0.0, d + 0.5]), (0.25 * d, 0.25 * d, 1.0),
                                   (0.03, 0.03, 0.03))])
        frame = kit.frame(camera, world, settings, rate, 12.0)
        fogged = kit.renderer(gl_ctx, shaders, world, size)
        fogged.render(frame)
        img = fogged.hdr_image() @ LUMA
        plain = kit.renderer(gl_ctx, shaders, world, size, effect=None)  # no atmosphere at all: the box's own L0
        plain.render(frame)
        l0 = np.median((plain.hdr_image() @ LUMA)[43:48, 78:83])
        l_obj = np.median(img[43:48, 78:83])
        l_sky = np.median(np.concatenate([img[43:48, 38:41], img[43:48, 120:123]]))
        contrast = (l_obj - l_sky) / l_sky
        expected = (l0 - l_sky) / l_sky * math.exp(-beta * d)
        assert contrast == pytest.approx(expected, rel=0.10), (rate, d, contrast, expected)
        kit.release(fogged, plain)


def test_no_rain_no_haze_skips_the_pass_and_a_rate_drop_returns_to_clear_air(gl_ctx, shaders, kit):
    size = (96, 54)
    world = kit.world([kit.box((0.0, 5.0, 500.0), (20.0, 10.0, 20.0), (0.3, 0.3, 0.3))],
                      [StreetLamp(np.array([0.0, 7.0, 560.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3))])
    camera = look_at((3.0, 1.5, 600.0), (0.0, 4.0, 500.0), fov_y_deg=60.0)
    settings = Settings()
    plain = kit.renderer(gl_ctx, shaders, world, size, effect=False)
    plain.render(kit.frame(camera, world, settings, 0.0, 22.0))
    clear = plain.hdr_image()
    r = kit.renderer(gl_ctx, shaders, world, size)
    r.render(kit.frame(camera, world, settings, 0.0, 22.0))
    assert [(s.name, s.ran) for s in r.stats if s.name.startswith("atmosphere")] == [("atmosphere", False)]
    np.testing.assert_array_equal(r.hdr_image(), clear)
    r.render(kit.frame(camera, world, settings, 20.0, 22.0))
    ran = {s.name for s in r.stats if s.ran}
    assert {"atmosphere.update", "atmosphere.post"} <= ran
    rainy = r.hdr_image()
    assert np.all(np.isfinite(rainy)) and np.abs(rainy - clear).max() > 0.01
    frame = kit.frame(camera, world, settings, 0.0, 22.0)
    r.render(frame)
    np.testing.assert_array_equal(r.hdr_image(), clear)
    # The frame block every program reads is back at the clear air, and the idle effect holds no medium.
    assert r.effects[0].state is None
    values = frame_block.unpack(r.frame_blocks.read_bound())
    for name, value in clear_air_uniforms(frame.lighting).items():
        np.testing.assert_allclose(values[name], value, rtol=1e-6)
    kit.release(r, plain)


@pytest.mark.parametrize("hour", [12.0, 22.0])
def test_extreme_rain_and_fog_stay_finite(gl_ctx, shaders, kit, hour):
    world = kit.world([kit.box((0.0, 5.0, 560.0), (20.0, 10.0, 2.0), (0.3, 0.3, 0.3))],
                      [StreetLamp(np.array([0.0, 7.0, 590.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3))])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 4.0, 500.0), fov_y_deg=60.0)
    settings = Settings()
    settings.atmosphere.haze_per_km = 60.0
    settings.atmosphere.glow = 4.0
    settings.atmosphere.light_scattering = 4.0
    settings.atmosphere.glow_resolution = 0.0625
    r = kit.renderer(gl_ctx, shaders, world, (64, 36))
    r.render(kit.frame(camera, world, settings, physics.R_MAX_MM_H, hour))
    img = r.hdr_image()
    assert np.all(np.isfinite(img)) and img.min() >= 0.0
    kit.release(r)
