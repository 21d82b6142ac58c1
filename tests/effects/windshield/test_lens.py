"""The windshield's drops as lenses (issue 14): one drop seen through the close-up glass camera, in front of a
background the test paints into the frame the glass pass refracts (a vertical gradient, or a uniform grey)."""

import numpy as np

from rain_core.camera import glass_camera
from rain_core.car_mesh import DRIVER_EYE_LOCAL
from rain_core.effects.windshield import WindshieldEffect, drop_mass
from rain_core.settings import Settings

SIZE = 480
FOV_DEG = 30.0
RADIUS_M = 5e-3


def _render(gl_ctx, shaders, background: str) -> np.ndarray:
    """HDR luminance (SIZE, SIZE), row 0 at the top, of one resting drop at the image centre."""
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = 0.0
    s.wipers.mode = "off"
    s.traffic.count = 0
    s.quality.windshield_resolution = 2048  # 0.75 mm texels: the drop is ~13 texels across
    effect = WindshieldEffect(gl_ctx, s, seed=1, shaders=shaders)
    scene = Scene(gl_ctx, (SIZE, SIZE), s, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = 0.0
    g = effect.glass
    look = g.point_ahead_of(DRIVER_EYE_LOCAL)
    st = np.array([[(look - g.bottom_center) @ g.right, (look - g.bottom_center) @ g.up]])
    effect.sim._append(st, np.zeros((1, 2)), drop_mass(np.array([RADIUS_M])))
    draw = effect._draw_glass

    def painted(rc):  # the street behind the glass replaced by the test's background, far away (depth 1)
        rc.hdr.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
        w, h = rc.size
        y = (np.arange(h) + 0.5) / h  # GL row 0 is the bottom: black at the bottom, white at the top
        lum = np.repeat(y[:, None], w, axis=1) if background == "gradient" else np.full((h, w), 0.5)
        data = np.ones((h, w, 4), np.float16)
        data[..., :3] = lum[..., None]
        rc.hdr.color.write(data.tobytes())
        draw(rc)

    effect._draw_glass = painted
    scene.render(glass_camera(scene.ego, DRIVER_EYE_LOCAL, look, fov_y_deg=FOV_DEG))  # no step: the drop rests
    image = scene.renderer.hdr_image().mean(axis=-1)
    scene.release()
    return image


def _ellipse(scale: float) -> np.ndarray:
    """Pixels inside the drop's outline (scale 1) as the camera sees it: the raked glass foreshortens it."""
    focal_px = SIZE / (2.0 * np.tan(np.radians(FOV_DEG / 2.0)))
    dist = float(np.linalg.norm(_look_offset()))
    a = RADIUS_M * focal_px / dist * scale
    b = a * _foreshortening()
    y, x = np.mgrid[0:SIZE, 0:SIZE] + 0.5 - SIZE / 2.0
    return (x / a) ** 2 + (y / b) ** 2 <= 1.0


def _look_offset() -> np.ndarray:
    from rain_core.effects.windshield import GlassGeometry

    return GlassGeometry().point_ahead_of(DRIVER_EYE_LOCAL) - np.asarray(DRIVER_EYE_LOCAL)


def _foreshortening() -> float:
    from rain_core.effects.windshield import GlassGeometry

    d = _look_offset()
    return abs(float(np.dot(d / np.linalg.norm(d), GlassGeometry().normal)))


def test_a_drop_shows_the_gradient_behind_it_upside_down(gl_ctx, shaders):
    grad = _render(gl_ctx, shaders, "gradient")
    flat = _render(gl_ctx, shaders, "uniform")
    # The background's part of the picture: the same pixels against the grey minus against the gradient
    # cancel what does not come from the frame (the cabin by total reflection, the sky off screen, glints).
    d = grad - flat
    rows = np.arange(SIZE)[:, None] + np.zeros((1, SIZE))
    outside = ~_ellipse(3.0)
    # Around the drop the gradient is upright: brighter above (smaller row index).
    assert np.corrcoef(rows[outside].ravel(), d[outside].ravel())[0, 1] < -0.99
    inside = _ellipse(0.9) & (np.abs(d) > 1e-3)
    assert inside.sum() >= 20, "the drop shows too little of the street behind it"
    centre = SIZE / 2.0
    upper = d[inside & (rows + 0.5 < centre)].mean()
    lower = d[inside & (rows + 0.5 >= centre)].mean()
    # Inside the drop it is reversed, and a lens: its few pixels span far more of the gradient than they cover.
    span_behind = 2.0 * np.sqrt(inside.sum() / np.pi) * _foreshortening() / SIZE
    assert lower - upper > 2.0 * span_behind, (upper, lower)


def test_a_drop_against_a_uniform_background_differs_from_the_glass_around_it(gl_ctx, shaders):
    flat = _render(gl_ctx, shaders, "uniform")
    drop = flat[_ellipse(0.8)].mean()
    around = flat[_ellipse(4.0) & ~_ellipse(2.5)].mean()
    assert abs(around - 0.5) < 0.01  # dry glass shows the background as it is
    assert abs(drop - around) > 0.1 * around, (drop, around)


def test_glass_camera_looks_at_the_glass_ahead_of_the_eye_and_is_focused_there():
    from app.cameras import CameraModes
    from rain_core.effects.windshield import GlassGeometry
    from rain_core.settings import set_value
    from rain_core.vehicles import EgoCar

    car = EgoCar(position=np.array([3.0, 0.0, -20.0]), yaw=0.4)
    g = GlassGeometry()
    look = g.point_ahead_of(DRIVER_EYE_LOCAL)
    rel = look - g.bottom_center
    assert g.contains(np.array([rel @ g.right, rel @ g.up]))
    cam = glass_camera(car, DRIVER_EYE_LOCAL, look)
    assert cam.inside_car and cam.fov_y_deg < 20.0
    eye_to_look = car.to_world(look[None])[0] - cam.position
    assert cam.focus_m == np.float64(np.linalg.norm(eye_to_look))
    assert 0.2 < cam.focus_m < 1.0  # the glass is within arm's length
    assert np.allclose(cam.forward, eye_to_look / cam.focus_m)
    modes = CameraModes()
    modes.toggle_glass(car)
    assert modes.mode == "glass"
    assert modes.camera(car, DRIVER_EYE_LOCAL, 0.0).focus_m == cam.focus_m
    modes.cycle(car)  # C from the close-up goes back to the driver's seat; G toggles
    assert modes.mode == "driver"
    modes.toggle_glass(car)
    modes.toggle_glass(car)
    assert modes.mode == "driver"
    s = Settings()
    set_value(s, "camera.mode", "glass")  # a public settings value
    assert s.camera.mode == "glass"
