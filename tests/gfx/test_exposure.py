"""Automatic exposure: the GPU meter and adaptation against the float64 reference (rain_core.exposure), its
stability, and what it does to a night street."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from rain_core import exposure as X

SHADERS = Path(__file__).resolve().parents[2] / "shaders"


def test_shader_constants_match_the_reference():
    src = (SHADERS / "exposure" / "meter.glsl").read_text()

    def vec2(name):
        m = re.search(rf"const vec2 {name} = vec2\(([^,]+), ([^)]+)\);", src)
        return tuple(float(eval(v)) for v in m.groups())  # noqa: S307 - our own constant expressions

    assert vec2("METER_CENTRE") == pytest.approx(X.METER_CENTRE)
    assert vec2("METER_SIGMA") == pytest.approx(X.METER_SIGMA)
    assert vec2("RANGE_EV") == pytest.approx(X.RANGE_EV)
    key = re.search(r"const float METER_KEY = ([^;]+);", src).group(1)
    assert eval(key) == pytest.approx(X.METER_KEY)  # noqa: S307
    assert float(re.search(r"const float LOG2_FLOOR = ([^;]+);", src).group(1)) == X.LOG2_FLOOR


def test_adaptation_is_exact_for_any_step():
    """First order in EV: one 1 s step equals thirty 1/30 s steps; a huge step lands on the target, never past
    it; no step leaves the segment between start and target."""
    one = X.adapt(0.0, 2.0, 1.0, 1.5)
    many = 0.0
    for _ in range(30):
        many = X.adapt(many, 2.0, 1.0 / 30.0, 1.5)
    assert many == pytest.approx(one, rel=1e-12)
    assert one == pytest.approx(2.0 * (1.0 - math.exp(-1.0 / 1.5)))
    assert X.adapt(-1.0, 2.0, 1e9, 1.5) == 2.0
    assert X.adapt(0.5, 2.0, 0.0, 1.5) == 0.5
    for dt in (1e-6, 0.01, 0.3, 7.0, 1e3):
        assert 0.5 <= X.adapt(0.5, 2.0, dt, 0.05) <= 2.0
    assert X.target_correction_ev(-40.0) == X.RANGE_EV[1]  # a black frame asks for the most the eye gives
    assert X.target_correction_ev(40.0) == X.RANGE_EV[0]


def _texture(ctx, image_top_first: np.ndarray):
    import moderngl

    img = np.ascontiguousarray(image_top_first[::-1], dtype=np.float32)  # GL rows start at the bottom
    tex = ctx.texture((img.shape[1], img.shape[0]), 3, img.tobytes(), dtype="f4")
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x = tex.repeat_y = False
    return tex


def test_gpu_meter_matches_the_reference_and_ignores_bad_pixels(gl_ctx):
    from rain_core.gfx.exposure import AutoExposure
    from rain_core.gfx.shaders import ShaderLibrary

    rng = np.random.default_rng(3)
    h, w = 90, 160
    yy, xx = np.mgrid[0:h, 0:w]
    image = (np.exp2(-8.0 + 10.0 * xx / w - 3.0 * yy / h)[..., None] * rng.uniform(0.5, 1.5, (h, w, 3)))
    image[40:44, 70:75] = np.nan  # a bad pixel counts as black, never as NaN
    image[10, 10] = np.inf
    image[60:62, :5] = 0.0
    shaders = ShaderLibrary(gl_ctx)
    ae = AutoExposure(gl_ctx, shaders)
    tex = _texture(gl_ctx, image)
    try:
        ae.update(tex, 1 / 30, 1.5, 0.0)
        ref = X.metered_log2_luminance(image)
        assert math.isfinite(ae.read_meter())
        assert ae.read_meter() == pytest.approx(ref, abs=2e-3)
        # The first frame has no history: the correction is the target at once.
        assert ae.read_ev() == pytest.approx(X.target_correction_ev(ref), abs=2e-3)
        # Then it adapts towards a new target as the reference says, step by step.
        dark = image * 2.0 ** -3
        tex_dark = _texture(gl_ctx, dark)
        expected = ae.read_ev()
        target = X.target_correction_ev(X.metered_log2_luminance(dark), 0.5)
        for dt in (1 / 30, 0.25, 0.0, 1.0, 1 / 240):
            ae.update(tex_dark, dt, 1.5, 0.5)
            expected = X.adapt(expected, target, dt, 1.5)
            assert ae.read_ev() == pytest.approx(expected, abs=2e-3)
        tex_dark.release()
    finally:
        tex.release()
        ae.release()
        shaders.release()


def _scene(ctx, hour, **values):
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in {"rain.rate_mm_h": 4.0, "time_of_day.hour": hour, **values}.items():
        set_value(settings, path, value)
    return Scene(ctx, (192, 108), settings, seed=1, gpu_timing=False)


def _luma(img):
    return float((img.astype(np.float64) / 255.0 @ np.array([0.2126, 0.7152, 0.0722])).mean())


def test_a_night_street_is_brightened_and_noon_barely_moves(gl_ctx):
    """At 22.5 h the lamp-lit street meters ~1 stop under the key: the eye opens up and the picture is brighter
    than the hour's meter alone gives; at noon the correction stays within half a stop. Switched off, the pass
    does not run and the picture is the meter's."""
    results = {}
    for hour in (12.0, 22.5):
        for auto in (True, False):
            scene = _scene(gl_ctx, hour, **{"camera.auto_exposure": auto})
            try:
                for _ in range(2):
                    scene.step(1 / 30)
                    scene.render()
                ran = dict((s.name, s.ran) for s in scene.renderer.stats)["exposure"]
                assert ran == auto
                ev = scene.renderer.exposure.read_ev() if auto else 0.0
                results[hour, auto] = (_luma(scene.image()), ev)
            finally:
                scene.release()
    assert abs(results[12.0, True][1]) < 0.5
    assert results[22.5, True][1] > 0.5
    assert results[22.5, True][0] > 1.3 * results[22.5, False][0]


