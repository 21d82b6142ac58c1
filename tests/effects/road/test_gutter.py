"""Kerb streams: the HEC-22 gutter equation, the spread growing from one inlet to the next, the GLSL twin against
the NumPy model, and the water reaching what the road, the spray and the labels read."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import gutter, layout
from rain_core.water_film import film_depth_mm


def test_spread_satisfies_the_hec22_gutter_equation():
    rate = 50.0  # mm/h
    k = gutter.spread_coefficient(rate)
    for length in (5.0, 20.0, 50.0):
        spread = k * length**0.375
        inflow = gutter.RUNOFF_C * rate / 3.6e6 * gutter.DRAINED_WIDTH_M * length  # rational method, m³/s
        assert gutter.gutter_flow_m3_s(spread) == pytest.approx(inflow, rel=1e-9)


def test_speed_is_the_flow_over_the_wetted_area():
    spread = np.array([0.3, 1.0, 2.0])
    area = gutter.CROSS_SLOPE * spread**2 / 2.0
    np.testing.assert_allclose(gutter.gutter_speed_m_s(spread), gutter.gutter_flow_m3_s(spread) / area, rtol=2e-3)


def test_published_magnitudes():
    # 50 mm/h on a 2 % crown, 0.5 % grade, n = 0.016, 50 m to the inlet: a spread of a metre or two and a few
    # centimetres at the kerb, the range HEC-22's design examples work in (spread limits of 1.5–3 m).
    spread = gutter.spread_coefficient(50.0) * 50.0**0.375
    assert 0.8 < spread < 2.5
    depth_mm = gutter.gutter_depth_mm(layout.ROAD_HALF_WIDTH_M - 0.01, 24.9, gutter.spread_coefficient(50.0))
    assert 15.0 < float(depth_mm) < 50.0


def test_deepest_at_the_kerb_growing_to_the_inlet_and_none_when_dry():
    k = gutter.spread_coefficient(16.0)
    x = np.linspace(0.0, layout.ROAD_HALF_WIDTH_M, 200)
    across = gutter.gutter_depth_mm(x, np.full_like(x, 1.0), k)
    assert across[-1] > 0.0 and across[0] == 0.0 and np.all(np.diff(across) >= 0.0)
    z = np.linspace(0.1, 49.9, 200)  # the +x kerb's inlets sit at z = 0, 50, …; the flow runs towards −z
    along = gutter.gutter_depth_mm(np.full_like(z, 6.99), z, k)
    assert np.all(np.diff(along) <= 1e-12)  # deeper downstream (smaller z), reset past each inlet
    assert gutter.spread_coefficient(0.0) == 0.0 and gutter.spread_coefficient(16.0, wetness=0.0) == 0.0
    assert np.all(gutter.gutter_depth_mm(x, np.full_like(x, 1.0), 0.0) == 0.0)


def test_the_film_model_adds_the_stream():
    k = gutter.spread_coefficient(20.0)
    x = np.array([6.9, 6.9, 3.0])
    z = np.array([10.0, 10.0, 10.0])
    without = film_depth_mm(x, z, 0.0, 0.0, wetness=1.0)
    with_stream = film_depth_mm(x, z, 0.0, 0.0, wetness=1.0, gutter_k=k)
    assert with_stream[0] > 5.0 * without[0] and with_stream[2] == without[2]


def test_glsl_twin_matches(gl_ctx, shaders):
    from rain_core.effects.road import RoadEffect
    from rain_core.world import build_world

    effect = RoadEffect(gl_ctx, shaders=shaders)
    world = build_world(seed=1)
    effect.set_world(world)
    rng = np.random.default_rng(3)
    x = rng.uniform(3.0, 7.0, 2000) * rng.choice([-1.0, 1.0], 2000)
    z = rng.uniform(0.0, layout.PERIOD_M, 2000)
    k = gutter.spread_coefficient(30.0)
    try:
        gpu = effect.film_depth_gpu(x, z, 0.0, 0.0, 0.5, 0, 0.0, gutter_k=k)[..., 0]
    finally:
        effect.release()
    cpu = film_depth_mm(x, z, 0.0, 0.0, 0.5, 0, world, gutter_k=k)
    assert (cpu > 0).mean() > 0.2
    np.testing.assert_allclose(gpu, cpu, atol=0.05, rtol=1e-3)


def test_frame_coefficient_follows_the_settings():
    from types import SimpleNamespace

    from rain_core.settings import Settings

    s = Settings()
    weather = SimpleNamespace(rate_mm_h=10.0, wetness=1.0)
    frame = SimpleNamespace(weather=weather, settings=s)
    assert gutter.frame_spread_coefficient(frame) == pytest.approx(gutter.spread_coefficient(10.0))
    s.road.kerb_streams = False
    assert gutter.frame_spread_coefficient(frame) == 0.0
    assert math.isfinite(gutter.spread_coefficient(500.0))
