"""Headless frames are real pictures: sky and road differ, day and night differ, no NaN, deterministic."""

import numpy as np
import pytest

from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

SIZE = (128, 72)


def make_scene(gl_ctx, hour=12.0, camera="driver", seed=1, rate=0.0, auto_exposure=True):
    settings = Settings()
    set_value(settings, "camera.auto_exposure", auto_exposure)
    set_value(settings, "time_of_day.hour", hour)
    set_value(settings, "camera.mode", camera)
    set_value(settings, "rain.rate_mm_h", rate)
    return Scene(gl_ctx, SIZE, settings=settings, seed=seed)


def run(scene, frames=10, dt=1 / 30):
    for _ in range(frames):
        scene.step(dt)
    scene.render()
    return scene.image()


@pytest.fixture(scope="module")
def noon_chase(gl_ctx):
    with gl_ctx:  # module fixtures run before the per-test fixture that makes the context current
        scene = make_scene(gl_ctx, camera="chase")
        image = run(scene)
    yield scene, image
    scene.release()


def test_frame_is_a_real_picture(noon_chase):
    scene, image = noon_chase
    assert image.shape == (SIZE[1], SIZE[0], 3) and image.dtype == np.uint8
    sky = image[: SIZE[1] // 8, 2 * SIZE[0] // 5: 3 * SIZE[0] // 5].reshape(-1, 3).mean(axis=0)
    road = image[-SIZE[1] // 6:, SIZE[0] // 3: 2 * SIZE[0] // 3].reshape(-1, 3).mean(axis=0)
    assert sky[2] > sky[0]  # a blue day sky above
    assert np.abs(sky - road).max() > 30  # and something else below
    assert image.std() > 20
    assert np.isfinite(scene.renderer.hdr_image()).all()


def test_passes_are_recorded(noon_chase):
    scene, _ = noon_chase
    names = [row[0] for row in scene.renderer.pass_table()]
    assert "scene" in names and names[-1] == "tonemap"
    for _name, ran, cpu_ms, gpu_ms, _note in scene.renderer.pass_table():
        if ran:
            assert cpu_ms >= 0 and (gpu_ms is None or gpu_ms >= 0)


def test_update_rows_carry_the_effects_notes(gl_ctx):
    """An effect's update row carries its describe(), taken when the table is asked for (not every frame)."""
    scene = make_scene(gl_ctx, rate=8.0)
    try:
        run(scene, frames=2)
        notes = {name: note for name, ran, _cpu, _gpu, note in scene.renderer.pass_table()
                 if name.endswith(".update")}
        assert "rainfall.update" in notes
        for effect in scene.effects:
            if f"{effect.name}.update" in notes:
                assert notes[f"{effect.name}.update"] == effect.describe()
        assert "streaks drawn" in notes["rainfall.update"]
    finally:
        scene.release()


def test_night_is_darker_but_lamps_light_the_road(gl_ctx):
    """At the hour's meter (automatic exposure lifts the night towards the day's key: tests/gfx/test_exposure.py)."""
    day = make_scene(gl_ctx, hour=12.0, auto_exposure=False)
    night = make_scene(gl_ctx, hour=22.0, auto_exposure=False)
    day_img, night_img = run(day, 3).astype(float), run(night, 3).astype(float)
    assert night_img.mean() < 0.6 * day_img.mean()
    assert night_img.max() > 200  # lamps and lit windows still glow
    day.release()
    night.release()


def test_same_seed_same_frame_other_seed_other_frame(gl_ctx):
    images = []
    for seed in (5, 5, 6):
        scene = make_scene(gl_ctx, camera="chase", seed=seed)
        images.append(run(scene, 20))
        scene.release()
    np.testing.assert_array_equal(images[0], images[1])
    assert np.abs(images[0].astype(int) - images[2]).mean() > 1.0


def test_driver_view_shows_cabin_and_road(gl_ctx):
    scene = make_scene(gl_ctx, camera="driver")
    image = run(scene, 5)
    assert scene.frame().camera.inside_car
    # The bottom rows are the car's hood/dashboard, much darker than the sky at the top.
    assert image[-8:].mean() < image[:8].mean()
    scene.release()


def test_bad_dt_is_rejected_and_huge_dt_is_clamped(gl_ctx):
    scene = make_scene(gl_ctx)
    with pytest.raises(ValueError, match="dt_s"):
        scene.step(float("nan"))
    scene.step(1e6)
    assert scene.last_dt_s <= 0.25
    scene.render()
    assert np.isfinite(scene.renderer.hdr_image()).all()
    scene.release()


def test_sun_shadows_darken_the_road_under_the_bridge_and_skip_at_night(gl_ctx):
    from rain_core import layout
    from rain_core.camera import look_at

    scene = make_scene(gl_ctx, hour=12.0)
    scene.step(1 / 30)

    def road_luminance(z):
        scene.render(look_at((3.0, 2.5, z), (3.0, 0.0, z - 0.5), fov_y_deg=30))
        return float(scene.renderer.hdr_image()[30:42, 58:70].mean())

    under = road_luminance(layout.BRIDGE_Z_M)
    open_road = road_luminance(layout.BRIDGE_Z_M + 120.0)
    assert under < 0.5 * open_road
    assert {n: r for n, r, *_ in scene.renderer.pass_table()}["shadow"] is True
    scene.release()
    night = make_scene(gl_ctx, hour=23.0)
    night.step(1 / 30)
    night.render()
    assert {n: r for n, r, *_ in night.renderer.pass_table()}["shadow"] is False
    night.release()


def test_changing_the_traffic_releases_old_meshes_and_draws_new_ones(gl_ctx):
    scene = make_scene(gl_ctx, camera="chase")
    for count in (5, 2, 7):
        scene.settings.traffic.count = count
        scene.step(1 / 30)
        scene.render()
        cached = scene.renderer.scene._vehicles
        assert set(cached) == {id(v) for v in scene.vehicles}
        for key, (vehicle, _mesh) in cached.items():
            assert id(vehicle) == key  # the cache holds the very vehicle it drew
    scene.release()
