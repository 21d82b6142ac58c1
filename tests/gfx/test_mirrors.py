"""Door mirrors: a plane mirror's geometry, and a view of the scene behind drawn only when a mirror is in view."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core.gfx import mirrors as M


def test_reflection_about_a_plane_is_an_involution_fixing_the_plane():
    rng = np.random.default_rng(2)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    point = rng.normal(size=3) * 10.0
    r = M.reflection_about(point, n)
    assert np.allclose(r @ r, np.eye(4))
    on_plane = point + np.cross(n, rng.normal(size=3))
    assert np.allclose((r @ np.r_[on_plane, 1.0])[:3], on_plane)
    off = point + 0.7 * n
    assert np.allclose((r @ np.r_[off, 1.0])[:3], point - 0.7 * n)


def test_the_glass_is_aimed_like_a_drivers_mirror():
    """Law of reflection: the ray from the eye to the glass's centre leaves level, AIM_OUTWARD_DEG outward of
    straight back, on the mirror's side."""
    from rain_core.car_mesh import DRIVER_EYE_LOCAL, door_mirror_faces

    yaw = 0.3
    model = np.eye(4)
    model[:3, :3] = [[np.cos(yaw), 0, np.sin(yaw)], [0, 1, 0], [-np.sin(yaw), 0, np.cos(yaw)]]
    model[:3, 3] = (3.0, 0.0, 50.0)
    eye = model[:3, :3] @ DRIVER_EYE_LOCAL + model[:3, 3]
    for side, face in zip((-1, 1), door_mirror_faces(), strict=True):
        centre = (face @ model[:3, :3].T + model[:3, 3]).mean(axis=0)
        n = M._adjusted_normal(model, centre, eye)
        d = (centre - eye) / np.linalg.norm(centre - eye)
        out = d - 2.0 * (d @ n) * n
        assert abs(out[1]) < 1e-9  # level
        rear, right = model[:3, 2], model[:3, 0]
        assert np.degrees(np.arctan2(side * (out @ right), out @ rear)) == pytest.approx(M.AIM_OUTWARD_DEG)


def _render(gl_ctx, **values):
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in {"rain.rate_mm_h": 2.0, "time_of_day.hour": 12.0, "traffic.count": 0, **values}.items():
        set_value(settings, path, value)
    scene = Scene(gl_ctx, (320, 180), settings, seed=1, gpu_timing=False)
    try:
        for _ in range(3):
            scene.step(1 / 30)
        frame = scene.render()
        ran = {s.name: s.ran for s in scene.renderer.stats}["mirrors"]
        rc = scene.renderer.render_context(frame)
        views = scene.renderer.mirrors.views(rc)
        return scene.image().astype(np.float64), ran, views
    finally:
        scene.release()


def test_mirrors_are_skipped_out_of_view_and_outside_the_car(gl_ctx):
    _, ran, views = _render(gl_ctx)  # the default driver view (40°): the door mirrors are beside it
    assert not ran and views == []
    _, ran, views = _render(gl_ctx, **{"camera.mode": "chase"})
    assert not ran and views == []
    _, ran, _ = _render(gl_ctx, **{"camera.driver_fov_deg": 70.0, "camera.mirrors": False})
    assert not ran


def test_a_mirror_in_view_shows_the_scene_behind(gl_ctx):
    """At a 70° driver view the left mirror is in view: its view is drawn, and its glass shows the road and the
    street behind (varied, brighter than the dark glass it replaces), while the rest of the frame is unchanged."""
    on, ran, views = _render(gl_ctx, **{"camera.driver_fov_deg": 70.0})
    off, _, _ = _render(gl_ctx, **{"camera.driver_fov_deg": 70.0, "camera.mirrors": False})
    assert ran and len(views) == 1
    x, y, w, h = views[0].box_px
    rows = slice(180 - (y + h) + 2, 180 - y - 2)  # GL's bottom-left box → image rows, inside the glass
    cols = slice(x + 2, x + w - 2)
    glass_on, glass_off = on[rows, cols].mean(axis=-1), off[rows, cols].mean(axis=-1)
    assert glass_on.mean() > glass_off.mean() + 10.0
    assert glass_on.std() > 4.0
    changed = np.abs(on - off).max(axis=-1) > 8.0
    changed[rows, cols] = False
    assert changed.mean() < 0.01


def test_the_shader_uses_the_mirrors_reflectance():
    from pathlib import Path

    src = (Path(__file__).resolve().parents[2] / "shaders" / "core" / "scene.frag").read_text()
    assert f"const float MIRROR_REFLECTANCE = {M.REFLECTANCE};" in src


def test_the_quick_rejection_only_drops_what_the_exact_test_drops():
    """views() first asks _clearly_out_of_view (Python floats, with margins); whenever it says "out", the exact
    NumPy test must drop every glass too, over random car poses, eyes, lenses and aims."""
    from types import SimpleNamespace

    from rain_core.camera import Camera
    from rain_core.car_mesh import CAR_SPEC, DRIVER_EYE_LOCAL

    rng = np.random.default_rng(7)
    mirrors = M.DoorMirrors(ctx=None)
    mirrors._local_faces(CAR_SPEC)
    quick = shown = 0
    for _ in range(400):
        ego = SimpleNamespace(yaw=float(rng.uniform(-np.pi, np.pi)), spec=CAR_SPEC,
                              position=np.array([rng.uniform(-5, 5), 0.0, rng.uniform(0, 400)]))
        c, s = np.cos(ego.yaw), np.sin(ego.yaw)
        ego.model_matrix = lambda c=c, s=s, p=ego.position: np.array(
            [[c, 0.0, s, p[0]], [0.0, 1.0, 0.0, p[1]], [-s, 0.0, c, p[2]], [0.0, 0.0, 0.0, 1.0]])
        rot = ego.model_matrix()[:3, :3]
        eye = rot @ (np.asarray(DRIVER_EYE_LOCAL) + rng.normal(size=3) * 0.3) + ego.position
        fwd = rot @ np.array([rng.normal() * 0.8, rng.normal() * 0.2, -1.0])
        cam = Camera(position=eye, forward=fwd, fov_y_deg=float(rng.uniform(30, 100)), inside_car=True)
        shift_z = 0.0 if rng.random() < 0.5 else 100.0
        view = cam.view_matrix(shift=(0.0, 0.0, shift_z))
        proj = cam.projection_matrix(16 / 9)
        rc = SimpleNamespace(frame=SimpleNamespace(ego=ego, camera=cam), shift_z=shift_z, view=view,
                             projection=proj, view_proj=proj @ view, size=(320, 180), camera_position=eye)
        if M._clearly_out_of_view(mirrors._corners, ego, shift_z, rc.view_proj):
            quick += 1
            # the exact test alone (the quick one switched off) drops both glasses as well
            saved, M._clearly_out_of_view = M._clearly_out_of_view, lambda *a: False
            try:
                assert mirrors.views(rc) == []
            finally:
                M._clearly_out_of_view = saved
        else:
            shown += bool(mirrors.views(rc))
    assert quick > 50 and shown > 20  # both answers were exercised
