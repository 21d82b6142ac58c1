"""The water on the road (rain_core.water_film): depth of the film and standing water, puddle coverage and soft
margins, the NumPy ↔ GLSL parity of the constants and of the film depth (shaders/road/film.glsl)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rain_core import layout, water_film
from rain_core.effects import road
from rain_core.effects.road import RoadEffect
from rain_core.paths import SHADERS_DIR


@pytest.fixture(scope="module")
def world():
    return water_film.default_world()


def _glsl_consts(*names) -> dict[str, str]:
    text = "".join((SHADERS_DIR / n).read_text() for n in names)
    return dict(re.findall(r"const\s+\w+(?:\[\d+\])?\s+(\w+)(?:\[\d+\])?\s*=\s*([^;]+);", text))


def _numbers(expr: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+\.\d+", expr)]  # the literals (vec3, float[10] aside)


def test_glsl_constants_match_numpy():
    consts = _glsl_consts("road/film.glsl", "road/surface.glsl")
    for name in ("WET_FILM_MM", "CRACK_MAX_MM", "CRACK_DEPTH_SPAN", "PUDDLE_MAX_MM", "PUDDLE_NOISE_WEIGHT",
                 "PUDDLE_DEPTH_SPAN", "MACROTEXTURE_MM", "WET_ALBEDO_FACTOR", "WET_SMOOTHNESS_GAIN", "WATER_F0",
                 "UNDERWATER_F0", "FILM_ROUGHNESS", "WATER_ROUGHNESS", "LIGHT_MIN_ROUGHNESS",
                 "LIGHT_SOURCE_RADIANCE", "MIRROR_LENS_FACTOR", "WET_MIN"):
        model = water_film if hasattr(water_film, name) else road
        assert float(consts[name]) == pytest.approx(getattr(model, name)), name
    assert float(consts["ROAD_HALF_WIDTH_M"]) == layout.ROAD_HALF_WIDTH_M
    assert float(consts["ROAD_PERIOD_M"]) == layout.PERIOD_M
    assert _numbers(consts["MURK_TINT"]) == pytest.approx(road.MURK_TINT)
    ids = sorted(road.MATERIAL_POROSITY)
    assert _numbers(consts["ROAD_POROSITY"]) == pytest.approx([road.MATERIAL_POROSITY[i] for i in ids])
    assert _numbers(consts["ROAD_FILM"]) == pytest.approx([road.MATERIAL_FILM[i] for i in ids])
    assert _numbers(consts["ROAD_REGION_COLORS"]) == pytest.approx(np.ravel(road.REGION_COLORS))


def test_film_depth_is_shallow_on_road_only_and_periodic(world):
    rng = np.random.default_rng(1)
    x = rng.uniform(-9.0, 9.0, 20000)
    z = rng.uniform(0.0, layout.PERIOD_M, 20000)
    d = water_film.film_depth_mm(x, z, 1.0, 1.0, 1.0, world=world, wetness=1.0)
    assert d.shape == x.shape and np.isfinite(d).all()
    assert d.min() >= 0.0 and d.max() <= water_film.PUDDLE_MAX_MM
    assert d.max() > 0.8 * water_film.PUDDLE_MAX_MM  # full puddles are up to ~10 mm deep
    assert (d[np.abs(x) > layout.ROAD_HALF_WIDTH_M] == 0).all()
    np.testing.assert_allclose(water_film.film_depth_mm(x, z + 3 * layout.PERIOD_M, 1.0, 1.0, 1.0, world=world,
                                                  wetness=1.0), d, atol=1e-9)
    assert (water_film.film_depth_mm(x, z, 0.0, 0.0, 1.0, world=world) == 0).all()
    # Under the railway bridge and the fuel-station canopy the rain does not reach the road.
    under = water_film.film_depth_mm(np.linspace(-6.5, 6.5, 50), layout.BRIDGE_Z_M, 1.0, 1.0, 1.0, world=world,
                               wetness=1.0)
    assert (under == 0).all()
    assert (water_film.film_depth_mm(5.0, layout.CANOPY_Z_M, 1.0, 1.0, 1.0, world=world, wetness=1.0) == 0).all()
    other_seed = water_film.film_depth_mm(x, z, 1.0, 1.0, 0.5, seed=7, world=world)
    assert np.abs(other_seed - water_film.film_depth_mm(x, z, 1.0, 1.0, 0.5, world=world)).max() > 1.0
    with pytest.raises(ValueError, match="puddles"):
        water_film.film_depth_mm(0.0, 0.0, 0.5, 1.5)


def _road_grid(step=0.05, z0=520.0, length=120.0):
    x = np.arange(-layout.ROAD_HALF_WIDTH_M, layout.ROAD_HALF_WIDTH_M, step) + step / 2
    z = np.arange(z0, z0 + length, step) + step / 2
    return np.meshgrid(x, z)


def test_puddle_coverage_grows_with_the_flood_level_and_has_soft_margins(world):
    x, z = _road_grid()
    levels = np.linspace(0.0, 1.0, 11)
    puddle, any_water = [], []
    for p in levels:
        standing, _ = water_film.water_depths_mm(x, z, 0.0, p, 0.5, world=world)
        cover = road.water_coverage(standing)
        puddle.append((cover >= 1).mean())
        any_water.append((cover > 0).mean())
        if p >= 0.5:
            # Soft margins: every puddle is ringed by drenched ground, not a hard edge.
            margin = (cover > 0) & (cover < 1)
            assert margin.mean() > 0.5 * (cover >= 1).mean()
            full = cover >= 1
            hard = (full[:, 1:] & (cover[:, :-1] == 0)) | (full[:, :-1] & (cover[:, 1:] == 0))
            edges = (full[:, 1:] != full[:, :-1])
            assert hard.sum() < 0.2 * edges.sum()
    assert puddle[0] == any_water[0] == 0.0
    assert all(b > a for a, b in zip(any_water[1:], any_water[2:], strict=False))
    assert all(b >= a for a, b in zip(puddle, puddle[1:], strict=False)) and puddle[-1] > 0.05
    # Cracks fill first and only the cracks: at the crack level alone little of the road is under water.
    standing, _ = water_film.water_depths_mm(x, z, 1.0, 0.0, 0.5, world=world)
    assert 0.0 < (standing > 0).mean() < 0.05
    # The four regions all occur at a moderate state.
    regions = road.road_regions(x, z, 0.8, 0.8, 0.8, 0.5, world=world)
    assert set(np.unique(regions)) >= {1, 2, 3}
    assert (road.road_regions(x, z, 0.0, 0.0, 0.0, world=world) == 0).all()


def test_film_depth_glsl_matches_numpy(gl_ctx, shaders, world):
    effect = RoadEffect(gl_ctx, shaders=shaders)
    effect.set_world(world)
    rng = np.random.default_rng(2)
    x = rng.uniform(-7.5, 7.5, 6000)
    z = np.concatenate([rng.uniform(0.0, 2 * layout.PERIOD_M, 5000), rng.uniform(290.0, 310.0, 1000)])
    for cracks, puddles, amount, seed, wet in ((0.7, 0.8, 0.6, 3, 0.5), (1.0, 1.0, 1.0, 0, 1.0)):
        gpu = effect.film_depth_gpu(x, z, cracks, puddles, amount, seed, wet)
        standing, film = water_film.water_depths_mm(x, z, cracks, puddles, amount, seed, world, wet)
        assert (standing > 0).mean() > 0.1
        # GPUs quantise bilinear weights (to 1/256 on many): a few hundredths of a mm at crack edges.
        np.testing.assert_allclose(gpu[..., 0], standing, atol=0.05)
        np.testing.assert_allclose(gpu[..., 1], film, atol=1e-3)
    effect.release()


def test_the_frames_film_function_is_film_depth_mm_bit_for_bit(gl_ctx):
    """rc.shared.film_depth_fn (what the ripples ask every frame) samples through a film_depth_sampler kept while
    the levels stay: the same values, bit for bit, as film_depth_mm with the frame's arguments, for arrays of any
    shape, broadcast scalars and off-road points; a change of level makes a new one."""
    from rain_core.bench.frame import heavy_rain_settings
    from rain_core.gfx.frame import SharedResources
    from rain_core.gutter import frame_spread_coefficient
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (32, 18), settings=heavy_rain_settings(10_000), seed=1)
    try:
        for _ in range(3):
            scene.step(1 / 30)
        effect = next(e for e in scene.effects if e.name == "road")
        rng = np.random.default_rng(4)
        for puddles in (1.0, 0.4):
            scene.weather.puddles = puddles
            frame = scene.frame()
            rc = scene.renderer.render_context(frame, shared=SharedResources())
            effect.update(frame, rc)
            fn = rc.shared.film_depth_fn
            _, cracks, level = effect.levels(frame)
            road_s = effect._road_settings(frame)
            args = (cracks, level, float(road_s.puddle_amount), int(road_s.puddle_seed), effect.world)
            k = frame_spread_coefficient(frame)
            for shape in ((5000,), (19, 512)):
                x, z = rng.uniform(-12.0, 12.0, shape), rng.uniform(-500.0, 3000.0, shape)
                got, want = fn(x, z), water_film.film_depth_mm(x, z, *args, gutter_k=k)
                assert got.shape == want.shape and np.array_equal(got, want)
                assert (want > 0).mean() > 0.05  # a real test: standing water among the points
            x = np.array([0.5, 3.0, 9.0])
            assert np.array_equal(fn(x, 100.0), water_film.film_depth_mm(x, 100.0, *args, gutter_k=k))
    finally:
        scene.release()
