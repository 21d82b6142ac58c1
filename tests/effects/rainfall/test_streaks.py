"""rainfall streaks: the tilt of the streaks, the shader against its NumPy twin, drops glowing in headlights."""

from __future__ import annotations

import dataclasses

import numpy as np

from rain_core import physics
from rain_core.effects.rainfall import RainfallSim, StreakCamera, streak_geometry
from rain_core.effects.rainfall.streak_pass import RECORD_BYTES

# --- what the camera sees ---------------------------------------------------------------------------------------


def test_tilt_equals_atan_of_car_speed_over_fall_speed(rain):
    """For a steady car the streak (the drop's path relative to the camera) leans towards the windshield by
    atan(v_car / v_fall), drop by drop, in the NumPy twin of the vertex shader."""
    v_car = 25.0
    sim = RainfallSim(3000, seed=4)
    t = rain.drive(sim, 1.0, speed=v_car, rate=8.0)
    eye = np.array([1.75, 1.2, 600.0 - v_car * t])
    from rain_core.camera import Camera

    cam = Camera(position=eye, forward=np.array([0.0, 0.0, -1.0]))
    view_proj = cam.projection_matrix(16 / 9) @ cam.view_matrix()
    sc = StreakCamera(view_proj, eye, 0.0, np.array([0.0, 0.0, -v_car]), 1.0 / 60.0, (320, 180))
    g = streak_geometry(sim, None, t, sc)
    seg = g["head"] - g["tail"]  # where the drop is now minus where it was relative to the camera
    vis = g["visible"] & (np.linalg.norm(seg, axis=1) > 1e-6)
    tilt = np.degrees(np.arctan2(seg[vis, 2], -seg[vis, 1]))  # from the vertical, towards +Z (the windshield)
    expected = np.degrees(np.arctan(v_car / physics.terminal_velocity(g["d_mm"][vis])))
    assert vis.sum() > 500
    assert np.max(np.abs(tilt - expected)) < 1.0
    assert np.all(np.abs(seg[vis, 0]) < 1e-9)  # no sideways lean without wind
    # Parked: the streaks are vertical; reversing: they lean the other way.
    for speed, sign in ((0.0, 0.0), (-5.0, -1.0)):
        sc2 = dataclasses.replace(sc, velocity=np.array([0.0, 0.0, -speed]))
        s2 = streak_geometry(sim, None, t, sc2)
        seg2 = s2["head"] - s2["tail"]
        lean = np.degrees(np.arctan2(seg2[vis, 2], -seg2[vis, 1]))
        want = sign * np.degrees(np.arctan(abs(speed) / physics.terminal_velocity(g["d_mm"][vis])))
        assert np.max(np.abs(lean - want)) < 1.0


def test_dense_streaks_spread_along_their_motion_before_widening(rain):
    """A drawn streak standing for many drops spreads their light first along its motion (a line of rain), then
    wider, then brighter — never a square fleck while it may still stretch — and keeps the light it carries."""
    from rain_core.camera import Camera
    from rain_core.effects.rainfall.constants import ALPHA_MAX, SPREAD_ALPHA, STRETCH_MAX, WIDTH_FLOOR_PX

    v_car = 15.0
    sim = RainfallSim(800, seed=2)  # a small budget: each drawn drop stands for many
    t = rain.drive(sim, 1.0, speed=v_car, rate=30.0)
    eye = np.array([1.75, 1.2, 600.0 - v_car * t])
    cam = Camera(position=eye, forward=np.array([0.0, 0.0, -1.0]))
    view_proj = cam.projection_matrix(16 / 9) @ cam.view_matrix()
    g = streak_geometry(sim, None, t, StreakCamera(view_proj, eye, 0.0, np.array([0.0, 0.0, -v_car]), 1.0 / 60.0,
                                                   (1280, 720)))
    vis = g["visible"]
    path = np.linalg.norm(g["tail_px"] - g["head_px"], axis=1)
    spread = vis & (g["light_px2"] > SPREAD_ALPHA * WIDTH_FLOOR_PX * (path + 1.0)) & (path > 2.0)
    assert spread.sum() > 50
    w, length = g["width_px"][spread], g["length_px"][spread]
    widened = w > WIDTH_FLOOR_PX + 1e-9
    # Wider only once as long as it may be: STRETCH_MAX × its unspread footprint (at least its path).
    assert np.all(length[widened] >= STRETCH_MAX * path[spread][widened] - 1e-6)
    assert np.all(length >= path[spread])
    # The light is kept wherever the opacity did not reach its ceiling.
    free = g["alpha"][spread] < ALPHA_MAX - 1e-9
    assert np.allclose(g["drawn_px2"][spread][free], g["light_px2"][spread][free], rtol=1e-9)


