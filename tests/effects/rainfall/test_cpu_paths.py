"""rainfall's per-frame CPU paths (issue 13): the cached and packed forms equal what they replace."""

from __future__ import annotations

import dataclasses
import struct
from types import SimpleNamespace

import numpy as np

from rain_core import layout
from rain_core.effects.rainfall.box_uniforms import box_pairs, splash_box_pairs
from rain_core.effects.rainfall.boxes import box_heights, layer_boxes, wrap_near
from rain_core.effects.rainfall.constants import (
    BOX_BOTTOM_Y_M,
    FADE_FRACTION,
    FORWARD_OFFSET,
    GROUND_Y_M,
    LAYER_PROFILE,
    LAYER_SCALES,
    MAX_VEHICLES,
    SPLASH_LAYER,
    TIME_PERIOD_S,
    TOP_PAD_M,
    TOP_SLOPE,
)
from rain_core.effects.rainfall.drops import time_split
from rain_core.effects.rainfall.effect import RainfallEffect
from rain_core.effects.rainfall.rain_block import RAIN_FRAME_BINDING, RAIN_FRAME_BYTES
from rain_core.effects.rainfall.sim import RainfallSim
from rain_core.effects.rainfall.vehicle_fate import (
    PIECES_PER_VEHICLE,
    PLANES_PER_PIECE,
    cull_vehicles,
    piece_volumes,
    vehicle_uniform_pairs,
    vehicle_uniforms,
)
from rain_core.lighting import MAX_LIGHTS
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, VAN_SPEC, Vehicle


def _fleet(rng, n=9):
    specs = (CAR_SPEC, VAN_SPEC, TRUCK_SPEC)
    return [Vehicle(specs[i % 3], position=(rng.uniform(-8, 8), 0.0, rng.uniform(-3000, 3000)),
                    yaw=rng.uniform(-3, 3)) for i in range(n)]


def test_vehicle_uniforms_equal_the_pieces_of_each_vehicle_in_order():
    rng = np.random.default_rng(4)
    for trial in range(4):
        vehicles = _fleet(rng, n=3 + 2 * trial)
        got = vehicle_uniforms(vehicles, shift_z=1200.0, around_z=40.0)
        n, m = PIECES_PER_VEHICLE, PIECES_PER_VEHICLE * PLANES_PER_PIECE
        assert got["u_veh_count"] == min(len(vehicles), MAX_VEHICLES)
        for i in range(MAX_VEHICLES):
            if i < len(vehicles):
                v = vehicles[i]
                plo, phi, pp = piece_volumes(v.spec)
                z = float(wrap_near(v.position[2] - 1200.0, 40.0))
                np.testing.assert_array_equal(got["u_veh_pose"][i], (v.position[0], v.position[1], z, v.yaw))
            else:
                plo = phi = np.zeros((n, 3))
                pp = np.zeros((m, 4))
                np.testing.assert_array_equal(got["u_veh_pose"][i], 0.0)
            np.testing.assert_array_equal(got["u_veh_lo"][i * n:(i + 1) * n, :3], plo)
            np.testing.assert_array_equal(got["u_veh_hi"][i * n:(i + 1) * n, :3], phi)
            np.testing.assert_array_equal(got["u_veh_plane"][i * m:(i + 1) * m], pp.reshape(-1, 4))
        # The pieces are shared and read-only: a caller cannot corrupt the next frame's.
        assert not got["u_veh_lo"].flags.writeable and not got["u_veh_plane"].flags.writeable


def test_cull_vehicles_keeps_the_nearest_within_reach_with_the_period_wrapped():
    rng = np.random.default_rng(7)
    vehicles = _fleet(rng, n=40)
    centre = np.array([1.0, 2500.0])
    reach = 80.0
    got = cull_vehicles(vehicles, centre, reach)
    dist = [float(np.hypot(v.position[0] - centre[0], wrap_near(v.position[2] - centre[1], 0.0))) for v in vehicles]
    want = sorted((d, i) for i, (d, v) in enumerate(zip(dist, vehicles, strict=True))
                  if d <= reach + 0.5 * v.spec.length_m)[:MAX_VEHICLES]
    assert [id(v) for v in got] == [id(vehicles[i]) for _, i in want]
    # A real test: some of the vehicles kept are near only through the period's wrap.
    assert any(abs(v.position[2] - centre[1]) > layout.PERIOD_M / 2 for v in got)


