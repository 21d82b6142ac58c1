"""The render path's per-frame shortcuts give what the plain computations give: draw items (kept for a frame) equal
the draw list, the lights chosen from cached candidates are the nearest, the lighting of an hour is one read-only
object, and an effect's observe is timed with its passes only while it runs."""

import numpy as np
import pytest

from rain_core import layout
from rain_core.gfx.effect import Effect
from rain_core.gfx.uniforms import mat4_bytes
from rain_core.lighting import (
    MAX_LIGHTS,
    light_candidates,
    light_set_for_frame,
    lighting_for_hour,
    lights_for_frame,
    nearest_lights,
    pack_lights,
    pack_nearest,
)
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

SIZE = (64, 36)


def _scene(gl_ctx, camera="driver", hour=12.0, effects=None, traffic=None):
    settings = Settings()
    set_value(settings, "camera.mode", camera)
    set_value(settings, "time_of_day.hour", hour)
    if traffic is not None:
        set_value(settings, "traffic.count", traffic)
    return Scene(gl_ctx, SIZE, settings=settings, seed=3, gpu_timing=False,
                 effects=[] if effects is None else effects)


@pytest.mark.parametrize("camera", ["driver", "chase"])
def test_draw_items_are_the_draw_list_inside_and_outside_a_frame(gl_ctx, camera):
    scene = _scene(gl_ctx, camera)
    try:
        scene.step(1 / 30)
        frame = scene.frame()
        drawer = scene.renderer.scene
        rc = scene.renderer.render_context(frame)
        for cabin in (True, False):
            plain = [(m, mat4_bytes(model), share) for m, model, share in drawer.draw_list(rc, cabin)]
            assert drawer.draw_items(rc, cabin) == plain  # outside a frame: computed
            drawer.begin_frame()
            try:
                first = drawer.draw_items(rc, cabin)
                assert first == plain and drawer.draw_items(rc, cabin) is first  # kept for the frame
            finally:
                drawer.end_frame()
        assert len(drawer.draw_items(rc, True)) != len(drawer.draw_items(rc, False)) or camera == "chase"
    finally:
        scene.release()


def test_nearest_of_the_candidates_are_the_lights_of_the_frame(gl_ctx):
    scene = _scene(gl_ctx, hour=22.0, traffic=12)
    try:
        rng = np.random.default_rng(5)
        for _ in range(5):
            scene.step(0.5)
            frame = scene.frame()
            cam = np.asarray(frame.camera.position) + rng.uniform(-3.0, 3.0, 3)
            shift = np.floor(cam[2] / layout.PERIOD_M) * layout.PERIOD_M
            wrapped = cam - [0.0, 0.0, shift]
            cand = light_candidates(scene.world.lamps, frame.vehicles, float(wrapped[2]), frame.lighting, shift,
                                    layout.PERIOD_M, True)
            assert len(cand) > MAX_LIGHTS  # a street at night with traffic: more lights than the shader takes
            chosen = nearest_lights(cand, wrapped)
            d_all = np.sort(np.sum((cand.position - wrapped) ** 2, axis=1))
            d_chosen = np.sum((chosen.position - wrapped) ** 2, axis=1)
            np.testing.assert_array_equal(d_chosen, d_all[:MAX_LIGHTS])  # the nearest, nearest first
            packed = pack_lights(light_set_for_frame(scene.world.lamps, frame.vehicles, cam, frame.lighting,
                                                     shift, layout.PERIOD_M, True))
            assert packed == pack_lights(lights_for_frame(scene.world.lamps, frame.vehicles, cam, frame.lighting,
                                                          shift, layout.PERIOD_M, True))
            # The renderer's path: the nearest gathered from rows packed once per candidate set, asked twice
            # (main and mirror view): the same bytes; also with fewer candidates than slots and with none.
            assert pack_nearest(cand, wrapped) == pack_nearest(cand, wrapped) == pack_lights(chosen)
            few = cand.take(np.arange(5))
            assert pack_nearest(few, wrapped) == pack_lights(nearest_lights(few, wrapped))
            none = cand.take(np.arange(0))
            assert pack_nearest(none, wrapped) == pack_lights(none)
    finally:
        scene.release()