def test_shader_draws_the_twins_streaks(gl_ctx, shaders, rain):
    """Every pixel the streak pass lights lies on a streak of the NumPy twin, and the light it adds (with the
    radiance switched to a constant) matches the twin's light budget."""
    from rain_core.camera import Camera

    s = rain.settings(rate=8.0, mode="driver", budget=300, container_m=16.0, splashes=False)
    s.wind.speed_m_s = 0.0
    scene, effect = rain.scene(gl_ctx, shaders, s, size=(240, 135))
    scene.ego.speed_m_s = 15.0
    scene.step(1.0 / 60.0)
    eye = scene.camera().position + np.array([1.6, 0.3, 0.0])  # beside the car, looking right
    cam = Camera(position=eye, forward=np.array([1.0, 0.0, 0.0]), fov_y_deg=60.0)
    frame = scene.render(cam)
    rain = scene.renderer.hdr_image()
    g = streak_geometry(effect.sim, None, frame.time_s, effect.streak_camera(scene.renderer.render_context(frame)))
    s.rainfall.enabled = False
    scene.render(cam)
    light = np.abs(rain - scene.renderer.hdr_image()).sum(axis=2)
    w, h = scene.renderer.size
    ys, xs = np.nonzero(light > 1e-5)
    assert xs.size > 200
    px = np.stack([xs + 0.5 - w / 2, h / 2 - (ys + 0.5)], axis=1)
    vis = g["visible"]
    a, b, width = g["head_px"][vis], g["tail_px"][vis], g["width_px"][vis]
    # The drawn footprint: the path, longer by the drop's chord or the compensation's stretch, about its centre.
    unit = (b - a) / np.maximum(np.linalg.norm(b - a, axis=1), 1e-9)[:, None]
    unit[np.linalg.norm(b - a, axis=1) <= 1e-4] = (0.0, 1.0)
    grow = 0.5 * np.maximum(g["length_px"][vis] - np.linalg.norm(b - a, axis=1), 0.0)[:, None] * unit
    a, b = a - grow, b + grow
    ab = b - a
    t = np.clip(((px[:, None] - a[None]) * ab[None]).sum(2) / np.maximum((ab**2).sum(1), 1e-9)[None], 0, 1)
    dist = np.linalg.norm(px[:, None] - (a[None] + t[..., None] * ab[None]), axis=2) - 0.5 * width[None]
    assert dist.min(axis=1).max() < 1.5  # within the 0.5 px antialiasing margin and the pixel's half-diagonal
    # The car's speed tilts the streaks: seen from the side they are almost horizontal.
    ok = vis & (np.linalg.norm(g["head_px"] - g["tail_px"], axis=1) > 3)
    d = g["tail_px"][ok] - g["head_px"][ok]
    from_horizontal = np.abs(np.degrees(np.arctan(d[:, 1] / np.where(d[:, 0] == 0, 1e-9, d[:, 0]))))
    assert np.median(from_horizontal) < 30.0