def test_lights_are_packed_as_each_buffer_alone():
    """_lights packs the three light buffers in one pass: the bytes equal packing each buffer by itself."""
    rng = np.random.default_rng(2)
    count, slots = 9, 16
    pos = np.zeros((slots, 4), np.float32)
    pos[:count, :3] = rng.uniform(-80, 80, (count, 3))
    pos[:count, 3] = rng.uniform(-40, 40, count)  # w < 0: a low beam (its |w| is the range)
    dirs = rng.standard_normal((slots, 4)).astype(np.float32)
    cols = rng.uniform(0, 5, (slots, 4)).astype(np.float32)
    boxes = layer_boxes(np.array([0.0, 1.2, 30.0]), np.array([0.0, 0.0, -1.0]), 40.0)
    rc = SimpleNamespace(lights=(pos.tobytes(), dirs.tobytes(), cols.tobytes(), count), shift_z=5.0)
    got = RainfallEffect._lights(None, rc, boxes)
    lo = boxes.lo[-1] - [0.0, 0.0, 5.0]
    hi = boxes.hi[-1] - [0.0, 0.0, 5.0]
    gap = np.maximum(np.maximum(lo - pos[:count, :3], pos[:count, :3] - hi), 0.0)
    keep = np.flatnonzero(np.linalg.norm(gap, axis=1) < np.abs(pos[:count, 3]))
    assert 0 < keep.size < count  # a real test: some lights reach the rain, some do not
    for arr, data in zip((pos, dirs, cols), got[:3], strict=True):
        packed = np.zeros_like(arr)
        packed[:keep.size] = arr[keep]
        assert data == packed.tobytes()
    assert got[3] == keep.size
    # The renderer's lights come nearest first, so those that reach are usually the first ones: cut, not gathered.
    order = np.concatenate([keep, np.setdiff1d(np.arange(count), keep)])
    for arr in (pos, dirs, cols):
        arr[:count] = arr[order]
    rc.lights = (pos.tobytes(), dirs.tobytes(), cols.tobytes(), count)
    got = RainfallEffect._lights(None, rc, boxes)
    assert got[3] == keep.size
    for arr, data in zip((pos, dirs, cols), got[:3], strict=True):
        packed = np.zeros_like(arr)
        packed[:keep.size] = arr[:keep.size]
        assert data == packed.tobytes()


def test_lights_that_reach_are_those_of_the_array_formula():
    """_lights decides in floats, per light, what the array form decided (float64 gap, einsum, float32 w²),
    lights near the box's faces and corners included; none, some or all reach."""
    rng = np.random.default_rng(8)
    boxes = layer_boxes(np.array([1.5, 1.2, 300.0]), np.array([0.1, -0.05, -1.0]), 40.0)
    shift = 240.0
    lo = boxes.lo[-1] - [0.0, 0.0, shift]
    hi = boxes.hi[-1] - [0.0, 0.0, shift]
    seen = set()
    for trial in range(300):
        count = int(rng.integers(1, 33))
        pos = np.zeros((32, 4), np.float32)
        pos[:count, :3] = rng.uniform(lo - 30.0, hi + 30.0, (count, 3))
        pos[:count, 3] = rng.uniform(-30.0, 30.0, count) * (trial % 3)  # trial % 3 == 0: zero ranges, none reach
        gap = np.maximum(np.maximum(lo - pos[:count, :3], pos[:count, :3] - hi), 0.0)
        want = np.flatnonzero(np.einsum("ij,ij->i", gap, gap) < pos[:count, 3] * pos[:count, 3])
        cols = rng.uniform(0, 5, (32, 4)).astype(np.float32)
        rc = SimpleNamespace(lights=(pos.tobytes(), cols.tobytes(), cols.tobytes(), count), shift_z=shift)
        got = RainfallEffect._lights(None, rc, boxes)
        assert got[3] == want.size
        packed = np.zeros_like(pos)
        packed[:want.size] = pos[want]
        assert got[0] == (pos.tobytes() if want.size == count else packed.tobytes())
        seen.add("none" if want.size == 0 else "all" if want.size == count else "some")
    assert seen == {"none", "some", "all"}


