"""The wet road (issue 4): wet BRDF calibration, water in cracks and puddles, film-depth parity NumPy ↔ GLSL,
planar reflections against an independent mirror camera, the dry path, the debug regions, extreme settings."""

from __future__ import annotations

import dataclasses
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core import layout, road
from rain_core.camera import Camera, look_at
from rain_core.gl import float_target
from rain_core.lighting import Lighting
from rain_core.mesh import MAT_ASPHALT, MAT_CONCRETE, MAT_METAL, MAT_PAINT
from rain_core.paths import SHADERS_DIR
from rain_core.renderer import Frame, Renderer
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value
from rain_core.weather import WeatherState
from rain_core.world import _rects_up

SIZE = (160, 90)


@pytest.fixture(scope="module")
def world():
    return road._default_world()


# --- NumPy model ---------------------------------------------------------------------------------------------

def _glsl_consts(*names) -> dict[str, str]:
    text = "".join((SHADERS_DIR / "common" / n).read_text() for n in names)
    return dict(re.findall(r"const\s+\w+(?:\[\d+\])?\s+(\w+)(?:\[\d+\])?\s*=\s*([^;]+);", text))


def _numbers(expr: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+\.\d+", expr)]  # the literals (vec3, float[10] aside)


def test_glsl_constants_match_numpy():
    consts = _glsl_consts("road/film.glsl", "road/surface.glsl")
    for name in ("WET_FILM_MM", "CRACK_MAX_MM", "CRACK_DEPTH_SPAN", "PUDDLE_MAX_MM", "PUDDLE_NOISE_WEIGHT",
                 "PUDDLE_DEPTH_SPAN", "MACROTEXTURE_MM", "WET_ALBEDO_FACTOR", "WET_SMOOTHNESS_GAIN", "WATER_F0",
                 "UNDERWATER_F0", "FILM_ROUGHNESS", "WATER_ROUGHNESS", "LIGHT_MIN_ROUGHNESS",
                 "LIGHT_SOURCE_RADIANCE", "MIRROR_LENS_FACTOR", "WET_MIN"):
        assert float(consts[name]) == pytest.approx(getattr(road, name)), name
    assert float(consts["ROAD_HALF_WIDTH_M"]) == layout.ROAD_HALF_WIDTH_M
    assert float(consts["ROAD_PERIOD_M"]) == layout.PERIOD_M
    assert _numbers(consts["MURK_TINT"]) == pytest.approx(road.MURK_TINT)
    ids = sorted(road.MATERIAL_POROSITY)
    assert _numbers(consts["ROAD_POROSITY"]) == pytest.approx([road.MATERIAL_POROSITY[i] for i in ids])
    assert _numbers(consts["ROAD_FILM"]) == pytest.approx([road.MATERIAL_FILM[i] for i in ids])
    assert _numbers(consts["ROAD_REGION_COLORS"]) == pytest.approx(np.ravel(road.REGION_COLORS))


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


def test_film_depth_is_shallow_on_road_only_and_periodic(world):
    rng = np.random.default_rng(1)
    x = rng.uniform(-9.0, 9.0, 20000)
    z = rng.uniform(0.0, layout.PERIOD_M, 20000)
    d = road.film_depth_mm(x, z, 1.0, 1.0, 1.0, world=world, wetness=1.0)
    assert d.shape == x.shape and np.isfinite(d).all()
    assert d.min() >= 0.0 and d.max() <= road.PUDDLE_MAX_MM
    assert d.max() > 0.8 * road.PUDDLE_MAX_MM  # full puddles are up to ~10 mm deep
    assert (d[np.abs(x) > layout.ROAD_HALF_WIDTH_M] == 0).all()
    np.testing.assert_allclose(road.film_depth_mm(x, z + 3 * layout.PERIOD_M, 1.0, 1.0, 1.0, world=world,
                                                  wetness=1.0), d, atol=1e-9)
    assert (road.film_depth_mm(x, z, 0.0, 0.0, 1.0, world=world) == 0).all()
    # Under the railway bridge and the fuel-station canopy the rain does not reach the road.
    under = road.film_depth_mm(np.linspace(-6.5, 6.5, 50), layout.BRIDGE_Z_M, 1.0, 1.0, 1.0, world=world,
                               wetness=1.0)
    assert (under == 0).all()
    assert (road.film_depth_mm(5.0, layout.CANOPY_Z_M, 1.0, 1.0, 1.0, world=world, wetness=1.0) == 0).all()
    other_seed = road.film_depth_mm(x, z, 1.0, 1.0, 0.5, seed=7, world=world)
    assert np.abs(other_seed - road.film_depth_mm(x, z, 1.0, 1.0, 0.5, world=world)).max() > 1.0
    with pytest.raises(ValueError, match="puddles"):
        road.film_depth_mm(0.0, 0.0, 0.5, 1.5)


def _road_grid(step=0.05, z0=520.0, length=120.0):
    x = np.arange(-layout.ROAD_HALF_WIDTH_M, layout.ROAD_HALF_WIDTH_M, step) + step / 2
    z = np.arange(z0, z0 + length, step) + step / 2
    return np.meshgrid(x, z)


def test_puddle_coverage_grows_with_the_flood_level_and_has_soft_margins(world):
    x, z = _road_grid()
    levels = np.linspace(0.0, 1.0, 11)
    puddle, any_water = [], []
    for p in levels:
        standing, _ = road.water_depths_mm(x, z, 0.0, p, 0.5, world=world)
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
    standing, _ = road.water_depths_mm(x, z, 1.0, 0.0, 0.5, world=world)
    assert 0.0 < (standing > 0).mean() < 0.05
    # The four regions all occur at a moderate state.
    regions = road.road_regions(x, z, 0.8, 0.8, 0.8, 0.5, world=world)
    assert set(np.unique(regions)) >= {1, 2, 3}
    assert (road.road_regions(x, z, 0.0, 0.0, 0.0, world=world) == 0).all()


def test_wind_waves_follow_the_wind():
    calm = road.wave_parameters((0.0, 0.0, 0.0), 1.0)
    breeze = road.wave_parameters((3.0, 0.0, 0.0), 1.0)
    gale = road.wave_parameters((0.0, 0.0, -30.0), 1.0)
    assert 0.0 < calm[2] < breeze[2] < gale[2] == pytest.approx(road.WAVE_SLOPE_MAX)
    assert breeze[0] > 0 and breeze[1] == 0.0  # ripples drift with the wind
    assert gale[1] < 0 and math.hypot(gale[0], gale[1]) <= 0.35  # never faster than capillary waves
    assert road.wave_parameters((5.0, 0.0, 5.0), 0.0)[2] == 0.0


# --- GPU ------------------------------------------------------------------------------------------------------

def test_film_depth_glsl_matches_numpy(gl_ctx, shaders, world):
    effect = road.RoadEffect(gl_ctx, shaders, world)
    rng = np.random.default_rng(2)
    x = rng.uniform(-7.5, 7.5, 6000)
    z = np.concatenate([rng.uniform(0.0, 2 * layout.PERIOD_M, 5000), rng.uniform(290.0, 310.0, 1000)])
    for cracks, puddles, amount, seed, wet in ((0.7, 0.8, 0.6, 3, 0.5), (1.0, 1.0, 1.0, 0, 1.0)):
        gpu = effect.film_depth_gpu(x, z, cracks, puddles, amount, seed, wet)
        standing, film = road.water_depths_mm(x, z, cracks, puddles, amount, seed, world, wet)
        assert (standing > 0).mean() > 0.1
        # GPUs quantise bilinear weights (to 1/256 on many): a few hundredths of a mm at crack edges.
        np.testing.assert_allclose(gpu[..., 0], standing, atol=0.05)
        np.testing.assert_allclose(gpu[..., 1], film, atol=1e-3)
    effect.release()


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
    effect = road.RoadEffect(gl_ctx, shaders, world, settings)
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


def _settings(hour=12.0, camera="driver", wetness=1.0, cracks=0.0, puddles=0.0, **road_values) -> Settings:
    s = Settings()
    set_value(s, "time_of_day.hour", hour)
    set_value(s, "camera.mode", camera)
    set_value(s, "traffic.count", 2)
    for name, value in (("wetness", wetness), ("cracks", cracks), ("puddles", puddles)):
        set_value(s, f"rain.{name}", value)
    for key, value in road_values.items():
        set_value(s, f"road.{key}", value)
    return s


@pytest.fixture(scope="module")
def wet_scene(gl_ctx, shaders, world):
    with gl_ctx:  # module fixtures run outside conftest's per-test _gl_current
        settings = _settings()
        effect = road.make_road(gl_ctx, settings)  # takes the scene's world from the first frame
        scene = Scene(gl_ctx, SIZE, settings, seed=1, effects=[effect], gpu_timing=False)
        for _ in range(20):
            scene.step(1 / 30)
    yield scene, effect
    with gl_ctx:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()  # not the released frame's framebuffer


def _apply(scene, settings):
    scene.settings = settings
    scene.step(0.0)  # takes the pins into the weather without moving anything


def test_dry_road_takes_the_dry_path(gl_ctx, wet_scene):
    scene, effect = wet_scene
    _apply(scene, _settings(wetness=0.0))
    scene.render()
    table = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
    assert table["road"] is False and "road.prepare" not in table
    dry = scene.image()
    # Exactly the picture without the effect: the shader's dry path changes nothing.
    effects = scene.renderer.effects
    scene.renderer.effects = []
    scene.render()
    bare = scene.image()
    scene.renderer.effects = effects
    np.testing.assert_array_equal(dry, bare)
    _apply(scene, _settings(wetness=1.0))
    scene.render()
    table = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
    assert table["road.prepare"] and effect.reflection_image() is not None
    wet = scene.image()
    road_rows = slice(SIZE[1] // 2 + 4, SIZE[1] // 2 + 12)  # road ahead, above the hood
    assert wet[road_rows].mean() != pytest.approx(dry[road_rows].mean(), abs=1.0)
    _apply(scene, _settings(wetness=1.0, reflections=False))
    scene.render()
    assert effect.reflection_image() is None  # no reflection pass when reflections are off
    _apply(scene, _settings(wetness=1.0, enabled=False))
    scene.render()
    assert {n: r for n, r, *_ in scene.renderer.pass_table()}["road"] is False
    np.testing.assert_array_equal(scene.image(), bare)


def _display(hdr_rgb) -> np.ndarray:
    """shaders/tonemap.frag in NumPy: ACES fit, then sRGB, 0–255."""
    x = np.maximum(np.asarray(hdr_rgb, float), 0.0)
    aces = np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    srgb = np.where(aces <= 0.0031308, 12.92 * aces, 1.055 * aces ** (1 / 2.4) - 0.055)
    return srgb * 255.0


def _region_masks(image) -> list[np.ndarray]:
    """Pixels showing each debug-view region colour (road_surface.glsl draws 0.5·colour after exposure)."""
    expected = _display(0.5 * np.asarray(road.REGION_COLORS))
    dist = np.linalg.norm(image.astype(float)[..., None, :] - expected[None, None], axis=-1)
    return [(dist.argmin(axis=-1) == k) & (dist.min(axis=-1) < 12.0) for k in range(4)]


def test_debug_view_shows_the_four_regions(wet_scene):
    scene, _ = wet_scene
    counts = []
    for w, c, p in ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 1.0)):
        _apply(scene, _settings(wetness=w, cracks=c, puddles=p, puddle_amount=1.0, debug_regions=True))
        scene.render()
        counts.append([int(m.sum()) for m in _region_masks(scene.image())])
    dry, wet, flooded = counts
    assert dry[0] > 1000 and dry[1] == dry[2] == dry[3] == 0  # all dry (the cabin too)
    assert wet[1] > 1000 and wet[2] == wet[3] == 0
    assert flooded[2] > 20 and flooded[3] > 20 and flooded[1] > 1000  # drenched margins and puddles
    assert flooded[0] > 1000  # the cabin stays dry


