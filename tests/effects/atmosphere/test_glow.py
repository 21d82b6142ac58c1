"""Atmosphere glow (issue 9): the post pass against its NumPy reference, and the halo growing with the rain."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.effects import atmosphere as atm
from rain_core.mesh import MAT_EMISSIVE
from rain_core.settings import Settings

LUMA = np.array([0.2126, 0.7152, 0.0722])


def _glow_scene(gl_ctx, shaders, kit, rate, glow, resolution=1.0):
    """A small bright emissive patch 30 m ahead of a dark wall at 60 m, at night: returns (before, after,
    weight w, σ px, k) with colours bottom row first."""
    size = (128, 72)
    world = kit.world([kit.box((0.0, 1.5, 540.0), (60.0, 40.0, 1.0), (0.05, 0.05, 0.05)),
                       kit.box((0.0, 1.5, 570.0), (0.4, 0.4, 0.4), (2.0, 2.0, 2.0), MAT_EMISSIVE)])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 1.5, 500.0), fov_y_deg=40.0)
    out = []
    for g in (0.0, glow):
        settings = Settings()
        settings.atmosphere.glow = g
        settings.atmosphere.glow_resolution = resolution
        settings.atmosphere.light_scattering = 0.0
        r = kit.renderer(gl_ctx, shaders, world, size)
        frame = kit.frame(camera, world, settings, rate, 22.0)
        r.render(frame)
        color, depth = kit.bottom_first(r)
        effect = r.effects[0]
        rc = r.render_context(frame)
        dist, dirs = atm.pixel_distances(depth, rc.view_proj, rc.camera_position)
        w = 1.0 - np.exp(-effect.state.medium_per_m * dist)
        out.append((color, w, effect.glow_sigma_px, effect.state.glow_strength))
        kit.release(r)
    (before, w, sigma, _), (after, _, _, k) = out
    return before, after, w, sigma, k


def test_glow_matches_the_numpy_reference_and_only_moves_light(gl_ctx, shaders, kit):
    before, after, w, sigma, k = _glow_scene(gl_ctx, shaders, kit, 30.0, 2.0)
    reference = atm.glow_reference(before, w, k, sigma)
    halo = (reference - before) @ LUMA
    err = (after - reference) @ LUMA
    assert np.abs(halo).max() > 0.05  # the halo is there
    assert np.abs(err).max() < 0.02 * np.abs(halo).max()
    assert (after @ LUMA).sum() == pytest.approx((before @ LUMA).sum(), rel=0.01)


def test_strong_glow_in_dense_rain_is_never_negative(gl_ctx, shaders, kit):
    """Glow 4× (k = 2) in 500 mm/h rain: k·w passes 1, where hdr·(1 − k·w) once went negative (issue 18)."""
    before, after, w, sigma, k = _glow_scene(gl_ctx, shaders, kit, 500.0, 4.0)
    assert k * w.max() > 1.0  # the cap is in play
    assert np.isfinite(after).all() and after.min() >= 0.0
    reference = atm.glow_reference(before, w, k, sigma)
    assert reference.min() >= 0.0
    halo = (reference - before) @ LUMA
    assert np.abs((after - reference) @ LUMA).max() < 0.02 * np.abs(halo).max()


def test_glow_reference_keeps_a_uniform_region_at_any_strength():
    color = np.full((9, 9, 3), 2.0)
    for k, w in ((0.5, 0.3), (2.0, 0.9), (2.0, 1.0)):
        out = atm.glow_reference(color, np.full((9, 9), w), k, 1.5)
        np.testing.assert_allclose(out, color, rtol=1e-12)


def test_halo_grows_in_size_and_strength_with_the_rain(gl_ctx, shaders, kit):
    profiles = {}
    for rate in (3.0, 50.0):
        before, after, _, sigma, _ = _glow_scene(gl_ctx, shaders, kit, rate, 1.0, resolution=0.25)
        halo = (after - before) @ LUMA
        cy, cx = np.unravel_index(np.argmax(before @ LUMA), halo.shape)
        profiles[rate] = (halo[cy, cx + 6], halo[cy, cx + 12], sigma)
    assert atm.glow_sigma_rad(atm.medium_extinction_per_m(50.0)) > 2 * atm.glow_sigma_rad(
        atm.medium_extinction_per_m(3.0))
    assert profiles[50.0][0] > 3 * profiles[3.0][0] > 0
    assert profiles[50.0][1] > 10 * max(profiles[3.0][1], 1e-6)
