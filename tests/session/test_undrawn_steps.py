"""Steps nobody looks at (``Session.step(draw=False)``): the simulations, and what the GPU holds of them, advance
exactly as in drawn steps; only the picture is not made. A headless run that keeps only a screenshot draws its
last frame alone."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from tests.session.conftest import cheap_settings

SIZE = (64, 40)
STEPS = 8
DT_S = 1 / 30
LAST_DRAWN = [False] * (STEPS - 1) + [True]  # a screenshot run's pattern
MIXED = [True, False, True, False, False, True, False, True]


def wet_settings(**values):
    """Heavy rain on a wet road with puddles: every effect with state (spray rings, the windshield's film
    texture, the ripples) runs."""
    return cheap_settings(**{"rain.rate_mm_h": 8.0, "rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 1.0,
                             **values})


def stepped(session, draws, backend, **values):
    sim = session(settings=wet_settings(**values), seed=5)
    for effect in sim.scene.effects:
        if effect.name == "ripples":
            effect.backend = backend  # not "auto": its timing could pick either on two sessions
    for draw in draws:
        sim.step(DT_S, draw=draw)
    return sim


@pytest.mark.parametrize("backend", ["numpy32", "gpu"])
@pytest.mark.parametrize("draws", [LAST_DRAWN, MIXED], ids=["last-drawn", "mixed"])
def test_undrawn_steps_leave_the_same_last_picture(session, backend, draws):
    # Without the automatic exposure (the one thing a drawn frame adds to the state: the eye's adaptation), the
    # last picture is the same to the bit whether the steps before it were drawn or not, in any order.
    drawn = stepped(session, [True] * STEPS, backend, **{"camera.auto_exposure": False})
    undrawn = stepped(session, draws, backend, **{"camera.auto_exposure": False})
    a, b = drawn.capture().rgb, undrawn.capture().rgb
    assert a.std() > 2.0
    assert np.array_equal(a, b)
    glass = [effect(s, "windshield").sim for s in (drawn, undrawn)]
    assert glass[0].count == glass[1].count > 0
    spray = effect(undrawn, "spray")  # its GPU rings hold what its CPU rings hold
    for ring, buffer in zip(spray.emitter.rings, spray._buffers, strict=True):
        assert ring.capacity and buffer.read() == ring.data.tobytes()


def effect(sim, name):
    return next(e for e in sim.scene.effects if e.name == name)


def test_an_undrawn_step_changes_the_picture_it_is_followed_by(session):
    # The test above would pass if undrawn steps did nothing and the drawn one did all: one undrawn step fewer
    # (the same drawn frame a step earlier) is another picture.
    off = {"camera.auto_exposure": False}
    full = stepped(session, [False] * (STEPS - 1) + [True], "numpy32", **off).capture().rgb
    short = stepped(session, [False] * (STEPS - 2) + [True], "numpy32", **off).capture().rgb
    assert not np.array_equal(full, short)


def test_the_eye_adapts_over_the_undrawn_time(session):
    from rain_core.exposure import adapt, target_correction_ev

    sim = stepped(session, [True], "numpy32")
    renderer = sim.scene.renderer
    before = renderer.exposure.read_ev()
    for _ in range(5):
        sim.step(DT_S, draw=False)
    assert renderer.exposure.read_ev() == before  # undrawn: the eye saw nothing
    sim.step(DT_S)
    tau = sim.settings.camera.adaptation_s
    want = adapt(before, target_correction_ev(renderer.exposure.read_meter()), 6 * DT_S, tau)
    assert renderer.exposure.read_ev() == pytest.approx(want, abs=1e-4)


def test_capture_after_an_undrawn_step_refuses_and_bad_draw_is_named(session):
    sim = stepped(session, [True, False], "numpy32")
    with pytest.raises(ValueError, match="not drawn"):
        sim.capture()
    with pytest.raises(ValueError, match="draw must be True or False"):
        sim.step(DT_S, draw="no")
    sim.step(DT_S)
    assert sim.capture().rgb.shape == (SIZE[1], SIZE[0], 3)


def test_offline_quality_undrawn_steps_advance_in_the_same_sub_steps(session):
    off = {"camera.auto_exposure": False}
    pictures = []
    for draws in ([True] * 3, [False, False, True]):
        sim = session(settings=wet_settings(**off), seed=5)
        for effect in sim.scene.effects:
            if effect.name == "ripples":
                effect.backend = "numpy32"
        for draw in draws:
            sim.step(DT_S, subframes=3, draw=draw)
        pictures.append(sim.capture().rgb)
    assert np.array_equal(*pictures)


def test_a_screenshot_run_draws_only_its_last_frame(tmp_path, monkeypatch):
    from app import headless
    from rain_core.gfx.renderer import Renderer
    from rain_core.settings import Settings, set_value

    draws = []
    render = Renderer.render
    monkeypatch.setattr(Renderer, "render", lambda self, frame, draw=True: (draws.append(draw),
                                                                            render(self, frame, draw)))
    settings = Settings()
    for key, value in {"quality.ripple_grid": 64, "quality.windshield_resolution": 128, "spray.budget": 3000,
                       "windshield.drop_budget": 1000, "traffic.count": 1}.items():
        set_value(settings, key, value)
    shot = tmp_path / "shot.png"
    args = SimpleNamespace(size=SIZE, seed=1, fps=10.0, seconds=0.5, record=None, labels=False, screenshot=shot,
                           panel=False)
    assert headless.run_headless(args, settings) == 0
    assert draws == [False] * 4 + [True] and shot.stat().st_size > 0