def _layer_boxes_arrays(camera_position, camera_forward, container_m):
    """layer_boxes as it was written with arrays (the oracle of the float form)."""
    cam = np.asarray(camera_position, dtype=np.float64)
    f = np.asarray(camera_forward, dtype=np.float64)
    fh = np.array([f[0], f[2]])
    n = float(np.hypot(*fh))
    fh = fh / n if n > 1e-9 else np.zeros(2)
    h = 0.5 * float(container_m) * np.asarray(LAYER_SCALES)
    height = box_heights(container_m)
    centre = cam[[0, 2]][None, :] + fh[None, :] * (FORWARD_OFFSET * h * min(n, 1.0))[:, None]
    top = np.maximum(BOX_BOTTOM_Y_M + height, max(float(cam[1]), GROUND_Y_M) + TOP_SLOPE * h + TOP_PAD_M)
    bottom = top - height
    lo = np.stack([centre[:, 0] - h, bottom, centre[:, 1] - h], axis=1)
    hi = np.stack([centre[:, 0] + h, top, centre[:, 1] + h], axis=1)
    fade = np.stack([FADE_FRACTION * h, FADE_FRACTION * height, FADE_FRACTION * h], axis=1)
    fade_bottom = np.minimum(bottom - BOX_BOTTOM_Y_M, FADE_FRACTION * height)
    return lo, hi, fade, np.asarray(LAYER_PROFILE, dtype=np.float64), fade_bottom


def test_layer_boxes_in_floats_equal_the_array_form_bit_for_bit():
    rng = np.random.default_rng(11)
    for trial in range(3000):
        cam = rng.uniform(-3000.0, 3000.0, 3)
        cam[1] = (rng.uniform(-1.0, 12.0), 1.2, 0.0)[trial % 3]
        fwd = rng.standard_normal(3) * (1e-3 if trial % 7 == 0 else 1.0)
        if trial % 50 == 0:
            fwd[0] = fwd[2] = 0.0  # straight down
        container = (40.0, float(rng.uniform(10.0, 120.0)))[trial % 2]
        got = layer_boxes(cam, fwd, container)
        want = _layer_boxes_arrays(cam, fwd, container)
        for name, w in zip(("lo", "hi", "fade", "nu", "fade_bottom"), want, strict=True):
            g = getattr(got, name)
            assert g.dtype == w.dtype and g.shape == w.shape and g.tobytes() == w.tobytes(), (name, trial)
    # the arrays every frame shares are read-only: no caller can corrupt the next frame's boxes
    assert not got.fade.flags.writeable and not got.nu.flags.writeable


def _as_bytes(value) -> bytes:
    if isinstance(value, bytes):
        return value
    if isinstance(value, np.ndarray):
        return np.ascontiguousarray(value, np.float32).tobytes()
    if isinstance(value, int):
        return struct.pack("=i", value)
    return np.asarray(value, np.float32).tobytes()


def test_packed_pairs_equal_the_uniform_dicts(rain):
    """box_pairs, splash_box_pairs and vehicle_uniform_pairs give the bytes drop_uniforms, splash_uniforms and
    vehicle_uniforms give (as the GPU receives them), the wind's integral and the shift included."""
    rng = np.random.default_rng(5)
    effect = RainfallEffect.__new__(RainfallEffect)
    effect.sim = RainfallSim(5000, seed=3)
    effect._occ_geom = {"fine": (0.0, 1.0, 0.0, 1.0), "coarse": (0.0, 1.0, 0.0, 1.0)}
    effect._road_extent = (1.0, 1.0)
    for trial in range(40):
        pos = (rng.uniform(-6, 6), rng.uniform(0.5, 9.0), rng.uniform(-3000, 3000))
        upd = effect.sim.advance(rain.input(0.1 + trial / 7.0, pos=pos, wind=tuple(rng.uniform(-20, 20, 3)),
                                            forward=rng.standard_normal(3), container_m=rng.uniform(10, 120)))
        effect.sim.wind_integral = rng.uniform(-5000, 5000, 3)
        upd.wind_integral_m = effect.sim.wind_integral.copy()
        shift = float(rng.choice([0.0, 1200.0, -2400.0]))
        want = effect.drop_uniforms(upd, shift, 30.0)
        for name, value in box_pairs(upd.boxes, upd.wind_integral_m, shift):
            assert value == _as_bytes(want[name]), (name, trial)
        splash = effect.splash_uniforms(upd, shift)
        for name, value in splash_box_pairs(upd.boxes, SPLASH_LAYER, shift):
            assert _as_bytes(value) == _as_bytes(splash[name]), (name, trial)
    vehicles = _fleet(rng, n=11)
    got = dict(vehicle_uniform_pairs(vehicles, 1200.0, 40.0))
    for name, value in vehicle_uniforms(vehicles, 1200.0, 40.0).items():
        assert _as_bytes(got[name]) == _as_bytes(value), name