def _vehicle_lights_stacked(vehicles, shift_z):
    """The vehicles' head and tail lights as light_candidates built them with np.stack (the twin)."""
    import math

    from rain_core.lighting import _vehicle_table
    from rain_core.vehicles import HEADLIGHT_PITCH_RAD

    n = len(vehicles)
    local = _vehicle_table(vehicles)[0]
    yaw = np.fromiter((v.yaw for v in vehicles), dtype=np.float64, count=n)
    centre = np.array([v.position for v in vehicles], dtype=np.float64).reshape(n, 3)
    c, s_ = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    lx, ly, lz = local[..., 0], local[..., 1], local[..., 2]
    pos = np.stack([c * lx + s_ * lz + centre[:, None, 0], ly + centre[:, None, 1],
                    -s_ * lx + c * lz + centre[:, None, 2]], axis=-1).reshape(4 * n, 3)
    pos[:, 2] -= shift_z
    fwd = np.stack([-np.sin(yaw), np.zeros(n), -np.cos(yaw)], axis=1)
    head_dir = fwd * math.cos(HEADLIGHT_PITCH_RAD) + np.array([0.0, math.sin(HEADLIGHT_PITCH_RAD), 0.0])
    return pos, np.stack([head_dir, head_dir, -fwd, -fwd], axis=1).reshape(4 * n, 3)


def test_vehicle_lights_are_the_stacked_formulas_bit_for_bit(gl_ctx, kernel_path):
    """Both paths (lighting_kernels.vehicle_lights and its NumPy twin) give the stacked formulas' bits."""
    scene = _scene(gl_ctx, hour=12.0, traffic=9)
    try:
        rng = np.random.default_rng(11)
        for step in range(5):
            scene.step(0.3)
            frame = scene.frame()
            for vehicle in frame.vehicles[1:]:
                vehicle.yaw = float(rng.uniform(-np.pi, np.pi))  # every heading, not just along the street
            if step == 4:  # signed zeros: yaw ±0.0 (sin ±0.0), a car at x = −0.0, one heading +z
                frame.vehicles[1].yaw = -0.0
                frame.vehicles[3].yaw = 0.0
                frame.vehicles[2].yaw = np.pi
                frame.vehicles[1].position = np.array([-0.0, 0.0, -0.0])
            shift = float(rng.choice([0.0, layout.PERIOD_M, -2.0 * layout.PERIOD_M]))
            cand = light_candidates([], frame.vehicles, 0.0, frame.lighting, shift, layout.PERIOD_M, True)
            pos, dirs = _vehicle_lights_stacked(frame.vehicles, shift)
            assert cand.position.tobytes() == pos.tobytes() and cand.direction.tobytes() == dirs.tobytes()
    finally:
        scene.release()


def test_lighting_of_an_hour_is_one_read_only_object():
    a, b = lighting_for_hour(12.0, 0.25), lighting_for_hour(12.0, 0.25)
    assert a is b and lighting_for_hour(12.0, 0.5) is not a
    with pytest.raises(ValueError):
        a.sun_direction[0] = 0.0
    with pytest.raises(ValueError, match="hour"):
        lighting_for_hour(float("nan"))


class _Watcher(Effect):
    """Observes every frame; runs only while ``on``."""

    name = "watcher"

    def __init__(self):
        self.on = False
        self.seen = 0

    def observe(self, frame):
        self.seen += 1

    def active(self, frame):
        return self.on


