"""What the windshield effect keeps from one call to the next within a frame (rain_core.effects.windshield.effect,
water_pass): each must be dropped when what it was made from changes."""

import numpy as np

from rain_core.effects.windshield import WindshieldEffect, drop_mass
from rain_core.effects.windshield.splats import FilmRows, drop_splats
from rain_core.settings import Settings


class _Brake:
    throttle, brake, steer, reverse = 0.0, 1.0, 0.0, False


def _wet_scene(gl_ctx, shaders):
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = 16.0
    s.wipers.mode = "low"
    s.quality.windshield_resolution = 256
    effect = WindshieldEffect(gl_ctx, s, seed=4, shaders=shaders)
    scene = Scene(gl_ctx, (96, 54), s, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = 0.0
    for _ in range(6):
        scene.step(1 / 30, _Brake)
        scene.render()
    drawn = {}

    def record(which, rows):  # the rows each splat draw uploads, as float32 bits
        drawn[which] = np.frombuffer(np.ascontiguousarray(rows).tobytes(), np.float32).copy()

    effect._draw_splats = record
    return s, effect, scene, drawn


def _bits(rows) -> np.ndarray:
    return np.frombuffer(np.ascontiguousarray(rows, dtype=None).tobytes(), np.float32)


def test_the_rows_update_makes_are_those_of_the_glass_the_water_pass_draws(gl_ctx, shaders):
    s, effect, scene, drawn = _wet_scene(gl_ctx, shaders)

    def next_frame():  # a step of the scene (rain arriving: splashes to draw) and its render context
        scene.step(1 / 30, _Brake)
        frame = scene.frame()
        return frame, scene.renderer.render_context(frame)

    # As the renderer runs them: update makes the rows, the water pass draws them.
    frame, rc = next_frame()
    effect.update(frame, rc)
    effect.render("prepare", rc)
    assert effect.sim.count > 10
    assert np.array_equal(drawn[1], _bits(drop_splats(effect.sim)))
    texel_m = max(effect.glass.width_bottom, effect.glass.height) / 256
    assert np.array_equal(drawn[0], _bits(FilmRows().rows(effect.sim, texel_m)))
    # A drop added between the two: the rows made before it are not drawn.
    frame, rc = next_frame()
    effect.update(frame, rc)
    g = effect.glass
    effect.sim._append(g.from_uv(np.array([[0.5, 0.5]])), np.zeros((1, 2)), drop_mass(np.array([2e-3])))
    effect.render("prepare", rc)
    assert np.array_equal(drawn[1], _bits(drop_splats(effect.sim)))
    assert len(drawn[1]) == 5 * effect._drop_rows
    # The resolution changed in the panel between the two: the film deposits are made for the new texels.
    frame, rc = next_frame()
    effect.update(frame, rc)
    s.quality.windshield_resolution = 64
    effect.render("prepare", rc)
    texel_m = max(effect.glass.width_bottom, effect.glass.height) / 64
    want = _bits(FilmRows().rows(effect.sim, texel_m))
    assert len(want) and np.array_equal(drawn[0], want)
    assert not np.array_equal(want, _bits(FilmRows().rows(effect.sim, texel_m / 4)))  # (the texels matter)
    # Another render context (another frame) does not take what update made for the last one.
    frame, rc = next_frame()
    effect.update(frame, rc)
    other = scene.renderer.render_context(frame)
    effect._early = (other, *effect._early[1:])
    effect.sim._append(g.from_uv(np.array([[0.3, 0.4]])), np.zeros((1, 2)), drop_mass(np.array([2e-3])))
    effect.sim.version -= 1  # (as if the drops had not changed: only the context tells the rows apart)
    effect.render("prepare", rc)
    assert np.array_equal(drawn[1], _bits(drop_splats(effect.sim)))
    scene.release()


def test_the_blade_angles_kept_follow_the_wipers():
    from rain_core.effects.windshield import GlassInputs, WindshieldSim

    sim = WindshieldSim(seed=1)
    inputs = GlassInputs.for_speed(0.0, 4.0, wiper_mode="high")
    seen = set()
    for _ in range(40):
        sim.step(1 / 30, inputs)
        want = [float(b.angle(sim.wipers.progress)) for b in sim.blades]
        assert sim.blade_angles() == want
        assert sim.blade_angles() == want  # (asked twice a frame: the kept ones)
        seen.add(tuple(want))
    assert len(seen) > 20  # the blades moved
