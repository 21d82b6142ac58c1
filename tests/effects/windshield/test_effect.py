"""rain_core.effects.windshield.effect: the settings it reads, the skip rule, the GPU water texture against the CPU
state, the view through wet glass, determinism."""

import math

import numpy as np
import pytest

from rain_core.effects.windshield import FILM_CELLS, WindshieldEffect
from rain_core.settings import Settings, SettingsError, set_value


def test_settings_have_wiper_and_windshield_options():
    s = Settings()
    assert s.wipers.mode in ("off", "intermittent", "low", "high", "auto")
    assert s.wipers.low_cycles_per_min < s.wipers.high_cycles_per_min
    set_value(s, "wipers.interval_s", 8.0)
    set_value(s, "windshield.drop_budget", 2000)
    with pytest.raises(SettingsError):
        set_value(s, "windshield.drop_budget", -1)
    with pytest.raises(SettingsError):
        set_value(s, "wipers.mode", "turbo")
    assert 64 <= s.quality.windshield_resolution <= 2048


def _scene(gl_ctx, settings, effect, size=(160, 90)):
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, size, settings, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = 0.0
    return scene


class _Brake:
    throttle, brake, steer, reverse = 0.0, 1.0, 0.0, False


def test_dry_glass_costs_nothing_and_outside_camera_skips(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 0.0
    s.wipers.mode = "auto"
    effect = WindshieldEffect(gl_ctx, s, seed=1, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    scene.step(1 / 30, _Brake)
    scene.render()

    def ran():
        return {name: done for name, done, *_ in scene.renderer.pass_table()}

    assert ran()["windshield"] is False and "windshield.overlay" not in ran()
    s.rain.rate_mm_h = 4.0
    scene.step(1 / 30, _Brake)
    scene.render(scene.camera("chase"))
    assert ran()["windshield"] is False  # outside the car
    scene.render()
    assert ran()["windshield.prepare"] and ran()["windshield.overlay"]
    scene.release()


def test_gpu_water_texture_agrees_with_the_cpu_state(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 8.0
    s.wipers.mode = "off"
    s.quality.windshield_resolution = 256
    effect = WindshieldEffect(gl_ctx, s, seed=2, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    for _ in range(12):
        scene.step(1 / 30, _Brake)
        scene.render()
    n = effect.resolution
    water = np.frombuffer(effect.water_texture.read(), np.float16).reshape(n, n, 4).astype(np.float64)
    assert np.all(np.isfinite(water))
    # The film channel, averaged over each CPU cell, is the CPU film (the rescaling keeps them together).
    k = n // FILM_CELLS
    gpu_cells = water[..., 1].reshape(FILM_CELLS, k, FILM_CELLS, k).mean(axis=(1, 3))
    cpu_cells = effect.sim.film_thickness_m() * 1e6
    wet = cpu_cells > 0.05
    assert wet.sum() > 100
    ratio = np.median(gpu_cells[wet] / cpu_cells[wet])
    assert 0.8 < ratio < 1.25
    # Every drop is a bump in the thickness texture where the CPU has it.
    uv = effect.glass.to_uv(effect.sim.pos)
    texel = np.clip((uv * n).astype(int), 0, n - 1)
    big = effect.sim.radius() > 1e-3
    assert np.mean(water[texel[big, 1], texel[big, 0], 0] > 0.05) > 0.9
    dry = water[..., 0] < 1e-4
    assert dry.mean() > 0.2
    scene.release()


def test_wet_glass_changes_the_view_and_stays_finite(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 16.0
    s.wipers.mode = "off"
    effect = WindshieldEffect(gl_ctx, s, seed=3, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    scene.step(1 / 30, _Brake)
    scene.render()
    dry = scene.renderer.hdr_image()
    for _ in range(40):
        scene.step(1 / 30, _Brake)
        scene.render(draw=False)  # the water builds faster than we draw
    scene.step(1 / 30, _Brake)
    scene.render()
    wet = scene.renderer.hdr_image()
    assert np.all(np.isfinite(wet))
    assert np.mean(np.abs(wet - dry)) > 0.01 * np.mean(dry)
    scene.release()


def test_rendering_is_deterministic(gl_ctx, shaders):
    def frame():
        s = Settings()
        s.rain.rate_mm_h = 8.0
        s.wipers.mode = "high"
        effect = WindshieldEffect(gl_ctx, s, seed=4, shaders=shaders)
        scene = _scene(gl_ctx, s, effect)
        for _ in range(8):
            scene.step(1 / 30, _Brake)
            scene.render()
        image = scene.image()
        scene.release()
        return image

    assert np.array_equal(frame(), frame())


def test_release_frees_every_gl_object_it_made(gl_ctx):
    import gc

    gc.collect()  # what earlier tests dropped is theirs, not this test's: collect it before counting
    old_mode = gl_ctx.gc_mode
    gl_ctx.gc_mode = "context_gc"  # unreleased objects whose wrapper died land in gl_ctx.objects
    try:
        s = Settings()
        s.rain.rate_mm_h = 8.0
        s.quality.windshield_resolution = 128
        effect = WindshieldEffect(gl_ctx, s, seed=5)  # its own shader library: its programs are its to release
        scene = _scene(gl_ctx, s, effect, size=(96, 54))
        for _ in range(3):
            scene.step(1 / 30, _Brake)
            scene.render()
        assert effect.water_texture is not None
        scene.release()
        del scene, effect
        gc.collect()
        leaked = [type(o).__name__ for o in gl_ctx.objects if type(o).__name__ != "InvalidObject"]
        assert not leaked, f"unreleased GL objects: {sorted(set(leaked))}"
    finally:
        gl_ctx.objects.clear()
        gl_ctx.gc_mode = old_mode


def test_splats_are_one_instanced_draw_per_water_target_with_only_what_the_frame_draws(gl_ctx, shaders, kernel_path):
    from rain_core.effects.windshield.splats import drop_splats, film_splats

    s = Settings()
    s.rain.rate_mm_h = 8.0
    s.wipers.mode = "high"
    s.quality.windshield_resolution = 128
    effect = WindshieldEffect(gl_ctx, s, seed=6, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    for _ in range(6):
        scene.step(1 / 30, _Brake)
        scene.render()
    texel = effect._texel_m()
    sets = [len(film_splats(effect.sim, texel)), len(drop_splats(effect.sim, texel))]
    rows = sum(sets)
    assert rows > 0 and effect.splat_draws == sum(k > 0 for k in sets)  # film deposits, drops: ≤ one draw each
    # 8 float32 a film splat, 5 float32 a drop row, the coarse film as float16.
    assert effect.upload_bytes == 32 * sets[0] + 20 * sets[1] + 2 * FILM_CELLS * FILM_CELLS
    assert effect.status()["upload_kb"] == effect.upload_bytes / 1024
    scene.release()


def test_shelter_lookup_is_kept_per_position_and_matches_the_roof(gl_ctx, shaders):
    # active() and inputs_for() both ask whether a roof is over the glass; the answer is kept for the last
    # world and position. Along the road (under the bridge and out) it must equal the direct lookup.
    s = Settings()
    effect = WindshieldEffect(gl_ctx, s, seed=1, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    ego, world = scene.ego, scene.world
    x0 = float(ego.position[0])
    seen = set()
    for z in np.linspace(-400.0, 400.0, 321):
        ego.position[2] = z
        frame = scene.frame()
        centre = ego.to_world(effect.glass.local_points(np.array([[0.0, 0.5 * effect.glass.height]])))[0]
        want = bool(float(np.asarray(world.occluder_height(centre[0], centre[2]))) > centre[1])
        assert effect._sheltered(frame) == want, z
        assert effect._sheltered(frame) == want, z  # the kept answer
        seen.add(want)
    assert seen == {True, False}, f"no roof over the road at x = {x0} in ±400 m"
    scene.release()


def test_roof_height_is_the_worlds_occluder_height_at_any_point(gl_ctx, shaders):
    # _sheltered looks the roof up in Python scalars (effect.roof_height): it must give World.occluder_height's
    # answer everywhere: on the fine map and the coarse one, beyond both, at negative and far z (periodic).
    from rain_core.effects.windshield.effect import roof_height

    s = Settings()
    effect = WindshieldEffect(gl_ctx, s, seed=1, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    world = scene.world
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(-12.0, 12.0, 3000), rng.uniform(-120.0, 120.0, 1000)])
    z = rng.uniform(-2500.0, 2500.0, len(x))
    want = world.occluder_height(x, z)
    got = np.array([roof_height(world, float(a), float(b)) for a, b in zip(x, z, strict=True)])
    assert np.array_equal(got, want)
    assert np.isfinite(want).sum() > 100 and np.isneginf(want).sum() > 100
    scene.release()


def test_half_bits_are_numpys_float16_to_the_last_bit():
    # The drop rows' radius and height go to the GPU as float16 through splats.half_bits (NumPy's cast is slow):
    # it must give NumPy's bits (ties may round the other way: one unit in the last place).
    from rain_core.effects.windshield.splats import half_bits

    rng = np.random.default_rng(3)
    x = (rng.random(20000) * 10.0 ** rng.uniform(-4.2, 4.5, 20000)).astype(np.float32)
    x = np.concatenate([x, np.float32([2.0**-14, 1.0, 0.5, 65504.0])])
    out = half_bits(x)
    expected = x.astype(np.float16).view(np.uint16).astype(np.int64)
    normal = x >= 2.0**-14
    assert np.abs(out[normal].astype(np.int64) - expected[normal]).max() <= 1
    assert (out[normal] == expected[normal]).mean() > 0.999
    assert np.all(out[~normal].view(np.float16) <= np.float16(2.0**-14))  # below the normals: 0 or the smallest


def test_rarely_changing_uniforms_follow_what_they_are_made_of(gl_ctx, shaders):
    # The uniforms that change only with the resolution, the view or the settings are written when those change
    # (OwnedUniforms.update_for), not looked at every frame: a new refraction, resolution or window size must
    # reach them, and two effects sharing one shader library must each see their own.
    s = Settings()
    s.rain.rate_mm_h = 8.0
    s.quality.windshield_resolution = 128
    effect = WindshieldEffect(gl_ctx, s, seed=3, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)

    def frame():
        scene.step(1 / 30, _Brake)
        scene.render()

    frame()
    assert effect.glass_prog["u_refraction"].value == pytest.approx(s.windshield.refraction)
    assert effect.normals_prog["u_texel"].value == pytest.approx((1 / 128, 1 / 128))
    s.windshield.refraction = 0.5
    frame()
    assert effect.glass_prog["u_refraction"].value == pytest.approx(0.5)
    s.quality.windshield_resolution = 256
    frame()
    assert effect.normals_prog["u_texel"].value == pytest.approx((1 / 256, 1 / 256))
    assert effect.film_prog["u_texel"].value == pytest.approx((1 / 256, 1 / 256))
    assert effect.drop_splat_prog["u_min_radius"].value == pytest.approx(0.75 * effect._texel_m(), rel=1e-6)
    assert effect.glass_prog["u_drop_lod"].value == pytest.approx(0.5)  # the eye's blur under a texel
    pixel = effect.drop_prog["u_pixel_rad"].value
    scene.renderer.resize((320, 540))
    frame()
    assert effect.glass_prog["u_drop_lod"].value == pytest.approx(math.log2(0.0037 * 540) + 0.5, rel=1e-6)
    assert effect.drop_prog["u_pixel_rad"].value == pytest.approx(pixel / 6, rel=1e-6)
    pixel = effect.drop_prog["u_pixel_rad"].value
    for seed, size, scale in ((4, (320, 540), 1.0), (5, (160, 270), 2.0)):  # the same programs, another effect
        other = WindshieldEffect(gl_ctx, s, seed=seed, shaders=shaders)
        scene2 = _scene(gl_ctx, s, other, size=size)
        scene2.step(1 / 30, _Brake)
        scene2.render()
        assert effect.film_prog["u_seed"].value == seed
        assert effect.drop_prog["u_pixel_rad"].value == pytest.approx(scale * pixel)
        frame()
        assert effect.film_prog["u_seed"].value == 3 and effect.drop_prog["u_pixel_rad"].value == pytest.approx(pixel)
        scene2.release()
    scene.release()


def test_inputs_are_made_again_only_when_what_they_are_made_of_changes(gl_ctx, shaders):
    # inputs_for gives the last GlassInputs again while the frame's weather, motion, roof and settings are the
    # same (a parked car): the very object, so the simulation skips its per-inputs work. Any change makes new ones,
    # equal to inputs made from scratch.
    from dataclasses import fields
    from types import SimpleNamespace

    s = Settings()
    s.rain.rate_mm_h = 8.0
    effect = WindshieldEffect(gl_ctx, s, seed=2, shaders=shaders)
    scene = _scene(gl_ctx, s, effect)
    scene.step(1 / 30, _Brake)
    first = effect.inputs_for(scene.frame())
    assert effect.inputs_for(scene.frame()) is first

    def fresh(frame):
        effect._inputs_memo = None
        return effect.inputs_for(frame)

    def same(a, b):
        return all(np.array_equal(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))

    def heavier(frame):
        frame.weather = SimpleNamespace(rate_mm_h=20.0, wind=frame.weather.wind)

    changes = (lambda f: set_value(s, "wipers.mode", "high"), heavier,
               lambda f: setattr(scene.ego, "speed_m_s", 5.0), lambda f: setattr(scene.ego, "yaw", 0.3))
    frame = scene.frame()
    for change in changes:
        before = effect.inputs_for(frame)
        change(frame)
        now = effect.inputs_for(frame)
        assert now is not before and not same(now, before)
        assert same(now, fresh(frame))
    scene.release()


def test_drop_rows_are_the_drops_as_they_are_and_the_beads_along_the_blades(kernel_path):
    # The drop buffer's rows (splats.DropRows): a drop's (s, t, vs, vt) and radius as float32, read from the fast
    # path's drop array or through the public arrays alike; a bead bin with water is a line from one end of its
    # bin to the other, 4 mm ahead of the blade (WindshieldSimReference.bead_bin_centres), of minus its radius.
    from rain_core.effects.windshield.constants import BEAD_BINS
    from rain_core.effects.windshield.inputs import GlassInputs
    from rain_core.effects.windshield.reference import WindshieldSimReference
    from rain_core.effects.windshield.sim import WindshieldSim
    from rain_core.effects.windshield.splats import DROP_ROW, DropRows

    sim = WindshieldSim(seed=4)
    inputs = GlassInputs.for_speed(60.0, 20.0, wiper_mode="high")
    for _ in range(40):
        sim.step(1 / 30, inputs)
    assert sim.beads.any() and (sim.vel != 0).any()
    builder = DropRows()
    rows = builder.rows(sim).copy()
    assert rows.dtype == DROP_ROW and len(rows) == sim.count + int((sim.beads > 0).sum())
    n = sim.count
    assert np.array_equal(rows["seg"][:n], np.hstack([sim.pos, sim.vel]).astype(np.float32))
    assert np.array_equal(rows["radius"][:n], sim.radius().astype(np.float32))
    ref = WindshieldSimReference(seed=4)
    ref.pos, ref.vel, ref.mass = sim.pos.copy(), sim.vel.copy(), sim.mass.copy()
    ref.beads, ref.wipers, ref.blades = sim.beads, sim.wipers, sim.blades
    public = DropRows().rows(ref)  # the public arrays give the same rows (the radius made anew from the mass)
    assert np.array_equal(public["seg"], rows["seg"])
    np.testing.assert_allclose(public["radius"], rows["radius"], rtol=1e-6)
    ahead = 0.004 if (sim.wipers.phase or 0.0) < 0.5 else -0.004
    row = n
    for b, blade in enumerate(sim.blades):
        angle = float(blade.angle(sim.wipers.progress))
        centres = sim.bead_bin_centres(blade, angle, ahead=ahead)
        half = np.array([math.cos(angle), math.sin(angle)]) * 0.5 * (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        keep = (sim.beads[b] > 0).nonzero()[0]
        lines = rows[row : row + len(keep)]
        np.testing.assert_allclose(lines["seg"][:, 0:2], centres[keep] - half, atol=1e-6)
        np.testing.assert_allclose(lines["seg"][:, 2:4], centres[keep] + half, atol=1e-6)
        assert np.all(lines["radius"] < 0)
        row += len(keep)
    assert len(builder.rows(sim)) == len(rows)  # the kept array, rewritten


def test_glass_inputs_check_the_settings_again_whenever_they_differ():
    # The settings' fields of the last inputs made are not checked again for the same plain numbers (a moving car
    # makes inputs every frame); anything else is: another value, a bool, an array, NaN, a fractional budget.
    from rain_core.effects.windshield.inputs import GlassInputs

    good = GlassInputs(drop_scale=1.0, drop_budget=6000)
    again = GlassInputs(drop_scale=1.0, drop_budget=6000)
    assert again.drop_scale == good.drop_scale == 1.0 and type(again.drop_budget) is int
    for bad in (True, math.nan, np.array([1.0, 1.0]), -1.0):
        with pytest.raises(ValueError, match="drop_scale"):
            GlassInputs(drop_scale=bad, drop_budget=6000)
        assert GlassInputs(drop_scale=1.0, drop_budget=6000).drop_scale == 1.0
    with pytest.raises(ValueError, match="drop_budget"):
        GlassInputs(drop_budget=6000.5)
    numpy_scale = GlassInputs(drop_scale=np.float64(0.5), drop_budget=np.int64(300))
    assert type(numpy_scale.drop_scale) is float and numpy_scale.drop_budget == 300
    assert type(numpy_scale.drop_budget) is int
    assert GlassInputs(drop_budget=300.0).drop_budget == 300 and type(GlassInputs(drop_budget=300.0).drop_budget) is int
