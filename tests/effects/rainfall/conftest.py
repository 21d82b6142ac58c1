"""Helpers shared by the rainfall tests, handed out as the ``rain`` fixture (tests are imported by path, so they
share code through fixtures), and the street ``world``."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rain_core.effects.rainfall import RainInput

FWD = np.array([0.0, -0.07, -1.0])


def _input(t, pos=(1.75, 1.2, 600.0), vel=(0.0, 0.0, 0.0), rate=8.0, wind=(0.0, 0.0, 0.0), **kw):
    return RainInput(time_s=t, camera_position=np.asarray(pos, float), camera_forward=kw.pop("forward", FWD),
                     camera_velocity=np.asarray(vel, float), rate_mm_h=rate, wind_m_s=np.asarray(wind, float), **kw)


def _drive(sim, seconds, speed=0.0, rate=8.0, wind=(0.0, 0.0, 0.0), t0=0.0, dt=1.0 / 30.0, **kw):
    """Advance a sim with the camera moving along −Z at speed (m/s); returns the last time."""
    t = t0
    for i in range(int(round(seconds / dt)) + 1):
        t = t0 + i * dt
        sim.advance(_input(t, pos=(1.75, 1.2, 600.0 - speed * t), vel=(0.0, 0.0, -speed), rate=rate, wind=wind,
                           **kw))
    return t


def _scene(gl_ctx, shaders, settings, size=(160, 90), seed=1):
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.scene import Scene

    effect = RainfallEffect(gl_ctx, shaders=shaders, settings=settings, seed=seed)
    return Scene(gl_ctx, size, settings, seed=1, effects=[effect], gpu_timing=False), effect


def _settings(rate=28.0, hour=12.0, mode="free", budget=6000, **rainfall):
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate
    s.time_of_day.hour = hour
    s.camera.mode = mode
    s.quality.particle_budget = budget
    s.traffic.count = 0
    for key, value in rainfall.items():
        setattr(s.rainfall, key, value)
    return s


def _rain_light(scene, camera, settings):
    """HDR difference between the frame with the rain and without it (the rainfall switched off)."""
    scene.render(camera)
    rain = scene.renderer.hdr_image()
    settings.rainfall.enabled = False
    scene.render(camera)
    dry = scene.renderer.hdr_image()
    settings.rainfall.enabled = True
    return np.abs(rain - dry).sum(axis=2)


@pytest.fixture
def rain():
    """``rain.input`` (a RainInput), ``rain.drive`` (advance a sim), ``rain.scene`` (a Scene with only the
    rainfall), ``rain.settings``, ``rain.light`` (the light the rain adds to a frame), ``rain.FWD``."""
    return SimpleNamespace(input=_input, drive=_drive, scene=_scene, settings=_settings, light=_rain_light, FWD=FWD)


@pytest.fixture(scope="module")
def world():
    from rain_core.world import build_world

    return build_world(seed=1)
