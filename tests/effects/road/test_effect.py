"""The road effect in the scene (rain_core.effects.road.effect): the dry path, the debug regions, planar
reflections against an independent mirror camera, ripple normals, wind waves, extreme settings, the clip plane,
the benchmark."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rain_core import layout
from rain_core.camera import Camera
from rain_core.effects import road
from rain_core.gfx.targets import float_target
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

SIZE = (160, 90)


def _draw_without_effects(renderer, rc, include_sky, clip_plane):
    """The renderer's scene pass into ``rc``'s bound target with no effect active (each binds its neutral
    inputs)."""
    rc.active = ()
    renderer.shadow.bind()
    renderer.scene.draw(rc, renderer.effects, include_sky=include_sky, clip_plane=clip_plane)


def _settings(hour=12.0, camera="driver", wetness=1.0, cracks=0.0, puddles=0.0, **road_values) -> Settings:
    s = Settings()
    set_value(s, "camera.auto_exposure", False)  # colours are checked against the road's model at the hour's meter
    set_value(s, "time_of_day.hour", hour)
    set_value(s, "camera.mode", camera)
    set_value(s, "traffic.count", 2)
    for name, value in (("wetness", wetness), ("cracks", cracks), ("puddles", puddles)):
        set_value(s, f"rain.{name}", value)
    for key, value in road_values.items():
        set_value(s, f"road.{key}", value)
    return s


@pytest.fixture(scope="module")
def wet_scene(gl_ctx):
    with gl_ctx:  # module fixtures run outside conftest's per-test _gl_current
        settings = _settings()
        effect = road.RoadEffect(gl_ctx, settings)  # takes the scene's world from the first frame
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


def test_scene_inputs_come_back_after_the_road_was_off(wet_scene):
    """The wet inputs are written again after a frame of the dry path with the same levels: bind_scene's planned
    tuple is then the same object, which OwnedUniforms.update_once would skip had unbind_scene not gone through it."""
    scene, effect = wet_scene
    prog = scene.renderer.scene.scene_prog
    _apply(scene, _settings(wetness=1.0))
    scene.render()
    wet, plan = scene.image(), effect._scene_plan
    _apply(scene, _settings(wetness=1.0, enabled=False))
    scene.render()
    assert prog["u_road_wet"].value == 0.0
    _apply(scene, _settings(wetness=1.0))
    scene.render()
    assert effect._scene_plan is plan and prog["u_road_wet"].value == 1.0
    np.testing.assert_array_equal(scene.image(), wet)


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
        # Kerb streams off: the regions follow the levels alone (test_gutter.py covers the streams).
        _apply(scene, _settings(wetness=w, cracks=c, puddles=p, puddle_amount=1.0, debug_regions=True,
                                kerb_streams=False))
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
        _draw_without_effects(scene.renderer, rc, include_sky=True, clip_plane=plane)
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
    effect._ripple_explicit = False  # back to reading rc.shared for the next tests
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
        _draw_without_effects(renderer, rc, include_sky=False, clip_plane=plane)
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


def test_cabin_inverse_follows_the_ego_with_and_without_the_mirror_pass(gl_ctx):
    """u_road_cabin (made ahead in update, kept per model array and shift) is the inverse of the ego's
    model in the wrapped frame after every move, with reflections on and off, and after a pose set in place."""
    from rain_core.gfx.linalg import inverse
    from rain_core.gfx.uniforms import mat4_bytes

    settings = _settings()
    effect = road.RoadEffect(gl_ctx, settings)
    scene = Scene(gl_ctx, SIZE, settings, seed=1, effects=[effect], gpu_timing=False)
    try:
        scene.ego.speed_m_s = 20.0
        prog = scene.renderer.scene.scene_prog
        for step, reflections in enumerate((True, True, False, False, True)):
            set_value(settings, "road.reflections", reflections)
            if step == 3:
                scene.ego.position = scene.ego.position + np.array([0.0, 0.0, 40.0])  # a new pose, not a step
            else:
                scene.step(1 / 30)
            frame = scene.render()
            assert effect.needs_reflection(frame) is reflections
            shift_z = math.floor(float(frame.camera.position[2]) / layout.PERIOD_M) * layout.PERIOD_M
            model = frame.ego.model_matrix().copy()
            model[2, 3] -= shift_z
            assert prog["u_road_cabin"].read() == mat4_bytes(inverse(model))
    finally:
        scene.release()