def _uniform_bytes(prog, name):
    uniform = prog.get(name, None)
    return None if uniform is None else uniform.read()


def _check_programs(effect, rc):
    """Every uniform the effect owns holds, in both programs, what the dict forms say for this frame."""
    upd = effect.last_update
    s = effect._settings(rc.frame)
    lights = effect._lights(rc, upd.boxes)
    common = effect.drop_uniforms(upd, rc.shift_z, float(rc.camera_position[2]))
    common.update({"u_viewport": tuple(float(v) for v in rc.size),
                   "u_focal_px": float(rc.projection[1, 1]) * rc.size[1] / 2.0,
                   "u_brightness": float(s.rainfall.streak_brightness)})
    streak = dict(common, u_cam_vel=tuple(effect.camera_velocity_m_s), u_exposure_s=float(s.camera.exposure_s),
                  u_near=float(rc.frame.camera.near_m), u_shape_area=effect._shape_area,
                  u_shape_width=effect._shape_width)
    splash = dict(common, **effect.splash_uniforms(upd, rc.shift_z))
    checked = 0
    for prog, values in ((effect.record_prog, streak), (effect.splash_prog, splash)):
        for name, value in values.items():
            if name == "u_seed_key" or name == "u_splash_key" or name == "u_splash_count" or name == "u_epoch":
                want = struct.pack("=I", value)
            else:
                want = _as_bytes(value)
            got = _uniform_bytes(prog, name)
            if got is not None:
                assert got[:len(want)] == want, name
                checked += 1
    assert checked > 40
    # The quads' program (the records' second pass) reads the viewport alone.
    assert _uniform_bytes(effect.streak_prog, "u_viewport") == _as_bytes(common["u_viewport"])
    # The RainFrame block (std140, drops.glsl) holds the rest: placed here word by word from the dict forms.
    block = np.zeros(RAIN_FRAME_BYTES // 4, np.float32)
    words = block.view(np.uint32)
    for k, name in enumerate(("u_box_lo", "u_box_off", "u_box_turb")):
        for layer, row in enumerate(np.asarray(common[name], np.float32)):
            block[16 * k + 4 * layer: 16 * k + 4 * layer + 3] = row
    block[48:80] = np.asarray(common["u_veh_pose"], np.float32).ravel()
    block[80:83] = common["u_wind"]
    words[83] = np.uint32(np.int32(common["u_time_whole"]).view(np.uint32))
    block[84] = common["u_time_frac"]
    words[85] = common["u_epoch"]
    block[88:91] = splash["u_splash_lo"]
    words[91] = splash["u_splash_count"]
    block[92:95] = splash["u_splash_off"]
    block[95] = splash["u_splash_tau"]
    block[96:99] = streak["u_cam_vel"]
    words[99] = lights[3]  # u_light_count, then the three vec4 arrays of the lights that reach the boxes
    for k in range(3):
        block[100 + 128 * k: 228 + 128 * k] = np.frombuffer(lights[k], np.float32)
    assert effect._frame_buffer.read() == block.tobytes()
    for prog in (effect.record_prog, effect.splash_prog):
        assert prog["RainFrame"].binding == RAIN_FRAME_BINDING
        assert prog["RainFrame"].size == RAIN_FRAME_BYTES
        for name in ("u_light_pos", "u_light_dir", "u_light_color", "u_light_count"):
            assert prog.get(name, None) is None  # RainFrame's member, not a plain uniform
    return lights[3] < rc.lights[3]


def test_programs_hold_this_frames_uniforms_through_live_changes(gl_ctx, shaders, rain):
    """The uniform cache never leaves a stale value: after every frame both programs hold what the dict forms
    give, through a container resize, a camera switch, the rain off and on, and a second effect drawing with
    the same programs (another seed)."""
    s = rain.settings(rate=12.0, mode="driver", budget=3000, hour=22.0, container_m=20.0)
    scene, effect = rain.scene(gl_ctx, shaders, s, seed=4)
    culled = []  # frames where some lights did not reach the boxes: their filtered list differs from the frame's
    other_settings = rain.settings(rate=3.0, mode="chase", budget=2000, container_m=25.0)
    other, other_effect = rain.scene(gl_ctx, shaders, other_settings, seed=9)
    assert other_effect.record_prog is effect.record_prog  # one shader library: shared programs
    try:
        changes = [lambda: None, lambda: setattr(s.rainfall, "container_m", 70.0),
                   lambda: setattr(s.camera, "mode", "chase"), lambda: setattr(s.rainfall, "enabled", False),
                   lambda: setattr(s.rainfall, "enabled", True), lambda: setattr(s.rainfall, "density_scale", 2.0)]
        for change in changes:
            change()
            for _ in range(2):
                scene.step(1.0 / 30.0)
                frame = scene.render()
            if s.rainfall.enabled:
                culled.append(_check_programs(effect, scene.renderer.render_context(frame)))
            other.step(1.0 / 30.0)
            other_frame = other.render()
            _check_programs(other_effect, other.renderer.render_context(other_frame))
        assert any(culled)
        # A pass drawn with another context than the update's (its own shift): made for it, not the update's.
        rc = dataclasses.replace(scene.renderer.render_context(frame), shift_z=scene.renderer.render_context(
            frame).shift_z + layout.PERIOD_M)
        effect.render("transparent", rc)
        _check_programs(effect, rc)
    finally:
        other.release()
        scene.release()


def test_a_frame_uniform_changing_alone_reaches_the_programs(gl_ctx, shaders, rain):
    """The constants and the frame's plain uniforms are skipped as one tuple while both stay (_plain_pairs): a
    narrower lens alone (u_focal_px) still reaches both programs."""
    s = rain.settings(rate=12.0, mode="chase", budget=3000, container_m=20.0)
    scene, effect = rain.scene(gl_ctx, shaders, s, seed=4)
    try:
        for fov in (60.0, 60.0, 40.0, 40.0):
            s.camera.fov_deg = fov
            scene.step(1.0 / 30.0)
            frame = scene.render()
            _check_programs(effect, scene.renderer.render_context(frame))
    finally:
        scene.release()


def test_environment_map_is_redrawn_when_the_lighting_or_the_medium_changes(gl_ctx, shaders, rain):
    """The drop's environment map is drawn only when what it reads changed; after an hour change (a new
    lighting) and a rain rate change (another medium) it equals a map drawn afresh."""
    from rain_core.scene import Scene

    s = rain.settings(rate=8.0, mode="driver", budget=2000)
    scene = Scene(gl_ctx, (64, 36), s, seed=1, gpu_timing=False)
    effect = next(e for e in scene.effects if e.name == "rainfall")
    try:
        def fresh():
            effect._env_key = None
            scene.render()
            return effect._env_tex.read()

        scene.step(1.0 / 30.0)
        scene.render()
        before = effect._env_tex.read()
        key = effect._env_key
        scene.step(1.0 / 30.0)
        scene.render()
        assert effect._env_key is key  # nothing it reads changed: not drawn again
        for change in (lambda: setattr(s.time_of_day, "hour", 17.5), lambda: setattr(s.rain, "rate_mm_h", 40.0)):
            change()
            for _ in range(3):
                scene.step(1.0 / 30.0)
                scene.render()
            kept = effect._env_tex.read()
            assert kept != before
            assert kept == fresh()
            before = kept
    finally:
        scene.release()


def test_environment_key_holds_the_lighting_and_each_medium_uniform():
    """_draw_environment draws again for a new lighting object or any medium value it reads; not for the
    frame's other uniforms (the shadow's, which move every frame)."""
    draws = []
    effect = RainfallEffect.__new__(RainfallEffect)
    effect._env_key, effect._optics_set, effect.env_prog = None, True, object()
    effect.ctx = SimpleNamespace(disable=lambda flag: None)
    effect._env_fbo = SimpleNamespace(use=lambda: None)
    effect._env_vao = SimpleNamespace(render=lambda *a, **k: draws.append(1))
    fbo = SimpleNamespace(use=lambda: None)
    lighting = object()
    uniforms = {"u_extinction_per_m": 1e-3, "u_airlight": (1.0, 1.0, 1.0), "u_shadow_matrix": b"0"}

    def draw():
        rc = SimpleNamespace(uniforms=dict(uniforms), frame=SimpleNamespace(lighting=lighting),
                             set_frame_uniforms=lambda prog: None, hdr=SimpleNamespace(fbo=fbo))
        effect._draw_environment(rc)
        return len(draws)

    assert draw() == 1 and draw() == 1
    uniforms["u_shadow_matrix"] = b"1"
    assert draw() == 1
    uniforms["u_airlight"] = (1.0, 2.0, 1.0)
    assert draw() == 2
    uniforms["u_phase_g"] = 0.7  # a medium uniform appearing (the atmosphere switched on)
    assert draw() == 3
    lighting = object()  # another hour or overcast
    assert draw() == 4 and draw() == 4


def _time_split_numpy(t):
    """time_split's NumPy form (the oracle of its float form)."""
    epoch = np.floor(t / TIME_PERIOD_S)
    tau = t - epoch * TIME_PERIOD_S
    whole = min(int(np.floor(tau)), TIME_PERIOD_S - 1)
    return whole, float(tau - whole), int(epoch) & 0xFFFFFFFF


def test_time_split_in_floats_equals_the_numpy_form_bit_for_bit():
    rng = np.random.default_rng(17)
    times = [0.0, -0.0, 1.0, TIME_PERIOD_S, -TIME_PERIOD_S, 3.0 * TIME_PERIOD_S - 1e-12, -1e-300, 5e-324,
             float(2 ** 40 * TIME_PERIOD_S), 1e15 + 0.5]
    times += rng.uniform(-1e5, 1e5, 2000).tolist() + (rng.integers(-50, 50, 500) * TIME_PERIOD_S).astype(float).tolist()
    times += (10.0 ** rng.uniform(-6, 12, 2000)).tolist() + (np.arange(3000) / 30.0).tolist()
    for t in times:
        got, want = time_split(t), _time_split_numpy(t)
        assert [type(v) for v in got] == [type(v) for v in want], t
        assert struct.pack("=qdq", *got) == struct.pack("=qdq", *want), t


def test_the_rain_programs_hold_the_filtered_lights_in_their_block_alone(gl_ctx, shaders, rain):
    """The rain programs read their lights from RainFrame alone (no plain light uniforms, no frame-block lights:
    _check_programs): the block holds this frame's filtered list at every frame, culled or not, never the frame's
    own list where some light does not reach the boxes."""
    s = rain.settings(rate=12.0, mode="driver", budget=3000, hour=22.0, container_m=20.0)
    scene, effect = rain.scene(gl_ctx, shaders, s, seed=4)
    try:
        culled = 0
        for _ in range(6):
            scene.step(1.0 / 30.0)
            frame = scene.render()
            rc = scene.renderer.render_context(frame)
            if _check_programs(effect, rc):
                culled += 1
                head = RAIN_FRAME_BYTES - 3 * 16 * MAX_LIGHTS
                assert effect._frame_buffer.read()[head:head + 16 * MAX_LIGHTS] != rc.lights[0]
        assert culled
    finally:
        scene.release()


def test_the_streaks_are_lit_by_the_blocks_lights(gl_ctx, shaders, rain, monkeypatch):
    """At night in the headlights, the streaks drawn with the block's lights differ from those drawn with an empty
    list, and drawing with the same list again gives the same pixels: the shaders read the lights from RainFrame."""
    s = rain.settings(rate=12.0, mode="driver", budget=3000, hour=22.0, container_m=20.0)
    scene, effect = rain.scene(gl_ctx, shaders, s, seed=4)
    try:
        scene.step(1.0 / 30.0)
        frame = scene.render()
        rc = scene.renderer.render_context(frame)
        lights = effect._lights(rc, effect.last_update.boxes)
        assert lights[3] > 0

        def streaks(lights):
            monkeypatch.setattr(effect, "_lights", lambda rc, boxes: lights)
            rc.hdr.fbo.use()
            rc.hdr.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
            effect.render("transparent", rc)
            return scene.renderer.hdr_image()

        lit = streaks(lights)
        dark = streaks((bytes(16 * MAX_LIGHTS),) * 3 + (0,))
        assert (lit.sum(axis=2) > dark.sum(axis=2)).sum() > 20
        np.testing.assert_array_equal(streaks(lights), lit)
    finally:
        scene.release()