def _karis_env_brdf(f0, roughness, nov):
    c0 = np.array([-1.0, -0.0275, -0.572, 0.022])
    c1 = np.array([1.0, 0.0425, 1.04, -0.04])
    r = roughness * c0 + c1
    a004 = np.minimum(r[0] * r[0], np.exp2(-9.28 * nov)) * r[0] + r[1]
    return f0 * (-1.04 * a004 + r[2]) + (1.04 * a004 + r[3])


def test_puddle_pixels_show_the_mirror_cameras_image(gl_ctx, wet_scene):
    scene, effect = wet_scene
    # No wet film (wetness 0): the scene outside the road is dry, puddles are flat mirrors of murky water.
    base = dict(wetness=0.0, cracks=0.0, puddles=1.0, puddle_amount=1.0, wave_strength=0.0,
                reflection_scale=1.0)
    _apply(scene, _settings(**base, debug_regions=True))
    scene.render()
    puddle = _region_masks(scene.image())[3]
    _apply(scene, _settings(**base))
    frame = scene.render()
    main = scene.renderer.hdr_image()
    # Without the planar reflection the water reflects the sky alone (and still shows its murky bottom).
    _apply(scene, _settings(**base, reflections=False))
    scene.render()
    sky_only = scene.renderer.hdr_image()
    assert puddle.sum() > 40
    # An independent mirror camera: a proper camera below the road, looking up (its picture is the mirror
    # image flipped left-right), drawn with the renderer's clip plane and without the road effect.
    cam = frame.camera
    flip = np.array([1.0, -1.0, 1.0])
    mirror_cam = Camera(position=cam.position * flip, forward=cam.forward * flip, up=np.array([0.0, -1.0, 0.0]),
                        fov_y_deg=cam.fov_y_deg, near_m=cam.near_m, far_m=cam.far_m, inside_car=False)
    rc = scene.renderer.render_context(dataclasses.replace(frame, camera=mirror_cam))
    target = float_target(gl_ctx, SIZE, 4, "f4", depth=True)

    def mirror_image(plane):
        target.fbo.use()
        target.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        scene.renderer.draw_scene(rc, [], include_sky=True, clip_plane=plane)
        data = np.frombuffer(target.fbo.read(components=3, dtype="f4", alignment=1), np.float32)
        return data.reshape(SIZE[1], SIZE[0], 3)[::-1, ::-1]

    mirror = mirror_image((0.0, 1.0, 0.0, -road.MIRROR_CLIP_Y_M))
    mirror_sky = mirror_image((0.0, 1.0, 0.0, -1.0e4))  # everything clipped: the sky alone
    gl_ctx.detect_framebuffer(0).use()  # never delete the bound framebuffer
    target.release()
    # Fresnel of flat water at each pixel's view angle.
    w, h = SIZE
    px, py = np.meshgrid((np.arange(w) + 0.5) / w * 2 - 1, 1 - (np.arange(h) + 0.5) / h * 2)
    r, u, f = cam.basis()
    t = math.tan(math.radians(cam.fov_y_deg) / 2)
    rays = f + px[..., None] * t * (w / h) * r + py[..., None] * t * u
    nov = -rays[..., 1] / np.linalg.norm(rays, axis=-1)
    fresnel = _karis_env_brdf(road.WATER_F0, road.WATER_ROUGHNESS, nov)[..., None]
    lum = np.array([0.2126, 0.7152, 0.0722])
    # What the reflection pass adds over the sky-only water must be F × (mirror camera − sky).
    seen = (main - sky_only)[puddle] @ lum
    expected = (fresnel * (mirror - mirror_sky))[puddle] @ lum
    assert np.abs(expected).mean() > 0.05 * (main[puddle] @ lum).mean()  # buildings, trees, cars mirrored
    corr = np.corrcoef(seen, expected)[0, 1]
    slope = np.polyfit(expected, seen, 1)[0]
    assert corr > 0.95 and 0.85 < slope < 1.15