def test_streak_records_are_the_twins_streaks(gl_ctx, shaders, rain):
    """The record pass (streak_record.vert, once per drop) writes, drop by drop, the streak of the NumPy twin:
    the ends in px, the half extents (width and length with the drop's chord and the compensation's stretch, plus
    the 0.5 px margin) and the opacity; it culls only what the twin leaves out or what lies beyond the view."""
    s = rain.settings(rate=8.0, mode="driver", budget=4000, container_m=16.0, splashes=False)
    scene, effect = rain.scene(gl_ctx, shaders, s, size=(320, 180))
    scene.ego.speed_m_s = 15.0
    for _ in range(3):
        scene.step(1.0 / 60.0)
        frame = scene.render()
    rc = scene.renderer.render_context(frame)
    rec = effect.read_streaks(rc)
    g = streak_geometry(effect.sim, None, frame.time_s, effect.streak_camera(rc))
    drawn = rec[:, 3] > 0.0
    assert drawn.sum() > 300
    assert not np.any(drawn & ~g["visible"])  # nothing the twin culls
    # The twin's drops whose whole streak lies well inside the view are drawn (none is under a roof here).
    half = 0.5 * np.asarray(rc.size, np.float64)
    inside = g["visible"] & np.all(np.abs(g["head_px"]) < 0.8 * half, axis=1) & np.all(
        np.abs(g["tail_px"]) < 0.8 * half, axis=1)
    assert inside.sum() > 200 and np.all(drawn[inside])
    k = drawn
    scale = 1e-4 * np.maximum(1.0, np.abs(g["head_px"][k]).max(axis=1))[:, None]  # float32 against float64
    assert np.all(np.abs(rec[k, 0:2] - g["head_px"][k]) <= 0.01 + scale)
    assert np.all(np.abs(rec[k, 4:6] - g["tail_px"][k]) <= 0.01 + scale)
    np.testing.assert_allclose(rec[k, 8], 0.5 * g["width_px"][k] + 0.5, rtol=1e-3)
    np.testing.assert_allclose(rec[k, 9], 0.5 * g["length_px"][k] + 0.5, rtol=1e-3)
    np.testing.assert_allclose(rec[k, 13], g["alpha"][k], rtol=2e-3)
    assert np.all(rec[k, 10:13] > 0.0)  # lit: the sky in each drop
    # Clip w is the drop's distance along the view: ahead of the near plane for both ends.
    assert np.all(rec[k, 3] >= 1.01 * frame.camera.near_m * (1 - 1e-6))
    assert np.all(rec[k, 7] >= 1.01 * frame.camera.near_m * (1 - 1e-6))
    # A budget changed live: the records follow the new capacity from the next frame on, and so does the picture.
    s.quality.particle_budget = 9000
    scene.step(1.0 / 60.0)
    frame = scene.render()
    rc = scene.renderer.render_context(frame)
    assert effect.sim.capacity == 9000 and effect.streaks.records.size == 9000 * RECORD_BYTES
    more = effect.read_streaks(rc)
    assert len(more) == 9000 and (more[:, 3] > 0.0).sum() > 2 * drawn.sum() * 0.8


def test_drops_in_a_headlight_beam_glow(gl_ctx, shaders, rain):
    from rain_core.camera import Camera

    s = rain.settings(rate=8.0, hour=23.0, mode="driver", budget=30000, splashes=False)
    s.wind.speed_m_s = 0.0
    scene, effect = rain.scene(gl_ctx, shaders, s)
    scene.ego.speed_m_s = 0.0
    lit = [0.0, 0.0]
    for _ in range(3):  # three moments (the beam holds a few hundred drops: average their sampling noise)
        scene.step(0.5)
        ego = scene.ego
        # A camera on the kerb side, looking across the road through the beams in front of the car.
        target = ego.position + ego.forward() * 6.0 + np.array([0.0, 0.8, 0.0])
        eye = target + ego.right() * 6.0 + np.array([0.0, 0.2, 0.0])
        cam = Camera(position=eye, forward=(target - eye) / np.linalg.norm(target - eye), fov_y_deg=50.0)
        for i, on in enumerate((True, False)):
            frame = dataclasses.replace(scene.frame(cam), headlights_on=on)
            scene.renderer.render(frame)
            rain = scene.renderer.hdr_image()
            s.rainfall.enabled = False
            scene.renderer.render(frame)
            dry = scene.renderer.hdr_image()
            s.rainfall.enabled = True
            h, w = rain.shape[:2]
            centre = (rain - dry)[h // 4: 3 * h // 4, w // 4: 3 * w // 4]  # the beam, away from the street lamps
            lit[i] += float(np.clip(centre, 0, None).sum())
    assert lit[0] > 3.0 * lit[1] and lit[0] > 0.0
