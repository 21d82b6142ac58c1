"""The atmosphere's per-frame CPU paths (issue 13): the medium is modelled once while what it depends on stays,
and afresh when that changes."""

from __future__ import annotations

import numpy as np

from rain_core.camera import look_at
from rain_core.effects import atmosphere as atm
from rain_core.effects.atmosphere.model import atmosphere_state, atmosphere_uniforms
from rain_core.settings import Settings
from rain_core.world import StreetLamp


def test_the_medium_is_modelled_once_and_again_when_its_inputs_change(gl_ctx, kit, monkeypatch):
    effect = atm.AtmosphereEffect(gl_ctx)
    calls = []
    model = atm.effect.atmosphere_state

    def counting(*args, **kwargs):
        calls.append(args)
        return model(*args, **kwargs)

    monkeypatch.setattr(atm.effect, "atmosphere_state", counting)
    settings = Settings()
    world = kit.world([kit.box((0.0, 5.0, 500.0), (20.0, 10.0, 20.0), (0.3, 0.3, 0.3))])
    camera = look_at((3.0, 1.5, 600.0), (0.0, 4.0, 500.0), fov_y_deg=60.0)
    frame = kit.frame(camera, world, settings, 8.0, 12.0)
    first = effect.frame_uniforms(frame)
    assert effect._state(frame) is effect._state(frame) and len(calls) == 1  # frame_uniforms, update: one model
    assert first == atmosphere_uniforms(atmosphere_state(settings.atmosphere, 8.0, frame.lighting))
    settings.atmosphere.fog_scale = 3.0  # the same frame with its settings edited: modelled afresh
    thicker = effect.frame_uniforms(frame)
    assert len(calls) == 2 and thicker["u_extinction_per_m"] > first["u_extinction_per_m"]
    np.testing.assert_equal(thicker, atmosphere_uniforms(atmosphere_state(settings.atmosphere, 8.0, frame.lighting)))
    # The next frame with the same rate, settings, lighting and world: the same state and the same uniforms
    # dict (the renderer's frame block then sees unchanged values), not modelled again.
    other = kit.frame(camera, world, settings, 8.0, 12.0)
    assert other is not frame and other.lighting is frame.lighting
    assert effect.frame_uniforms(other) is thicker and len(calls) == 2
    later = kit.frame(camera, world, settings, 8.0, 18.0)  # another hour: another lighting, modelled again
    np.testing.assert_equal(effect.frame_uniforms(later),
                            atmosphere_uniforms(atmosphere_state(settings.atmosphere, 8.0, later.lighting)))
    assert len(calls) == 3
    assert effect.frame_uniforms(kit.frame(camera, world, settings, 2.0, 18.0))["u_extinction_per_m"] \
        < thicker["u_extinction_per_m"] and len(calls) == 4  # another rate: modelled again
    effect.release()


def test_each_blur_direction_keeps_its_own_program_and_step(gl_ctx, shaders, kit):
    """The two blur draws use one program each (so u_step is written once, not twice a frame): after frames
    drawn with another renderer's atmosphere in between and a glow resolution change, the horizontal program
    still holds (1, 0) and the vertical (0, 1), and the glow equals a fresh renderer's."""
    world = kit.world([kit.box((0.0, 1.5, 570.0), (0.4, 0.4, 0.4), (2.0, 2.0, 2.0))])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 1.5, 500.0), fov_y_deg=40.0)
    settings = Settings()
    settings.atmosphere.glow = 2.0
    renderers = [kit.renderer(gl_ctx, shaders, world, (64, 36)) for _ in range(2)]
    try:
        frame = kit.frame(camera, world, settings, 30.0, 22.0)
        for resolution in (0.5, 0.25):
            settings.atmosphere.glow_resolution = resolution
            for r in renderers * 2:
                r.render(frame)
            effect = renderers[0].effects[0]
            blur = {key[1]: prog for key, prog in effect._programs.items() if isinstance(key, tuple)}
            assert blur[0] is not blur[1]
            assert tuple(blur[0]["u_step"].value) == (1, 0) and tuple(blur[1]["u_step"].value) == (0, 1)
            fresh = kit.renderer(gl_ctx, shaders, world, (64, 36))
            try:
                fresh.render(frame)
                renderers[0].render(frame)
                assert np.array_equal(renderers[0].hdr_image(), fresh.hdr_image())
            finally:
                kit.release(fresh)
    finally:
        kit.release(*renderers)


def test_post_uniforms_follow_live_setting_changes(gl_ctx, shaders, kit):
    """The post programs' uniforms are made only when their inputs change (update_for): after each live change
    of the glow, its resolution, the light scattering and the rain, every program holds this frame's values."""
    world = kit.world([kit.box((0.0, 1.5, 570.0), (0.4, 0.4, 0.4), (2.0, 2.0, 2.0))], lamps=[
        StreetLamp(np.array([0.0, 7.0, 560.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3))])
    camera = look_at((0.0, 1.5, 600.0), (0.0, 1.5, 500.0), fov_y_deg=40.0)
    settings = Settings()
    renderer = kit.renderer(gl_ctx, shaders, world, (64, 36))
    effect = renderer.effects[0]
    changes = [lambda: None, lambda: setattr(settings.atmosphere, "glow", 3.0),
               lambda: setattr(settings.atmosphere, "glow_resolution", 0.25),
               lambda: setattr(settings.atmosphere, "light_scattering", 2.0), lambda: None]
    try:
        for rate, change in zip((8.0, 8.0, 8.0, 8.0, 40.0), changes, strict=True):
            change()
            frame = kit.frame(camera, world, settings, rate, 22.0)
            renderer.render(frame)
            state = effect.state
            composite = effect._programs["atmosphere/composite.frag"]
            assert composite["u_glow_factor"].value == effect._glow_factor
            assert composite["u_glow_strength"].value == np.float32(state.glow_strength)
            assert composite["u_scatter_count"].value == effect._scatter_count
            assert composite["u_scatter_per_m"].value == np.float32(state.scatter_per_m)
            if state.glow_strength > 0.0:
                assert effect._programs["atmosphere/glow_down.frag"]["u_factor"].value == effect._glow_factor
                sigma = min(effect.glow_sigma_px / effect._glow_factor, atm.glow.MAX_BLUR_RADIUS / 3.0)
                for axis in (0, 1):
                    blur = effect._programs[("atmosphere/blur.frag", axis)]
                    assert blur["u_sigma_px"].value == np.float32(sigma)
                    assert blur["u_radius"].value == atm.glow.blur_radius(sigma)
    finally:
        kit.release(renderer)