def test_ripple_normals_move_the_reflection_and_none_restores_flat_water(gl_ctx, wet_scene):
    scene, effect = wet_scene
    settings = _settings(wetness=0.5, cracks=1.0, puddles=1.0, puddle_amount=1.0, wave_strength=0.0)
    _apply(scene, settings)
    scene.render()
    flat = scene.renderer.hdr_image()
    slopes = np.zeros((64, 64, 2), np.float32)
    slopes[..., 0] = 0.25 * np.sin(np.arange(64) / 3.0)[None, :]
    tex = gl_ctx.texture((64, 64), 2, slopes.tobytes(), dtype="f4")
    ego = scene.ego.position
    effect.set_ripple_normals(tex, (ego[0] - 15.0, ego[2] - 30.0), 30.0)
    scene.render()
    rippled = scene.renderer.hdr_image()
    assert np.abs(rippled - flat).max() > 0.01 * flat.max()
    effect.set_ripple_normals(None)
    scene.render()
    np.testing.assert_array_equal(scene.renderer.hdr_image(), flat)
    effect._ripple_explicit = False  # back to reading rc.resources for the next tests
    tex.release()


def test_wind_waves_ruffle_only_standing_water(gl_ctx, wet_scene):
    scene, _ = wet_scene
    still = _settings(wetness=1.0, cracks=1.0, puddles=1.0, puddle_amount=1.0, wave_strength=0.0)
    _apply(scene, still)
    scene.render()
    flat = scene.renderer.hdr_image()
    _apply(scene, _settings(wetness=0.0, cracks=1.0, puddles=1.0, puddle_amount=1.0, debug_regions=True))
    scene.render()
    puddle = _region_masks(scene.image())[3]
    windy = _settings(wetness=1.0, cracks=1.0, puddles=1.0, puddle_amount=1.0, wave_strength=1.0)
    set_value(windy, "wind.speed_m_s", 10.0)
    _apply(scene, windy)
    scene.render()
    waves = scene.renderer.hdr_image()
    changed = np.abs(waves - flat).max(axis=-1) > 1e-3 * flat.max()
    assert changed[puddle].mean() > 0.3  # the puddles ripple
    assert changed[~puddle].mean() < changed[puddle].mean()  # the rest barely changes (puddle margins do)


