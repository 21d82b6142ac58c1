"""The windshield's water reads as water (issue 14), seen through the close-up glass camera in front of a
background the test paints into the frame the glass pass refracts: a drop is a clear lens with a darker rim and a
bright highlight; the misted film is blurrier than the view through a drop; a sliding drop leaves a trail of
beads that evaporate; the wiper's wet wake dries in streaks along the blade's motion."""


import numpy as np

from rain_core.camera import glass_camera
from rain_core.car_mesh import DRIVER_EYE_LOCAL
from rain_core.effects.windshield import WindshieldEffect, drop_mass
from rain_core.physics import RHO_WATER
from rain_core.settings import Settings

SIZE = 240
FOV_DEG = 8.0
RADIUS_M = 5e-3


def _setup(gl_ctx, shaders, background="uniform", resolution=1024, rate=0.0, wipers="off", speed=0.0):
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = rate
    s.wipers.mode = wipers
    s.traffic.count = 0
    s.quality.windshield_resolution = resolution
    effect = WindshieldEffect(gl_ctx, s, seed=1, shaders=shaders)
    scene = Scene(gl_ctx, (SIZE, SIZE), s, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = speed
    scene.autopilot.target_speed_m_s = speed
    g = effect.glass
    look = g.point_ahead_of(DRIVER_EYE_LOCAL)
    st = np.array([(look - g.bottom_center) @ g.right, (look - g.bottom_center) @ g.up])
    if background is not None:
        draw = effect._draw_glass

        def painted(rc):  # the street behind the glass replaced by the test's background, far away (depth 1)
            rc.hdr.fbo.clear(0.0, 0.0, 0.0, 1.0, depth=1.0)
            w, h = rc.size
            if background == "stripes":  # vertical stripes 4 px wide: high frequencies the blur removes
                lum = np.tile(((np.arange(w) // 4) % 2).astype(float)[None, :], (h, 1)) * 0.8 + 0.1
            else:
                lum = np.full((h, w), 0.5)
            data = np.ones((h, w, 4), np.float16)
            data[..., :3] = lum[..., None]
            rc.hdr.color.write(data.tobytes())
            draw(rc)

        effect._draw_glass = painted
    camera = glass_camera(scene.ego, DRIVER_EYE_LOCAL, look, fov_y_deg=FOV_DEG)
    return scene, effect, st, camera


def _image(scene, camera) -> np.ndarray:
    scene.render(camera)
    return scene.renderer.hdr_image().mean(axis=-1)


def _ellipse(scale: float) -> np.ndarray:
    """Pixels inside a resting drop's outline (× scale) at the image centre: the raked glass foreshortens it."""
    from rain_core.effects.windshield import GlassGeometry

    g = GlassGeometry()
    d = g.point_ahead_of(DRIVER_EYE_LOCAL) - np.asarray(DRIVER_EYE_LOCAL)
    dist = float(np.linalg.norm(d))
    focal_px = SIZE / (2.0 * np.tan(np.radians(FOV_DEG / 2.0)))
    a = RADIUS_M * focal_px / dist * scale
    b = a * abs(float(np.dot(d / dist, g.normal)))
    y, x = np.mgrid[0:SIZE, 0:SIZE] + 0.5 - SIZE / 2.0
    return (x / a) ** 2 + (y / b) ** 2 <= 1.0


def _one_drop(gl_ctx, shaders, background):
    scene, effect, st, camera = _setup(gl_ctx, shaders, background)
    effect.sim._append(st[None], np.zeros((1, 2)), drop_mass(np.array([RADIUS_M])))
    image = _image(scene, camera)  # no step: the drop rests
    scene.release()
    return image


def test_a_drop_has_a_darker_rim_and_a_bright_highlight(gl_ctx, shaders):
    img = _one_drop(gl_ctx, shaders, "uniform")
    around = img[_ellipse(3.0) & ~_ellipse(2.0)].mean()
    assert abs(around - 0.5) < 0.01
    centre = img[_ellipse(0.45)].mean()
    rim = img[_ellipse(0.95) & ~_ellipse(0.7)].mean()
    print("rim", rim, "centre", centre)
    assert rim < 0.7 * centre, (rim, centre)
    top = img[_ellipse(0.95)].max()
    print("highlight", top)
    assert top > 2.0 * centre, (top, centre)  # a small bright highlight from the sky


def _hf(img: np.ndarray, mask: np.ndarray) -> float:
    """Mean squared horizontal second difference over the mask (high-frequency energy)."""
    lap = np.zeros_like(img)
    lap[:, 1:-1] = img[:, 2:] - 2.0 * img[:, 1:-1] + img[:, :-2]
    return float(np.mean(lap[mask] ** 2))


def test_the_misted_film_is_blurrier_than_the_view_through_a_drop(gl_ctx, shaders):
    scene, effect, st, camera = _setup(gl_ctx, shaders, "stripes")
    sim = effect.sim
    sim.film[:] = RHO_WATER * 20e-6 * sim.glass.cells()[1]  # 20 µm of film everywhere: misted glass
    sim._append(st[None], np.zeros((1, 2)), drop_mass(np.array([RADIUS_M])))
    img = _image(scene, camera)
    scene.release()
    drop = _hf(img, _ellipse(0.6))
    film = _hf(img, _ellipse(3.5) & ~_ellipse(2.0))
    print("hf drop", drop, "film", film)
    assert film < 0.25 * drop, (film, drop)


def _film_channels(effect) -> np.ndarray:
    """The film texture (n, n, 2): film (µm), bead-trail density (0..1); row iv, column iu."""
    n = effect.resolution
    tex = effect._film[effect._film_index].color
    return np.frombuffer(tex.read(), np.float16).reshape(n, n, 2).astype(np.float64)


def test_a_sliding_drop_leaves_beads_that_evaporate(gl_ctx, shaders):
    scene, effect, st, camera = _setup(gl_ctx, shaders, None, resolution=512)
    sim = effect.sim
    start = st + np.array([0.0, 0.05])
    sim._append(start[None], np.array([[0.0, -0.2]]), drop_mass(np.array([4e-3])))
    for _ in range(20):
        scene.step(1 / 30)
        scene.render(camera)
    assert sim.count >= 1
    end = sim.pos[np.argmax(sim.radius())]
    run = float(np.linalg.norm(end - start))
    assert run > 0.01, run  # it slid
    n = effect.resolution
    beads = _film_channels(effect)[..., 1]
    # Along the path, between the start and 5 mm behind the drop: beads left behind.
    path = start[None] + (end - start)[None] * np.linspace(0.05, 1.0 - 0.005 / run, 12)[:, None]
    uv = effect.glass.to_uv(path)
    along = beads[(uv[:, 1] * n).astype(int), (uv[:, 0] * n).astype(int)]
    print("beads along the path", np.round(along, 2))
    assert np.mean(along > 0.5) > 0.8, along
    # Beside the path: none.
    side = effect.glass.to_uv(path + np.array([0.02, 0.0]))
    assert beads[(side[:, 1] * n).astype(int), (side[:, 0] * n).astype(int)].max() == 0.0
    seen = _image(scene, camera)
    sim.vel[:] = 0.0
    for _ in range(70):  # 17.5 s: the beads where it slid evaporate (BEAD_LIFE_S), one by one
        scene.step(0.25)
        scene.render(camera)
    left = _film_channels(effect)[..., 1][(uv[:, 1] * n).astype(int), (uv[:, 0] * n).astype(int)]
    print("beads left", left.max())
    assert left.max() < 0.02
    assert np.all(np.isfinite(seen))
    scene.release()


def test_the_wipers_wake_dries_in_streaks_along_the_blade(gl_ctx, shaders):
    scene, effect, st, camera = _setup(gl_ctx, shaders, None, resolution=512, wipers="low", speed=15.0)
    sim = effect.sim
    sim.film[:] = RHO_WATER * 5e-6 * sim.glass.cells()[1]  # a wet glass: 5 µm of film
    blade = sim.blades[0]
    steps = 0
    while steps < 120:  # render until the first blade has swept past the middle of its arc
        scene.step(1 / 30)
        scene.render(camera)
        steps += 1
        if sim.wipers.phase is not None and sim.wipers.phase > 0.3:
            break
    angle = float(blade.angle(sim.wipers.progress))
    n = effect.resolution
    # The swept region behind the blade, in polar coordinates about its pivot: rows along the blade (radius),
    # columns across it (angle, a few degrees behind the blade).
    r = np.linspace(blade.r_inner_m + 0.05, blade.r_outer_m - 0.05, 200)
    phis = angle - np.radians(np.linspace(4.0, 12.0, 24)) * (1.0 if sim.wipers.phase < 0.5 else -1.0)

    def polar(film):
        pts = np.asarray(blade.pivot)[None, None] + r[:, None, None] * np.stack(
            [np.cos(phis), np.sin(phis)], axis=-1)[None]
        uv = effect.glass.to_uv(pts)
        iu = np.clip((uv[..., 0] * n).astype(int), 0, n - 1)
        iv = np.clip((uv[..., 1] * n).astype(int), 0, n - 1)
        return film[iv, iu]

    wake = polar(_film_channels(effect)[..., 0])
    along = np.var(np.diff(wake, axis=0))  # along the blade: across the streaks
    across = np.var(np.diff(wake, axis=1))  # along the blade's motion: along each streak
    print("wake mean", wake.mean(), "var along the blade", along, "across", across)
    assert wake.mean() > 0.05
    assert along > 1.3 * across, (along, across)
    sim.frame_sweeps = lambda: [None] * len(sim.blades)  # the texture sees no further strokes
    for _ in range(12):  # 3 s later: the thin parts have dried first, the wake is fading
        scene.step(0.25)
        scene.render(camera)
    later = polar(_film_channels(effect)[..., 0])
    print("wake mean later", later.mean(), "var along", np.var(np.diff(later, axis=0)))
    assert later.mean() < 0.7 * wake.mean(), (later.mean(), wake.mean())
    assert np.var(np.diff(later, axis=0)) < 0.5 * along
    scene.release()
