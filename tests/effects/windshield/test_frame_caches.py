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

    def record(which, rows):  # the rows each splat buffer is written with, as float32 bits
        drawn[which] = np.frombuffer(np.ascontiguousarray(rows).tobytes(), np.float32).copy()
        return len(rows)

    effect._write_splats = record
    return s, effect, scene, drawn


def _bits(rows) -> np.ndarray:
    return np.frombuffer(np.ascontiguousarray(rows, dtype=None).tobytes(), np.float32)


def test_the_rows_update_makes_are_those_of_the_glass_the_water_pass_draws(gl_ctx, shaders):
    s, effect, scene, drawn = _wet_scene(gl_ctx, shaders)

    def next_frame():  # a step of the scene (rain arriving: splashes to draw) and its render context
        scene.step(1 / 30, _Brake)
        frame = scene.frame()
        return frame, scene.renderer.render_context(frame)

    # As the renderer runs them: update makes the rows, the upload writes them, the water pass draws them.
    frame, rc = next_frame()
    effect.update(frame, rc)
    effect.render("upload", rc)
    assert effect.sim.count > 10
    assert np.array_equal(drawn[1], _bits(drop_splats(effect.sim)))
    texel_m = max(effect.glass.width_bottom, effect.glass.height) / 256
    assert np.array_equal(drawn[0], _bits(FilmRows().rows(effect.sim, texel_m)))
    drawn.clear()
    effect.render("prepare", rc)
    assert not drawn  # the water pass draws what the upload wrote: nothing is written twice
    # The water pass asked without the upload (a benchmark, a test) writes the rows itself; a drop added after
    # update: the rows made before it are not drawn.
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


def test_moved_inputs_are_the_constructors_and_are_checked():
    import math

    import pytest

    from rain_core.effects.windshield import GlassInputs

    base = GlassInputs.for_speed(50.0, 4.0, wiper_mode="low", drop_budget=3000, blade_wear=0.5)
    yaw = 0.3
    rot = np.array([[math.cos(yaw), 0.0, math.sin(yaw)], [0.0, 1.0, 0.0], [-math.sin(yaw), 0.0, math.cos(yaw)]])
    vel, wind = np.array([-3.0, 0.0, -20.0]), [1.5, 0.0, -0.5]
    moved = base.moved(6.0, vel, wind, rot, True)
    made = GlassInputs(rate_mm_h=6.0, car_velocity_m_s=vel, wind_m_s=wind, car_rotation=rot, sheltered=True,
                       **{k: getattr(base, k) for k in ("drop_scale", "drop_budget", "wiper_mode", "wiper_interval_s",
                                                        "wiper_low_cpm", "wiper_high_cpm", "wiper_sensitivity",
                                                        "blade_wear")})
    for name in GlassInputs.__dataclass_fields__:
        a, b = getattr(moved, name), getattr(made, name)
        assert type(a) is type(b) and np.array_equal(a, b), name
    assert not moved.car_velocity_m_s.flags.writeable and moved.car_velocity_m_s is not vel
    assert base.car_velocity_m_s[2] < -13.0  # (the one it was made from is as it was)
    for bad in [dict(rate_mm_h=-1.0), dict(car_velocity_m_s=[0.0, 0.0, 1e4]), dict(wind_m_s=[math.nan, 0.0, 0.0]),
                dict(car_rotation=2.0 * rot), dict(sheltered="yes")]:
        args = dict(rate_mm_h=6.0, car_velocity_m_s=vel, wind_m_s=wind, car_rotation=rot, sheltered=False) | bad
        with pytest.raises(ValueError):
            base.moved(**args)


def test_the_inputs_of_a_moving_car_follow_the_settings_changed_live(gl_ctx, shaders):
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = 8.0
    s.wipers.mode = "low"
    effect = WindshieldEffect(gl_ctx, s, seed=4, shaders=shaders)
    scene = Scene(gl_ctx, (64, 36), s, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = 20.0
    scene.autopilot.target_speed_m_s = 20.0

    def inputs():
        scene.step(1 / 30)
        return effect.inputs_for(scene.frame())

    first, second = inputs(), inputs()
    assert second is not first and second.wiper_mode == "low"  # made from the first (the car moved)
    assert not np.array_equal(first.car_velocity_m_s, second.car_velocity_m_s) or first.rate_mm_h != 0
    s.wipers.mode = "high"
    s.windshield.drop_budget = 1234
    third = inputs()
    assert third.wiper_mode == "high" and third.drop_budget == 1234
    s.wipers.blade_wear = 0.7
    assert inputs().blade_wear == 0.7 and inputs().wiper_mode == "high"
    scene.release()
