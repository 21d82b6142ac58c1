"""Wakes ahead of the driver (issue 14): the ripple window reaches ~20 m ahead of the ego car, so the wake of a
car 15 m ahead crossing a puddle is simulated there and changes the driver's picture; wakes keep the water's
volume; where the window sits for each camera."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core.camera import look_at
from rain_core.effects.ripples import RippleField, window_centre_xz, window_offset_m
from rain_core.effects.ripples.constants import WINDOW_EDGE_FADE

SIZE = (256, 144)
SPEED_M_S = 14.0  # 50 km/h, both cars
GAP_M = 15.0  # the lead car's centre ahead of the ego car's
# The default street (seed 1) at puddle_amount 0.8 holds water in both wheel tracks of lane 0 over
# z = 486.5 … 496.5 m: the ego car starts at 512 m with the lead car at 497 m, so after STEPS frames the lead
# car has just crossed the puddle and its wake lies 7–14 m ahead of the driver.
EGO_START_Z_M = 512.0
STEPS = 18
FPS = 30.0


def _driver_scene(gl_ctx):
    from rain_core import layout
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    effects = ("road", "ripples", "rainfall", "spray", "windshield", "atmosphere", "drips", "lightning", "rainbow")
    values = {**{f"{e}.enabled": e in ("road", "ripples") for e in effects},
              "rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 1.0, "road.puddle_amount": 0.8,
              "rain.rate_mm_h": 0.0, "time_of_day.hour": 12.0, "camera.mode": "driver", "traffic.count": 1,
              "quality.ripple_grid": 512}
    for path, value in values.items():
        set_value(settings, path, value)
    scene = Scene(gl_ctx, SIZE, settings, seed=1, gpu_timing=False)
    ripples = next(e for e in scene.effects if e.name == "ripples")
    ripples.backend = "numpy32"  # "auto" would time the backends: pinned, as in the golden views
    lane_x = layout.LANE_CENTRES_X[0]
    ego = scene.ego
    ego.position = np.array([lane_x, 0.0, EGO_START_Z_M])
    ego.speed_m_s = SPEED_M_S
    ego.previous_wheel_contacts = ego.wheel_contacts()
    lead = scene.traffic.vehicles[0]
    lead.position = np.array([lane_x, 0.0, EGO_START_Z_M - GAP_M])
    lead.yaw, lead.speed_m_s = layout.LANE_YAW[0], SPEED_M_S
    lead.previous_wheel_contacts = lead.wheel_contacts()
    scene.traffic.lanes[0] = 0
    scene.traffic.desired_speeds_m_s[0] = SPEED_M_S
    return scene, ripples


def _hold_speed(scene):
    """Drive straight on, the throttle holding SPEED_M_S."""
    throttle = float(np.clip(0.3 + 0.5 * (SPEED_M_S - scene.ego.speed_m_s), 0.0, 1.0))
    return SimpleNamespace(throttle=throttle, brake=0.0, steer=0.0, reverse=False)


def _road_band(camera, size, near_m, far_m) -> np.ndarray:
    """(h, w) bool: pixels whose ray meets the road plane (y = 0, |x| < 7 m) between near_m and far_m ahead of
    the camera along its horizontal heading."""
    w, h = size
    r, u, f = camera.basis()
    t = math.tan(math.radians(camera.fov_y_deg) / 2.0)
    ys = (1.0 - 2.0 * (np.arange(h) + 0.5) / h) * t
    xs = (2.0 * (np.arange(w) + 0.5) / w - 1.0) * t * w / h
    gx, gy = np.meshgrid(xs, ys)
    d = f + gx[..., None] * r + gy[..., None] * u
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(d[..., 1] < -1e-6, -camera.position[1] / d[..., 1], np.nan)
    p = camera.position + s[..., None] * d
    heading = np.array([f[0], 0.0, f[2]]) / math.hypot(f[0], f[2])
    along = (p - camera.position) @ heading
    return (along >= near_m) & (along <= far_m) & (np.abs(p[..., 0]) < 7.0)


@pytest.fixture(scope="module")
def driver_wake(gl_ctx):
    """The scene after STEPS frames: the frame with ripples and the same frame without them, the band of road
    10–20 m ahead, the field and the ego car."""
    with gl_ctx:
        scene, ripples = _driver_scene(gl_ctx)
        try:
            for _ in range(STEPS):
                scene.step(1.0 / FPS, drive=_hold_speed(scene))
                frame = scene.render()
            with_ripples = np.asarray(scene.image()[..., :3], dtype=np.int16)
            scene.settings.ripples.enabled = False  # the same frame again, the road's water left flat
            scene.render()
            without = np.asarray(scene.image()[..., :3], dtype=np.int16)
            lead = scene.traffic.vehicles[0]
            yield SimpleNamespace(on=with_ripples, off=without, band=_road_band(frame.camera, SIZE, 10.0, 20.0),
                                  field=ripples.field, ego_xz=(float(scene.ego.position[0]),
                                                               float(scene.ego.position[2])),
                                  gap_m=float(scene.ego.position[2] - lead.position[2]),
                                  track_x=float(lead.wheel_contacts()[0, 0]))
        finally:
            scene.release()


def test_the_window_reaches_20_m_ahead_of_the_driver(driver_wake):
    field, (x, z) = driver_wake.field, driver_wake.ego_xz
    ox, oz = field.origin_xz
    # Heading −z: the window's far edge is its lowest z.
    assert z - oz >= 20.0, "the window must reach 20 m ahead of the driver"
    assert oz + field.extent_m - z >= 2.3, "and keep the ego car (its rear 2.3 m behind the centre) inside"
    assert ox <= x <= ox + field.extent_m


def test_the_wake_15_m_ahead_is_simulated(driver_wake):
    assert 13.0 < driver_wake.gap_m < 17.0
    field = driver_wake.field
    ex, ez = driver_wake.ego_xz
    # The lead car's front wheels crossed this point 0.1 s ago: its trough (film ~2 mm × 1.4 at 14 m/s).
    ix, iz = (int(round(float(v))) for v in field.world_to_cell(driver_wake.track_x, ez - 15.0))
    assert 3 <= ix < field.n - 3 and 3 <= iz < field.n - 3, "15 m ahead lies inside the window"
    near = np.abs(field.height[iz - 3:iz + 4, ix - 3:ix + 4]).max()
    assert near > 5e-4, f"height 15 m ahead on the lead car's track is {near * 1e3:.4f} mm"


def test_the_wake_changes_the_drivers_view_10_to_20_m_ahead(driver_wake):
    d = np.abs(driver_wake.on - driver_wake.off).max(axis=2)
    band = driver_wake.band
    assert band.sum() > 1000  # the road 10–20 m ahead is in view (~2.4k of 37k pixels at 256×144)
    changed = (d > 8)[band].mean()  # 8/255: a change anyone sees on a wet, mirroring road
    # Measured 4.1 % (the tracks are ~0.7 m wide with their side crests, a few pixels here; 0.27 % of the
    # rest of the picture, its reflections); the window centred on the car (before issue 14) gave exactly 0.
    assert changed > 0.005, f"only {changed:.2%} of the road 10–20 m ahead changed"
    # The change is the wake on the road ahead, not a shift of the whole picture.
    assert (d > 8)[~band].mean() < 0.2 * changed


def test_window_placement_per_camera():
    ego_xz, heading = (1.75, 500.0), (0.0, -1.0)  # driving towards −z
    extent, half_len = 25.0, 2.3
    fade = WINDOW_EDGE_FADE * extent

    def span(camera):
        cx, cz = window_centre_xz(ego_xz, heading, extent, camera.position, camera.basis()[2],
                                  car_half_length_m=half_len)
        assert cx == pytest.approx(ego_xz[0])
        ahead = ego_xz[1] - cz  # the centre's distance ahead of the car
        return ahead - extent / 2, ahead + extent / 2  # rear and front edges, m ahead of the car's centre

    driver = look_at((1.4, 1.23, 500.43), (1.4, 1.23, 480.0), 40.0)
    rear, front = span(driver)
    assert rear == pytest.approx(-half_len - fade) and front > 20.0
    chase = look_at((1.75, 2.6, 507.0), (1.75, 1.0, 494.0), 60.0)
    rear, front = span(chase)
    assert rear == pytest.approx(-7.0 - fade) and front > 15.0  # behind the chase camera, over the car
    backwards = look_at((1.75, 2.6, 493.0), (1.75, 1.0, 506.0), 60.0)
    assert span(backwards) == pytest.approx((-extent / 2, extent / 2))  # looking back: centred, as before
    far_behind = look_at((1.75, 40.0, 800.0), (1.75, 0.0, 700.0), 60.0)
    assert span(far_behind) == pytest.approx((-extent / 2, extent / 2))
    assert window_offset_m(5.0, -0.4, half_len) == 0.0  # a 5 m window cannot reach past the car: centred
    assert window_centre_xz(ego_xz, heading, extent) == ego_xz  # no camera: centred


def test_a_wake_keeps_the_water_volume():
    field = RippleField(n=128, extent_m=12.7, backend="reference")
    field.recenter(0.0, 0.0)
    field.add_wheel_sweep((-3.0, 0.5), (3.0, 0.5), speed_m_s=14.0, film_depth_mm=3.0, tire_width_m=0.225)
    h = field.height
    # Net volume under 1 % of the volume moved (a trough alone: −100 %).
    assert abs(h.sum()) < 0.01 * np.abs(h).sum()
    # The water pushed out of the track stands beside it (the side waves, within 0.5 m), not on it.
    ix, iz = (round(float(v)) for v in field.world_to_cell(0.0, 0.5))
    across = h[:, ix]
    assert across[iz] < -2e-3 and across.max() > 1e-3
    assert abs(int(np.argmax(across)) - iz) * field.cell_m < 0.5
