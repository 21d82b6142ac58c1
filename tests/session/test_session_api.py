"""Session round trip (issue 15): steps in seconds, captures with labels, boundary errors naming the argument."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.session import Weather, camera_intrinsics, camera_to_world, project

SIZE = (64, 40)
LABEL_KEYS = {"rain_mm_h", "wetness", "cracks", "puddles", "visibility_m", "wind_m_s", "wind_direction_deg",
              "wind_velocity_m_s", "hour", "ego_speed_m_s", "wiper_mode", "wiper_angle_rad", "camera_mode",
              "fov_y_deg", "camera_intrinsics", "camera_to_world", "seed", "time_s", "frame", "lightning_lux",
              "lightning_sky_cd_m2", "exposure_ev100"}


def test_round_trip_steps_weather_and_capture(session):
    sim = session(seed=3)
    sim.set_weather(Weather(rain_mm_h=8.0, hour=18.5, wind_m_s=3.0, wetness=1.0))
    for _ in range(3):
        sim.step(1 / 30)
    cap = sim.capture()
    assert cap.rgb.shape == (SIZE[1], SIZE[0], 3) and cap.rgb.dtype == np.uint8 and cap.rgb.std() > 2.0
    assert cap.depth_m is None and cap.masks == {}  # label images only when asked
    lab = cap.labels
    assert set(lab) == LABEL_KEYS
    assert lab["rain_mm_h"] == 8.0 and lab["hour"] == 18.5 and lab["wind_m_s"] == 3.0 and lab["wetness"] == 1.0
    assert lab["seed"] == 3 and lab["frame"] == 3 and lab["time_s"] == pytest.approx(0.1)
    assert lab["camera_mode"] == "driver" and len(lab["wiper_angle_rad"]) == 2
    assert 0.0 < lab["ego_speed_m_s"] < 40.0 and 100.0 < lab["visibility_m"] < 40_000.0
    # Displayed at the hour's meter less the eye's adaptation, within the stops the eye adapts.
    adapted = sim.scene.frame().lighting.ev100 - lab["exposure_ev100"]
    assert -3.0 <= adapted <= 3.0 and adapted != 0.0
    assert np.array_equal(sim.render().rgb, cap.rgb)  # render() is the last step's picture, not a new frame
    assert sim.weather.rain_mm_h == 8.0 and sim.settings.rain.rate_mm_h == 8.0


def test_more_rain_less_visibility_and_long_steps_are_sub_stepped(session):
    sim = session()
    sim.set_weather(Weather(rain_mm_h=1.0))
    sim.step(0.0)
    light = sim.capture().labels["visibility_m"]
    calls = []
    step = sim.scene.step
    sim.scene.step = lambda dt, drive=None: (calls.append(dt), step(dt, drive))
    sim.set_weather(Weather(rain_mm_h=50.0))
    sim.step(0.6)  # longer than MAX_FRAME_DT_S (0.25 s): three sub-steps of 0.2 s
    assert calls == pytest.approx([0.2, 0.2, 0.2]) and sim.time_s == pytest.approx(0.6)
    assert sim.capture().labels["visibility_m"] < light / 3


def test_settings_and_scenario_are_copied_and_applied(session, tmp_path):
    from rain_core.settings import Settings

    mine = Settings()
    mine.traffic.count = 0
    scenario = tmp_path / "night.toml"
    scenario.write_text("[time_of_day]\nhour = 22.0\n[quality]\nripple_grid = 64\n")
    sim = session(settings=mine, scenario=scenario)
    sim.set_weather(Weather(rain_mm_h=30.0))
    assert mine.rain.rate_mm_h == 2.0  # the caller's settings are not changed
    assert sim.settings.time_of_day.hour == 22.0 and sim.settings.traffic.count == 0
    bad = tmp_path / "bad.toml"
    bad.write_text("[rain]\nrate_mm_h = -4.0\n")
    with pytest.raises(ValueError, match="rain.rate_mm_h"):
        session(scenario=bad)


def test_camera_intrinsics_match_the_rendered_projection():
    """K and camera_to_world project world points to the same pixels as the renderer's GL matrices."""
    cam = look_at([1.0, 1.5, 3.0], [4.0, 0.5, -20.0], fov_y_deg=55.0)
    size = (160, 90)
    k, c2w = camera_intrinsics(cam.fov_y_deg, size), camera_to_world(cam)
    assert k[1, 1] == pytest.approx(45.0 / math.tan(math.radians(27.5))) and k[0, 0] == k[1, 1]
    assert np.allclose(c2w[:3, :3].T @ c2w[:3, :3], np.eye(3)) and np.linalg.det(c2w[:3, :3]) == pytest.approx(1.0)
    rng = np.random.default_rng(0)
    pts = np.array(cam.position) + 10.0 * np.asarray(cam.forward) + rng.uniform(-4.0, 4.0, (200, 3))
    clip = np.c_[pts, np.ones(len(pts))] @ (cam.projection_matrix(size[0] / size[1]) @ cam.view_matrix()).T
    ndc = clip[:, :2] / clip[:, 3:4]
    gl_px = np.c_[(ndc[:, 0] + 1.0) * 0.5 * size[0], (1.0 - ndc[:, 1]) * 0.5 * size[1]]  # top-left origin
    px, z = project(pts, k, c2w)
    assert np.allclose(px, gl_px, atol=1e-9)
    assert np.allclose(z, clip[:, 3])  # GL's w is the depth along the optical axis


