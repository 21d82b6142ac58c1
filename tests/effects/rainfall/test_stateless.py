"""rainfall without state: the GPU's drops are the NumPy twin's, at any time; the CPU's per-frame work does not
grow with the budget; bad input is refused at the boundary."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from rain_core import layout
from rain_core.effects.rainfall import RainfallSim, RainInput
from rain_core.effects.rainfall.constants import TIME_PERIOD_S
from rain_core.effects.rainfall.drops import time_split


def _street_effect(gl_ctx, shaders, rain, budget, t0=0.0):
    """A RainfallEffect driven directly (no Scene): the street's world, the ego car and a van, 100 km/h, gusty
    wind. Returns (effect, step(t) -> the update)."""
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.vehicles import VAN_SPEC, EgoCar, Vehicle
    from rain_core.world import build_world

    effect = RainfallEffect(gl_ctx, shaders=shaders, seed=5)
    world = build_world(seed=1)
    effect._ensure(budget, world)
    ego = EgoCar(position=np.array([layout.LANE_CENTRES_X[0], 0.0, layout.BRIDGE_Z_M + 60.0]), speed_m_s=27.8)
    van = Vehicle(VAN_SPEC, position=np.array([layout.LANE_CENTRES_X[1], 0.0, layout.BRIDGE_Z_M + 45.0]))

    def step(t, dt=1.0 / 30.0):
        ego.step(dt, 0.0, 0.0, 0.0)
        ego.speed_m_s = 27.8
        gust = 2.0 + 1.5 * math.sin(0.7 * t)
        eye = ego.position + np.array([-0.37, 1.2, 0.59])
        upd = effect.sim.advance(rain.input(t, pos=eye, vel=ego.velocity(), rate=28.0, wind=(gust, 0.0, -1.0),
                                            vehicles=(ego, van), forward=ego.forward(), puddles=0.5, wetness=1.0))
        effect._sync_table()
        effect.last_update = upd
        return upd, eye

    return effect, step


def _compare(effect, eye):
    shift = math.floor(eye[2] / layout.PERIOD_M) * layout.PERIOD_M
    gpu = effect.read_drops(shift, eye[2] - shift).astype(np.float64)
    twin = effect.sim.drops()
    p = twin["pos"].copy()
    p[:, 2] -= shift
    flags = twin["drawn"].astype(float) + 2.0 * twin["occluded"].astype(float)
    return gpu, p, flags, twin


def test_gpu_drops_are_the_twins_after_many_frames(gl_ctx, shaders, rain):
    """After 90 frames of driving under the bridge at 100 km/h in gusts, every instance's position (float32
    on the GPU, float64 in the twin), thinning and occlusion (roofs, the two vehicles, the ground) agree."""
    effect, step = _street_effect(gl_ctx, shaders, rain, 40_000)
    try:
        for i in range(90):
            upd, eye = step(i / 30.0)
        gpu, p, flags, twin = _compare(effect, eye)
        err = np.abs(gpu[:, :3] - p).max(axis=1)
        # A float32 rounding can put a drop on the other side of a wrap or a pass boundary: rare, allowed.
        assert np.mean(err < 2e-3) > 0.999, np.percentile(err, [50, 99, 99.99])
        assert np.mean(gpu[:, 3] == flags) > 0.999
        assert twin["drawn"].mean() > 0.5 and twin["occluded"].any() and not twin["occluded"].all()
        # The drops moved with the gusts: their horizontal velocity is the wind's (± the turbulence).
        assert np.allclose(np.median(twin["vel"][:, 0] / upd.wind_m_s[0]), 1.0)
    finally:
        effect.release()


@pytest.mark.parametrize("t0", [1e6, TIME_PERIOD_S * 3 - 1.0 / 60.0])
def test_large_times_keep_float32_precision(t0, gl_ctx, shaders, rain):
    """At t = 10⁶ s (and across an epoch of the GPU's clock) the GPU's drops still agree with the twin, and
    between two frames 1/60 s apart every drop that stayed in its pass moved by exactly its velocity × dt."""
    effect, step = _street_effect(gl_ctx, shaders, rain, 8_000)
    try:
        dt = 1.0 / 60.0
        step(t0 - dt, dt)
        upd, eye = step(t0, dt)
        gpu0, p0, _, twin0 = _compare(effect, eye)
        assert np.mean(np.abs(gpu0[:, :3] - p0).max(axis=1) < 2e-3) > 0.999
        upd, eye1 = step(t0 + dt, dt)
        gpu1, _, _, twin1 = _compare(effect, eye1)
        same = (twin0["cycle"] == twin1["cycle"]) & (np.abs(gpu1[:, 1] - gpu0[:, 1]) < 1.0)
        moved = gpu1[same, :3] - gpu0[same, :3]
        want = twin1["vel"][same] * dt
        ext = upd.boxes.ext[twin1["layer"][same]]
        miss = moved - want
        miss = miss - ext * np.round(miss / ext)  # a drop the moving box left behind re-enters at its far face
        assert same.sum() > 7000
        assert np.abs(miss).max() < 2e-4  # 0.2 mm of a 2–15 cm step
    finally:
        effect.release()


def test_time_split_is_exact():
    for t in (0.0, 1.5, TIME_PERIOD_S - 1e-9, 1e6 + 0.25, 3.0e9):
        whole, frac, epoch = time_split(t)
        assert 0 <= whole < TIME_PERIOD_S and 0.0 <= frac < 1.0
        assert epoch * TIME_PERIOD_S + whole + frac == pytest.approx(t, abs=1e-6 * max(1.0, t / 1e9))


def test_per_frame_work_does_not_grow_with_the_budget(rain):
    """The CPU's per-frame state is a handful of numbers: a frame's allocations are the same at 10k and 1M
    instances (memory, not wall time, so the test is exact on a busy machine)."""
    peaks = {}
    for budget in (10_000, 1_000_000):
        sim = RainfallSim(budget, seed=1)
        t = rain.drive(sim, 0.2, speed=27.8, rate=8.0, wind=(2.0, 0.0, 0.0))
        tracemalloc.start()
        for i in range(10):
            sim.advance(rain.input(t + (i + 1) / 60.0, pos=(1.75, 1.2, 600.0 - 27.8 * t), rate=8.0,
                                   wind=(2.0 + 0.1 * i, 0.0, 0.0)))
        peaks[budget] = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peaks[1_000_000] < peaks[10_000] + 64 * 1024, peaks


@pytest.mark.parametrize("field, value", [("container_m", 0.0), ("container_m", 1e9), ("density_scale", 1e9),
                                          ("density_scale", -1.0), ("rate_mm_h", float("nan")),
                                          ("wind_m_s", np.array([np.nan, 0.0, 0.0])),
                                          ("wind_m_s", np.array([0.0, 0.0, np.inf])), ("time_s", float("inf")),
                                          ("camera_position", np.array([0.0, np.nan, 0.0]))])
def test_bad_input_is_refused_at_the_boundary(field, value):
    """Out-of-range settings and non-finite inputs (a NaN wind would make NaN drops) get a ValueError naming
    the field; the effect's settings ranges are the same (rainfall.container_m 10–120 m, density_scale 0–4)."""
    good = dict(time_s=0.0, camera_position=np.array([1.75, 1.2, 600.0]), camera_forward=np.array([0.0, 0.0, -1.0]),
                camera_velocity=np.zeros(3), rate_mm_h=8.0)
    RainInput(**good)
    with pytest.raises(ValueError, match=field):
        RainInput(**{**good, field: value})


@pytest.mark.parametrize("capacity", [-1, 10**9, 2.5, True])
def test_bad_capacity_is_refused(capacity):
    with pytest.raises(ValueError, match="capacity"):
        RainfallSim(capacity)


def test_no_nan_drop_for_any_accepted_input(rain):
    sim = RainfallSim(5000, seed=1)
    for inp in (rain.input(0.0, rate=500.0, wind=(60.0, 0.0, -60.0), container_m=10.0, density_scale=4.0),
                rain.input(1e9, rate=1e-6, container_m=120.0, density_scale=0.0),
                rain.input(2e9, pos=(300.0, 50.0, -1e7), rate=8.0, forward=(0.0, -1.0, 0.0))):
        sim.reset()
        sim.advance(inp)
        d = sim.drops()
        for key in ("pos", "vel", "weight"):
            assert np.all(np.isfinite(d[key])), key
    assert isinstance(RainInput, type)


def test_unchecked_input_is_the_checked_one():
    """The effect's per-frame RainInput (built without re-checking values checked where they entered) holds the
    same fields as the checked constructor makes; a missing field is a TypeError, not a half-made input."""
    good = dict(time_s=2.0, camera_position=np.array([1.75, 1.2, 600.0]), camera_forward=np.array([0.0, 0.0, -1.0]),
                camera_velocity=np.array([0.0, 0.0, -27.8]), rate_mm_h=8.0, wind_m_s=np.array([2.0, 0.0, -1.0]),
                container_m=40.0, density_scale=1.0, splashes=True, wetness=0.5, puddles=0.25, vehicles=())
    checked, unchecked = RainInput(**good), RainInput.unchecked(**good)
    for name in good:
        np.testing.assert_array_equal(getattr(unchecked, name), getattr(checked, name))
    with pytest.raises(TypeError, match="unchecked"):
        RainInput.unchecked(**{k: v for k, v in good.items() if k != "wind_m_s"})


def test_camera_velocity_is_the_car_point_velocity(gl_ctx, shaders):
    """The driver camera's velocity: the car's at the camera point, with its yaw rate; across the period seam
    too (the camera and the car on either side of z = PERIOD_M). The vector formula it replaced is the twin."""
    from types import SimpleNamespace

    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.effects.rainfall.boxes import wrap_near
    from rain_core.settings import Settings
    from rain_core.vehicles import EgoCar

    effect = RainfallEffect(gl_ctx, shaders=shaders, seed=5)
    rng = np.random.default_rng(4)
    try:
        for _ in range(50):
            z = rng.choice([rng.uniform(-500.0, 500.0), layout.PERIOD_M + rng.uniform(-1.0, 1.0)])
            ego = EgoCar(position=np.array([rng.uniform(-6.0, 6.0), 0.0, z]), speed_m_s=rng.uniform(0.0, 40.0),
                         yaw=rng.uniform(-np.pi, np.pi))
            ego.yaw_rate_rad_s = rng.uniform(-0.5, 0.5)
            eye = ego.position + rng.uniform(-1.5, 1.5, 3)
            eye[2] = eye[2] + rng.choice([0.0, layout.PERIOD_M, -layout.PERIOD_M])
            frame = SimpleNamespace(settings=Settings(), ego=ego, camera=SimpleNamespace(position=eye))
            rel = eye - ego.position
            rel[2] = wrap_near(rel[2], 0.0)
            want = ego.velocity().copy()
            want[0] += ego.yaw_rate_rad_s * rel[2]
            want[2] -= ego.yaw_rate_rad_s * rel[0]
            np.testing.assert_array_equal(effect.camera_velocity(frame), want)
    finally:
        effect.release()
