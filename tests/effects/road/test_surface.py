"""The wet road surface (rain_core.effects.road.surface): the wet material per material, the wind waves, and the
wet asphalt's BRDF calibrated against measurements (rendered)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import layout, water_film
from rain_core.camera import look_at
from rain_core.effects import road
from rain_core.gfx.frame import Frame
from rain_core.gfx.renderer import Renderer
from rain_core.lighting import Lighting
from rain_core.mesh import MAT_ASPHALT, MAT_CONCRETE, MAT_METAL, MAT_PAINT
from rain_core.settings import Settings, set_value
from rain_core.weather import WeatherState
from rain_core.world import _rects_up


@pytest.fixture(scope="module")
def world():
    return water_film.default_world()


def test_wet_material_follows_lagarde_per_material():
    alb, rough = road.wet_material((0.2, 0.2, 0.2), 0.9, 0.0, MAT_ASPHALT)
    np.testing.assert_allclose(alb, 0.2)
    assert rough == pytest.approx(0.9)
    alb, rough = road.wet_material((0.2, 0.2, 0.2), 0.9, 1.0, MAT_ASPHALT)
    np.testing.assert_allclose(alb, 0.2 * 0.3)  # porous asphalt: ×0.3
    assert 1 - rough == pytest.approx(0.1 * 2.5)  # smoothness ×2.5
    _, rough = road.wet_material(0.5, 0.5, 1.0, MAT_ASPHALT)
    assert rough == pytest.approx(0.02)  # smoothness capped at 1 (and the shader's roughness floor)
    paint, _ = road.wet_material(0.6, 0.6, 1.0, MAT_PAINT)
    concrete, _ = road.wet_material(0.6, 0.6, 1.0, MAT_CONCRETE)
    metal, _ = road.wet_material(0.6, 0.6, 1.0, MAT_METAL)
    assert 0.6 * 0.3 < concrete < paint < metal == pytest.approx(0.6)


def test_wind_waves_follow_the_wind():
    calm = road.wave_parameters((0.0, 0.0, 0.0), 1.0)
    breeze = road.wave_parameters((3.0, 0.0, 0.0), 1.0)
    gale = road.wave_parameters((0.0, 0.0, -30.0), 1.0)
    assert 0.0 < calm[2] < breeze[2] < gale[2] == pytest.approx(road.WAVE_SLOPE_MAX)
    assert breeze[0] > 0 and breeze[1] == 0.0  # ripples drift with the wind
    assert gale[1] < 0 and math.hypot(gale[0], gale[1]) <= 0.35  # never faster than capillary waves
    assert road.wave_parameters((5.0, 0.0, 5.0), 0.0)[2] == 0.0


def _flat_world():
    """A big flat asphalt patch, nothing else: the BRDF calibration scene."""
    verts = _rects_up(-7.0, 7.0, 0.0, layout.PERIOD_M, 0.0, (0.075, 0.075, 0.078), 0.9, MAT_ASPHALT)
    return SimpleNamespace(vertices=verts, lamps=[])


def _sun_only(direction) -> Lighting:
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    return Lighting(12.0, d, np.full(3, 1.0e4), np.zeros(3), np.zeros(3), 0.0, 0.0, math.log2(1e4 / 2.5))


def _calibration_radiance(gl_ctx, shaders, world, wetness, sun_deg, view_deg) -> float:
    """Mean pre-exposure luminance of a patch lit by the sun from sun_deg (from the normal, −x side) and seen
    from view_deg (+x side), with a narrow lens far away so the geometry is the same over the patch."""
    settings = Settings()
    set_value(settings, "road.reflections", False)
    effect = road.RoadEffect(gl_ctx, settings, shaders=shaders)
    effect.set_world(world)  # the default street's road: the renderer's world is a bare patch
    renderer = Renderer(gl_ctx, (32, 32), _flat_world(), effects=[effect], shaders=shaders, gpu_timing=False)
    sun = (-math.sin(math.radians(sun_deg)), math.cos(math.radians(sun_deg)), 0.0)
    target = np.array([0.0, 0.0, 600.0])
    eye = target + 40.0 * np.array([math.sin(math.radians(view_deg)), math.cos(math.radians(view_deg)), 0.0])
    lighting = _sun_only(sun)
    frame = Frame(0.0, 0.0, look_at(eye, target, fov_y_deg=1.0), lighting, renderer.world,
                  weather=WeatherState(wetness=wetness), settings=settings)
    renderer.render(frame)
    hdr = renderer.hdr_image()
    renderer.release()
    effect.release()
    gl_ctx.detect_framebuffer(0).use()  # not the released frame's framebuffer
    return float(hdr[8:24, 8:24].mean() / lighting.exposure)


def test_wet_asphalt_darker_diffuse_brighter_specular_in_calibrated_range(gl_ctx, shaders, world):
    # Nakamae et al. 1990: wet diffuse ×0.1–0.3, specular ×5–10 (near normal incidence).
    dry_d = _calibration_radiance(gl_ctx, shaders, world, 0.0, 0.0, 60.0)
    wet_d = _calibration_radiance(gl_ctx, shaders, world, 1.0, 0.0, 60.0)
    dry_s = _calibration_radiance(gl_ctx, shaders, world, 0.0, 30.0, 30.0)
    wet_s = _calibration_radiance(gl_ctx, shaders, world, 1.0, 30.0, 30.0)
    assert dry_d > 0 and dry_s > 0
    assert 0.1 <= wet_d / dry_d <= 0.3
    assert 5.0 <= wet_s / dry_s <= 10.0
    half = _calibration_radiance(gl_ctx, shaders, world, 0.5, 30.0, 30.0)
    assert dry_s < half < wet_s