def test_the_eye_adapts_over_seconds_when_the_light_changes(gl_ctx):
    """Dusk to night in one step (as into an underpass): the correction moves towards the new target by
    1 − e^(−t/τ), not at once, and gets there within a few τ."""
    scene = _scene(gl_ctx, 12.0, **{"camera.adaptation_s": 0.5, "traffic.count": 0})
    try:
        scene.step(1 / 30)
        scene.render()
        start = scene.renderer.exposure.read_ev()
        scene.settings.time_of_day.hour = 22.5
        evs = []
        for _ in range(12):
            scene.step(0.25)
            scene.render()
            evs.append(scene.renderer.exposure.read_ev())
        target = X.target_correction_ev(scene.renderer.exposure.read_meter())
        assert evs[0] - start < 0.6 * (target - start)  # not at once
        assert abs(evs[-1] - target) < 0.1 * abs(target - start) + 0.05  # there after 6 τ
        assert all(math.isfinite(e) for e in evs)
    finally:
        scene.release()


def test_exposures_sharing_programs_keep_their_own_inputs(gl_ctx):
    """The adaptation's uniforms are skipped while unchanged (per program, shared by every AutoExposure of a
    shader library): two eyes adapting in turn with other steps, time constants, compensations and resets each
    follow the reference as if alone."""
    from rain_core.gfx.exposure import AutoExposure
    from rain_core.gfx.shaders import ShaderLibrary

    image = np.full((36, 64, 3), 0.02)
    shaders = ShaderLibrary(gl_ctx)
    eyes = [AutoExposure(gl_ctx, shaders), AutoExposure(gl_ctx, shaders)]
    tex = _texture(gl_ctx, image)
    try:
        target = {0: X.target_correction_ev(X.metered_log2_luminance(image), 0.0),
                  1: X.target_correction_ev(X.metered_log2_luminance(image), 1.0)}
        expected = {0: None, 1: None}
        steps = [(0, 1 / 30, 1.5), (1, 0.25, 0.5), (0, 1 / 30, 1.5), (1, 0.25, 0.5), (1, 0.25, 0.5), (0, 0.5, 3.0)]
        for i, (eye, dt, tau) in enumerate(steps):
            if i == 4:
                eyes[1].reset()  # takes the target at once, then adapts again
                expected[1] = None
            eyes[eye].update(tex, dt, tau, float(eye))
            previous = expected[eye]
            expected[eye] = target[eye] if previous is None else X.adapt(previous, target[eye], dt, tau)
            assert eyes[eye].read_ev() == pytest.approx(expected[eye], abs=2e-3)
    finally:
        tex.release()
        for eye in eyes:
            eye.release()
        shaders.release()


def test_tone_map_follows_live_exposure_changes(gl_ctx):
    """The tone map's uniforms are skipped while unchanged: a frame shown with auto exposure off at +1 EV after
    a frame with it on is the frame a fresh renderer shows with those settings (no effects: no state besides)."""
    import dataclasses

    from rain_core.gfx.renderer import Renderer
    from rain_core.settings import set_value

    scene = _scene(gl_ctx, 12.0)
    fresh = None
    try:
        scene.step(1 / 30)
        frame = scene.frame()
        off = dataclasses.replace(frame, settings=dataclasses.replace(frame.settings))
        off.settings.camera = dataclasses.replace(frame.settings.camera)
        set_value(off.settings, "camera.auto_exposure", False)
        set_value(off.settings, "camera.exposure_compensation_ev", 1.0)
        renderer = Renderer(gl_ctx, (192, 108), scene.world, gpu_timing=False, shaders=scene.renderer.shaders)
        fresh = Renderer(gl_ctx, (192, 108), scene.world, gpu_timing=False)
        renderer.render(frame)
        on_image = renderer.image()
        renderer.render(off)
        fresh.render(off)
        np.testing.assert_array_equal(renderer.image(), fresh.image())
        assert np.abs(renderer.image().astype(int) - on_image.astype(int)).max() > 0
        fresh.render(frame)  # and back: auto exposure from a reset, as the first frame
        renderer.exposure.reset()
        renderer.render(frame)
        np.testing.assert_array_equal(renderer.image(), fresh.image())
        renderer.release()
    finally:
        if fresh is not None:
            fresh.release()
        scene.release()
