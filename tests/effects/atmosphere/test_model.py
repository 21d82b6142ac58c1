"""Atmosphere model (issue 9): extinction from the rain, contrast law, rain-grey, airlight and phase function.
NumPy only."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.atmosphere import model as atm
from rain_core.lighting import lighting_for_hour
from rain_core.settings import AtmosphereSection

LUMA = np.array([0.2126, 0.7152, 0.0722])


def test_extinction_follows_weber_and_visibility_is_the_5_percent_distance():
    rates = np.array([0.5, 2.0, 10.0, 50.0])
    beta = np.array([atm.extinction_per_m(r) for r in rates])
    np.testing.assert_allclose(beta - atm.CLEAR_AIR_EXTINCTION_PER_M, 0.312e-3 * rates**0.67, rtol=1e-12)
    assert atm.extinction_per_m(10.0, fog_scale=2.0, haze_per_km=3.0) == pytest.approx(
        atm.CLEAR_AIR_EXTINCTION_PER_M + 2 * 0.312e-3 * 10**0.67 + 3e-3)
    vis = atm.visibility_m(beta)
    np.testing.assert_allclose(atm.transmittance(beta, vis), 0.05, rtol=1e-12)
    assert np.all(np.diff(vis) < 0)
    # 10 mm/h: β ≈ 1.56 /km → about 1.9 km of visibility.
    assert 1800 < atm.visibility_m(atm.extinction_per_m(10.0)) < 2000


def test_clear_air_is_the_renderers():
    from rain_core.gfx.renderer import CLEAR_AIR_EXTINCTION_PER_M

    assert atm.CLEAR_AIR_EXTINCTION_PER_M == CLEAR_AIR_EXTINCTION_PER_M


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


def test_extinction_matches_physics_module():
    np.testing.assert_allclose(atm.rain_extinction_per_m([1.0, 8.0]) * 1e3,
                               physics.rain_extinction_per_km(np.array([1.0, 8.0])))


def test_model_imports_without_gl():
    """The model and the NumPy references run where moderngl is absent."""
    import subprocess
    import sys

    code = ("import sys\n"
            "class Block:\n"
            "    def find_spec(self, name, path=None, target=None):\n"
            "        if name.split('.')[0] == 'moderngl': raise ImportError('moderngl blocked')\n"
            "sys.meta_path.insert(0, Block())\n"
            "from rain_core.effects.atmosphere import glow, model, scattering, sky_overcast\n"
            "from rain_core.settings import AtmosphereSection\n"
            "assert model.extinction_per_m(10.0) > 0 and glow.blur_radius(2.0) == 6\n"
            "assert sky_overcast(AtmosphereSection(), 2.0) > 0\n"
            "assert 'moderngl' not in sys.modules\n")
    subprocess.run([sys.executable, "-c", code], check=True)