@pytest.mark.parametrize("hour,camera,scale", [(12.0, "chase", 0.125), (22.0, "driver", 1.0)])
def test_extreme_settings_stay_finite(gl_ctx, wet_scene, hour, camera, scale):
    scene, effect = wet_scene
    settings = _settings(hour=hour, camera=camera, wetness=1.0, cracks=1.0, puddles=1.0, puddle_amount=1.0,
                         wave_strength=1.0, reflection_scale=scale, puddle_seed=2**31 - 1)
    set_value(settings, "wind.speed_m_s", 40.0)
    set_value(settings, "wind.gustiness", 1.0)
    _apply(scene, settings)
    scene.step(1 / 30)
    scene.render()
    assert np.isfinite(scene.renderer.hdr_image()).all()
    assert np.isfinite(effect.reflection_image()).all()
    assert scene.image().std() > 5


def test_clip_plane_removes_what_lies_below_it(gl_ctx, wet_scene):
    scene, _ = wet_scene
    _apply(scene, _settings(wetness=0.0))
    frame = scene.render()
    renderer = scene.renderer
    target = float_target(gl_ctx, SIZE, 4, "f4", depth=True)

    def draw(plane):
        rc = renderer.render_context(frame, target)
        target.fbo.use()
        target.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        renderer.draw_scene(rc, [], include_sky=False, clip_plane=plane)
        return np.frombuffer(target.fbo.read(components=3, dtype="f4", alignment=1), np.float32).copy()

    _ = gl_ctx.error  # reading it clears what earlier users of the shared context left
    everything = draw(None)
    nothing = draw((0.0, 1.0, 0.0, -1.0e4))  # keep only y > 10 km: no geometry
    above = draw((0.0, 1.0, 0.0, -1.0))  # keep y > 1 m: the road goes
    assert (everything != 0).mean() > 0.5
    assert (nothing == 0).all()
    assert 0 < (above != 0).mean() < (everything != 0).mean()
    assert gl_ctx.error == "GL_NO_ERROR"
    gl_ctx.detect_framebuffer(0).use()
    target.release()
    # The clip distance is switched off again for the normal passes.
    assert not gl_ctx.is_enabled(0x3000) if hasattr(gl_ctx, "is_enabled") else True
    scene.render()
    assert scene.image().std() > 5




def test_benchmark_quick_writes_table_and_plot(gl_ctx, tmp_path):
    from rain_core.bench import road as bench

    assert bench.main(["--quick", "--out", str(tmp_path)], ctx=gl_ctx) == 0
    text = (tmp_path / "road.md").read_text()
    assert "effect disabled" in text and "dry road" in text and "reflection scale" in text
    assert (tmp_path / "road.png").stat().st_size > 1000
    errors = [float(line.split("|")[4]) for line in text.splitlines() if line.startswith("| 0.125 |")
              or line.startswith("| 1 |")]
    assert errors[-1] == 0.0 and errors[0] > 0.0  # scale 1 is the reference; a coarse texture differs