def test_observe_is_timed_with_its_effect_only_while_it_runs(gl_ctx):
    watcher = _Watcher()
    scene = _scene(gl_ctx, effects=[watcher])
    try:
        scene.step(1 / 30)
        scene.render()
        rows = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
        assert watcher.seen == 1 and rows["watcher"] is False and "watcher.observe" not in rows
        watcher.on = True
        scene.render()
        rows = {name: ran for name, ran, *_ in scene.renderer.pass_table()}
        assert watcher.seen == 2 and rows["watcher.observe"] is True and rows["watcher.update"] is True
        assert "watcher" not in rows
    finally:
        scene.release()


def test_mirror_views_keep_their_own_programs_values_across_live_changes(gl_ctx):
    """The mirror views (the road's reflection, the door mirrors) draw with a scene program of their own that keeps
    its values between frames: a frame drawn again after the road and the mirrors were switched off and on live
    is the frame drawn the first time, and the frame a fresh renderer draws."""
    import dataclasses

    from rain_core.effects.road import RoadEffect
    from rain_core.gfx.renderer import Renderer

    def settings(**values):
        s = Settings()
        for path, value in {"time_of_day.hour": 12.0, "camera.auto_exposure": False, "traffic.count": 2,
                            "camera.driver_fov_deg": 70.0, "rain.wetness": 1.0, "rain.puddles": 1.0,
                            **values}.items():
            set_value(s, path, value)
        return s

    wet = settings()
    scene = Scene(gl_ctx, (320, 180), settings=wet, seed=2, gpu_timing=False, effects=[RoadEffect(gl_ctx, wet)])
    fresh = None
    try:
        for _ in range(3):
            scene.step(1 / 30)
        frame = scene.frame()
        renderer = scene.renderer
        renderer.render(frame)
        first = renderer.hdr_image()
        assert {s.name: s.ran for s in renderer.stats}["mirrors"]  # a door mirror drawn, and the reflection
        for off in ({"road.enabled": False}, {"camera.mirrors": False}, {"road.reflections": False}):
            renderer.render(dataclasses.replace(frame, settings=settings(**off)))
            assert np.abs(renderer.hdr_image() - first).max() > 0.0
            renderer.render(frame)
            np.testing.assert_array_equal(renderer.hdr_image(), first)
        fresh = Renderer(gl_ctx, (320, 180), scene.world, effects=[RoadEffect(gl_ctx, wet)], gpu_timing=False)
        fresh.render(frame)
        np.testing.assert_array_equal(fresh.hdr_image(), first)
    finally:
        if fresh is not None:
            fresh.release()
        scene.release()


def _random_lights(rng, count):
    from rain_core.lighting import LightSet

    return LightSet(rng.normal(size=(count, 3)) * rng.uniform(1.0, 100.0), rng.normal(size=(count, 3)),
                    rng.uniform(0.0, 1000.0, count), rng.uniform(0.0, 1.0, (count, 3)), rng.uniform(0.0, 1.0, count),
                    rng.uniform(0.0, 1.0, count), rng.uniform(1.0, 50.0, count), rng.random(count) < 0.5)


def test_pack_nearest_is_pack_lights_of_the_nearest(kernel_path):
    """Both paths of pack_nearest (lighting_kernels.gather_nearest and its NumPy twin) give pack_lights' bytes of
    nearest_lights, ties (lamps mirrored across the street, repeated positions) in index order; the kernel's
    reused buffer leaves nothing of a longer list behind."""
    rng = np.random.default_rng(21)
    for count in (0, 1, 2, 5, 31, 32, 33, 60, 200, 3):
        for trial in range(12):
            lights = _random_lights(rng, count)
            if count > 4 and trial % 2:
                lights.position[1::2] = lights.position[0::2][: count // 2] * [-1.0, 1.0, 1.0]
            camera = rng.normal(size=3) * 20.0
            camera[0] = 0.0  # on the mirror line: equal distances
            for slots in (MAX_LIGHTS, 8, 1):
                expected = pack_lights(nearest_lights(lights, camera, slots), slots)
                assert pack_nearest(lights, camera, slots) == expected