def test_labels_camera_matches_the_frame(session):
    sim = session(camera="chase")
    sim.step(1 / 30)
    lab = sim.capture().labels
    cam = sim.scene.camera()
    assert lab["camera_mode"] == "chase" and lab["fov_y_deg"] == pytest.approx(min(sim.settings.camera.fov_deg, 65))
    assert np.allclose(lab["camera_intrinsics"], camera_intrinsics(lab["fov_y_deg"], SIZE))
    assert np.allclose(lab["camera_to_world"][:3, 3], cam.position, atol=0.5)  # the chase rig moved a little since
    fixed = session(camera=look_at([0.0, 20.0, 0.0], [0.0, 0.0, -30.0], fov_y_deg=40.0))
    fixed.step(1 / 30)
    lab = fixed.capture().labels
    assert lab["camera_mode"] == "fixed" and lab["camera_to_world"][1, 3] == 20.0 and lab["fov_y_deg"] == 40.0


def test_capture_with_labels(session):
    pytest.importorskip("rain_core.labels", reason="the label images come from rain_core.labels (issue 15)")
    sim = session()
    sim.set_weather(Weather(rain_mm_h=10.0, wetness=1.0))
    for _ in range(2):
        sim.step(1 / 30)
    cap = sim.capture(labels=True)
    assert cap.depth_m.shape == (SIZE[1], SIZE[0]) and cap.depth_m.dtype == np.float32
    assert set(cap.masks) == {"rain", "glass_water", "road_water", "spray", "class"}
    assert cap.labels["class_ids"]["sky"] in set(np.unique(cap.masks["class"])) | {cap.labels["class_ids"]["sky"]}
    assert cap.labels["road_water_ids"]["puddle"] == 3
    assert np.isinf(cap.depth_m[cap.masks["class"] == cap.labels["class_ids"]["sky"]]).all()
    assert set(sim.capture(labels=True, masks=("rain",)).masks) == {"rain"}


@pytest.mark.parametrize("kwargs, fragment", [
    ({"size": (8, 40)}, "size must be (width, height)"),
    ({"size": (64, 9000)}, "[16, 8192]"),
    ({"size": (64.0, 40)}, "size must be"),
    ({"size": "64x40"}, "size must be"),
    ({"seed": -1}, "seed must be an integer in [0, 2147483647]"),
    ({"seed": 1.5}, "seed must be"),
    ({"seed": True}, "seed must be"),
    ({"camera": "drone"}, "camera must be one of driver, chase"),
    ({"settings": {"rain": {}}}, "settings must be a rain_core.settings.Settings"),
])
def test_bad_arguments_name_the_argument_and_range(gl_ctx, kwargs, fragment):
    from rain_core import Session

    with pytest.raises(ValueError) as exc:
        Session(**{"size": SIZE, "ctx": gl_ctx, **kwargs})
    assert fragment in str(exc.value), str(exc.value)


@pytest.mark.parametrize("dt, fragment", [(-0.1, "dt_s must be finite and in [0, 3600] s"), (math.nan, "dt_s"),
                                          (math.inf, "dt_s"), ("0.1", "dt_s"), (4000.0, "[0, 3600]")])
def test_bad_steps_and_weather(session, dt, fragment):
    sim = session()
    with pytest.raises(ValueError, match=None) as exc:
        sim.step(dt)
    assert fragment in str(exc.value)
    with pytest.raises(ValueError, match="weather must be a rain_core.Weather"):
        sim.set_weather({"rain_mm_h": 3.0})
    with pytest.raises(ValueError, match=r"Weather.rain_mm_h: rain.rate_mm_h"):
        sim.set_weather(Weather(rain_mm_h=-3.0))


def test_closed_session_refuses_and_close_twice_is_safe(session):
    sim = session()
    sim.step(1 / 30)
    sim.close()
    sim.close()
    with pytest.raises(RuntimeError, match="closed"):
        sim.step(1 / 30)


def test_offline_quality_averages_sub_frames_across_the_shutter(session):
    from rain_core.session.offline import Accumulator, linear_to_srgb, srgb_to_linear

    values = np.arange(256, dtype=np.uint8)
    assert np.array_equal(linear_to_srgb(srgb_to_linear(values)), values)
    acc = Accumulator()
    acc.add(np.zeros((1, 1, 3), np.uint8))
    acc.add(np.full((1, 1, 3), 255, np.uint8))
    assert acc.result()[0, 0, 0] == 188  # half the light is sRGB 188, not 128

    sim = session()
    sim.settings.camera.exposure_s = 0.02
    calls, shown = [], []
    step, render = sim.scene.step, sim.scene.render
    sim.scene.step = lambda dt, drive=None: (calls.append(dt), step(dt, drive))
    sim.scene.render = lambda cam=None, draw=True: (shown.append(sim.settings.camera.exposure_s),
                                                     render(cam, draw))[1]
    sim.step(0.1, subframes=4)
    assert calls == pytest.approx([0.08, 0.005, 0.005, 0.005, 0.005])  # up to the shutter, then 4 slices of it
    assert shown == pytest.approx([0.02, 0.005, 0.005, 0.005, 0.005])  # each slice's streaks cover only it
    assert sim.settings.camera.exposure_s == 0.02 and sim.time_s == pytest.approx(0.1)
    averaged = sim.capture().rgb
    assert averaged.shape == (SIZE[1], SIZE[0], 3) and not np.array_equal(averaged, sim.scene.image())
    sim.step(1 / 30)
    assert np.array_equal(sim.capture().rgb, sim.scene.image())  # a plain step shows its own render
    with pytest.raises(ValueError, match=r"subframes must be an integer in \[1, 256\]"):
        sim.step(0.1, subframes=0)
