"""Atmosphere light scattering (issue 9): the post pass against the dense single-scattering quadrature."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.effects import atmosphere as atm
from rain_core.lighting import Light, pack_lights
from rain_core.settings import Settings

LUMA = np.array([0.2126, 0.7152, 0.0722])


SIZE = (96, 64)
CAMERA = look_at((-3.0, 2.0, 604.0), (1.0, 2.5, 570.0), fov_y_deg=60.0)
# A down-lit street lamp, a sideways lamp and a low-beam headlight cone.
LAMP = Light(np.array([2.0, 6.0, 580.0]), np.array([0.0, -1.0, 0.0]), 6000.0, np.ones(3),
             math.cos(math.radians(75)), math.cos(math.radians(55)), 70.0)
SIDE_LAMP = Light(np.array([-4.0, 3.0, 575.0]), np.array([1.0, 0.0, 0.0]), 3000.0, np.array([1.0, 0.8, 0.6]),
                  math.cos(math.radians(75)), math.cos(math.radians(55)), 70.0)
LOW_BEAM = Light(np.array([1.0, 0.7, 590.0]), np.array([0.0, -0.026, -1.0]) / np.linalg.norm([0.0, -0.026, -1.0]),
                 20000.0, np.array([1.0, 0.96, 0.88]), math.cos(math.radians(30)), math.cos(math.radians(12)),
                 150.0, low_beam=True)


@pytest.fixture
def float32_frame(monkeypatch):
    """The renderer's HDR frame in float32 instead of half floats, so that changes as small as the skip budgets
    show."""
    from rain_core.gfx import renderer as renderer_module

    half = renderer_module.float_target
    monkeypatch.setattr(renderer_module, "float_target",
                        lambda ctx, size, components=4, dtype="f2", **kw: half(ctx, size, components, "f4", **kw))


def _render_lit(gl_ctx, shaders, kit, lights, hour, *, scale=1.0, skip=None, relative=None, glow=0.0, out=None,
                near_box=False):
    """The pre-exposed HDR image (bottom row first) of a far box under ``lights`` alone, in 20 mm/h rain at
    ``hour``, ``glow`` (the setting; 0: none), ``scale`` × the light scattering; ``skip`` and ``relative``: the
    effect's scatter_skip and scatter_skip_relative (None: its own). Returns (image, the effect's state, the render
    context); ``out`` (a dict) also gets the glow target's alpha ("kept", bottom row first) and "factor";
    ``near_box``: a dark box in view too, 20 m ahead (edges against the sky)."""
    parts = [kit.box((0.0, -50.0, -3000.0), (1.0, 1.0, 1.0), (0.1, 0.1, 0.1))]
    if near_box:
        parts.append(kit.box((0.0, 2.0, 585.0), (3.0, 2.0, 1.0), (0.02, 0.02, 0.02)))
    world = kit.world(parts)
    settings = Settings()
    settings.atmosphere.glow = glow
    settings.atmosphere.light_scattering = scale
    r = kit.renderer(gl_ctx, shaders, world, SIZE)
    if skip is not None:
        r.effects[0].scatter_skip = skip
    if relative is not None:
        r.effects[0].scatter_skip_relative = relative
    original = r.render_context

    def with_lights(frame, *args, **kwargs):
        rc = original(frame, *args, **kwargs)
        rc.lights = pack_lights(lights)  # our lights, no vehicles needed
        return rc

    r.render_context = with_lights
    frame = kit.frame(CAMERA, world, settings, 20.0, hour)
    r.render(frame)
    image = kit.bottom_first(r)[0]
    state, rc = r.effects[0].state, r.render_context(frame)
    if out is not None:
        glow_target = r.effects[0]._targets[2][0]
        w, h = glow_target.color.size
        texels = np.frombuffer(glow_target.color.read(), dtype=np.float16).reshape(h, w, 4)
        out.update(kept=texels[..., 3].astype(np.float64), factor=r.effects[0]._glow_factor)
    kit.release(r)
    return image, state, rc


def test_light_scattering_matches_single_scattering_reference(gl_ctx, shaders, kit):
    """A down-lit street lamp, a sideways lamp and a low-beam headlight cone against the dense quadrature."""
    lights = [LAMP, SIDE_LAMP, LOW_BEAM]
    dark, _, _ = _render_lit(gl_ctx, shaders, kit, lights, 22.0, scale=0.0)
    lit_image, state, rc = _render_lit(gl_ctx, shaders, kit, lights, 22.0)
    shader = (lit_image - dark)[1::3, 1::3]  # every third pixel: the reference is dense and slow
    _, dirs = atm.pixel_distances(np.ones(SIZE[::-1]), rc.view_proj, rc.camera_position)
    ref = sum(atm.light_inscatter_reference(rc.camera_position, dirs[1::3, 1::3], atm.SCATTER_MAX_M, light,
                                            state.extinction_per_m, state.scatter_per_m, n=4000)
              for light in lights) * rc.frame.lighting.exposure
    y_ref, y_gl = ref @ LUMA, shader @ LUMA
    lit = y_ref > 0.01 * y_ref.max()
    assert lit.mean() > 0.1  # the cones cover a good part of the frame …
    assert (~lit).mean() > 0.05  # … but not all of it (the headlight cone is clipped)
    rel = np.abs(y_gl[lit] - y_ref[lit]) / y_ref[lit]
    assert np.median(rel) < 0.04 and np.percentile(rel, 98) < 0.10
    assert np.abs(y_gl[~lit]).max() < 0.02 * y_ref.max()


def test_skipped_lights_change_no_pixel_by_more_than_the_skip_budget(gl_ctx, shaders, kit, float32_frame):
    """The composite skips a light whose bound on its quadrature fits in what is left of the pixel's budget
    (``scatter_skip``, SCATTER_SKIP of exposed radiance): at noon, away from the beams, lights are skipped (pixels
    change), and none changes by more than the budget. A float32 target, so that changes this small show."""
    from rain_core.effects.atmosphere.scattering import SCATTER_SKIP
    exact, skipped, exact_again = (
        _render_lit(gl_ctx, shaders, kit, [LAMP, LOW_BEAM], 12.0, skip=skip, relative=0.0)[0]
        for skip in (0.0, SCATTER_SKIP, 0.0))
    np.testing.assert_array_equal(exact_again, exact)  # the budget is the effect's: set back, nothing skipped
    change = np.abs(skipped - exact)
    assert (change > 0).mean() > 0.05  # lights were skipped
    assert change.max() <= SCATTER_SKIP


def test_each_glow_block_holds_the_least_light_its_pixels_keep(gl_ctx, shaders, kit):
    """The glow's first step writes, per block of its pixels, the least light a pixel keeps after the composite
    (its dimmest channel × (1 − k·w)), and the blur carries it through: all of it without a halo (k = 0), less
    with one, never more than the darkest pixel of the block (the sky's edge against the box included)."""
    # Nothing traced and no glow: no post pass, the scene as the composite finds it.
    pre = _render_lit(gl_ctx, shaders, kit, [LAMP, LOW_BEAM], 12.0, scale=0.0, near_box=True)[0]
    for glow in (0.0, 1.0):
        out = {}
        _render_lit(gl_ctx, shaders, kit, [LAMP, LOW_BEAM], 12.0, glow=glow, out=out, near_box=True)
        f, kept = out["factor"], out["kept"]
        h, w = kept.shape
        dim = np.full((h * f, w * f), np.inf)
        dim[:SIZE[1], :SIZE[0]] = pre.min(axis=-1)
        block_min = dim.reshape(h, f, w, f).min(axis=(1, 3))
        assert f > 1 and np.ptp(block_min) > 0.1 * block_min.max()  # blocks of several pixels, sky and box
        if glow == 0.0:
            np.testing.assert_allclose(kept, block_min, rtol=2.0**-11)  # (a half float's rounding)
        else:
            assert np.all(kept <= block_min * (1.0 + 2.0**-11))
            assert (kept < 0.99 * block_min).mean() > 0.5  # the halo's share moved away


@pytest.mark.parametrize("glow", [0.0, 1.0])
def test_lights_skipped_for_a_share_of_the_pixels_own_light_change_it_by_at_most_that_share(
        gl_ctx, shaders, kit, float32_frame, glow):
    """On top of the fixed budget, a light is skipped when its bound fits in ``scatter_skip_relative`` of the light
    the pixel keeps (its glow block's least, the dimmest channel): no pixel changes by more than the fixed budget
    plus that share of its own value, and more pixels skip than with the fixed budget alone (by day the pixels
    are bright). With the glow drawn or not (then its first step runs for the share alone)."""
    from rain_core.effects.atmosphere.scattering import SCATTER_SKIP, SCATTER_SKIP_RELATIVE
    exact, fixed, shared = (
        _render_lit(gl_ctx, shaders, kit, [LAMP, LOW_BEAM], 12.0, skip=skip, relative=relative, glow=glow)[0]
        for skip, relative in ((0.0, 0.0), (SCATTER_SKIP, 0.0), (SCATTER_SKIP, SCATTER_SKIP_RELATIVE)))
    change = np.abs(shared - exact)
    allowed = SCATTER_SKIP + SCATTER_SKIP_RELATIVE * exact.min(axis=-1, keepdims=True)
    assert np.all(change <= allowed * (1.0 + 1e-5))
    assert (change > 0).mean() > (np.abs(fixed - exact) > 0).mean() + 0.05  # the share skips more
    assert change.max() > SCATTER_SKIP  # … lights the fixed budget alone would have traced


def test_the_pixels_share_is_a_quarter_step_where_the_tone_map_is_steepest():
    """SCATTER_SKIP_RELATIVE: a relative change of the exposed radiance by that share moves a displayed 8-bit
    value by at most a quarter of a step, wherever the value lies on the tone map's curve (shaders/core/
    tonemap.frag: the ACES fit, then sRGB; the exposure's stops scale L and leave L·dV/dL as it is)."""
    from rain_core.effects.atmosphere.scattering import SCATTER_SKIP_RELATIVE

    L = np.logspace(-7.0, 4.0, 400_001)
    aces = np.clip((L * (2.51 * L + 0.03)) / (L * (2.43 * L + 0.59) + 0.14), 0.0, 1.0)
    shown = 255.0 * np.where(aces < 0.0031308, 12.92 * aces, 1.055 * aces ** (1.0 / 2.4) - 0.055)
    steps_per_relative_change = np.gradient(shown, np.log(L))  # L·dV/dL
    steepest = steps_per_relative_change.max()
    assert 72.0 < steepest < 74.0
    assert SCATTER_SKIP_RELATIVE * steepest <= 0.25
    assert SCATTER_SKIP_RELATIVE * steepest > 0.24  # … and not far below it: the skips it allows are not wasted
