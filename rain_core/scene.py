"""A whole driving scene: settings → weather → world, ego car, traffic → effects → renderer (DESIGN §1).

The app, the headless runs and the benchmarks all drive the same ``Scene``, so what is measured is what is shown.
"""

from __future__ import annotations

import time

import numpy as np

from rain_core import checks, layout
from rain_core.atmosphere import sky_overcast
from rain_core.camera import Camera, ChaseRig, driver_camera, glass_camera
from rain_core.car_mesh import DRIVER_EYE_LOCAL
from rain_core.checks import MAX_FRAME_DT_S  # noqa: F401  (re-exported: older imports of rain_core.scene keep working)
from rain_core.collision import StreetCollider, street_solids
from rain_core.effects import default_effects
from rain_core.effects.lightning.storm import Storm
from rain_core.gfx.frame import Frame
from rain_core.gfx.renderer import Renderer
from rain_core.lighting import lighting_for_hour, with_sky_light
from rain_core.settings import Settings
from rain_core.traffic import Autopilot, Traffic
from rain_core.vehicles import EgoCar
from rain_core.weather import Weather
from rain_core.world import shared_world


class Scene:
    """Owns the simulation state and the renderer for one street.

    ``step(dt_s, drive=None)`` advances time (``drive``: a DriveInput-like object with throttle, brake, steer,
    reverse; None lets the autopilot drive). ``render(camera=None)`` draws a frame (default: the camera mode in
    settings) and returns it (``render(draw=False)``: the effects' simulations advance, nothing is drawn);
    ``image()`` gives the tone-mapped uint8 picture of the last frame drawn.
    """

    def __init__(self, ctx, size: tuple[int, int], settings: Settings | None = None, seed: int = 1,
                 effects=None, gpu_timing: bool = True):
        self.ctx = ctx
        self.settings = settings if settings is not None else Settings()
        self.settings.validate()
        self.seed = int(seed)
        self.world = shared_world(seed=self.seed)  # read-only, shared by the scenes of this seed
        self.ego = EgoCar(position=np.array([layout.LANE_CENTRES_X[0], 0.0, layout.PERIOD_M * 0.5]),
                          speed_m_s=16.0)
        self.autopilot = Autopilot(lane_index=0, target_speed_m_s=22.0, seed=self.seed)
        self.collider = StreetCollider(street_solids(self.world))  # kerbs, façades, posts: the car stays in
        self.ego.collider = self.collider
        self.traffic = Traffic(count=self.settings.traffic.count, seed=self.seed + int(self.settings.traffic.seed),
                               ego=self.ego)
        self.weather = Weather.from_settings(self.settings)
        self.weather_state = self.weather.state
        self.storm = Storm(seed=self.seed)  # lightning: weather like the rain, drawn by the lightning effect
        self.time_s = 0.0
        self.last_dt_s = 0.0
        self.step_cpu_ms = 0.0  # the last step's CPU time (ms)
        self.chase = ChaseRig()
        self.effects = default_effects(ctx, self.settings, self.seed) if effects is None else list(effects)
        self.renderer = Renderer(ctx, size, self.world, effects=self.effects, gpu_timing=gpu_timing)

    # --- simulation -----------------------------------------------------------------------------------------
    def set_traffic_count(self, count: int):
        if count != len(self.traffic.vehicles):
            self.traffic = Traffic(count=count, seed=self.seed + int(self.settings.traffic.seed), ego=self.ego)

    def step(self, dt_s: float, drive=None) -> None:
        """Advance the scene by dt_s seconds (clamped to [0, MAX_FRAME_DT_S]; non-finite → ValueError). Its CPU
        time (ms, wall clock, as the renderer's passes take theirs) is ``step_cpu_ms``."""
        t0 = time.perf_counter()
        dt_s = checks.time_step(dt_s)
        self.weather.apply_settings(self.settings)
        self.weather_state = self.weather.step(dt_s, self.settings.rain.rate_mm_h)
        if drive is None:
            throttle, brake, steer = self.autopilot.controls(self.ego, dt_s, others=self.traffic.vehicles)
            self.ego.step(dt_s, throttle, brake, steer, reverse=self.autopilot.reverse)
        else:
            self.ego.step(dt_s, drive.throttle, drive.brake, drive.steer, reverse=drive.reverse)
        self.set_traffic_count(self.settings.traffic.count)
        self.traffic.step(dt_s)
        self.time_s += dt_s
        self.last_dt_s = dt_s
        self.step_cpu_ms = (time.perf_counter() - t0) * 1e3

    @property
    def vehicles(self) -> list:
        return [self.ego, *self.traffic.vehicles]

    def camera(self, mode: str | None = None) -> Camera:
        mode = mode or self.settings.camera.mode
        view = self.settings.camera
        fov = view.fov_deg
        if mode == "driver":
            return driver_camera(self.ego, DRIVER_EYE_LOCAL, fov_y_deg=view.driver_fov_deg,
                                 pitch_deg=view.driver_pitch_deg)
        if mode == "glass":  # the windshield close-up from the driver's eye
            if getattr(self, "_glass_look", None) is None:
                from rain_core.effects.windshield.glass import GlassGeometry

                self._glass_look = GlassGeometry(self.ego.spec).point_ahead_of(DRIVER_EYE_LOCAL)
            return glass_camera(self.ego, DRIVER_EYE_LOCAL, self._glass_look)
        return self.chase.camera(self.ego, self.last_dt_s, fov_y_deg=min(fov, 65.0), keep_inside=self.collider)

    def frame(self, camera: Camera | None = None) -> Frame:
        # Rain greys and darkens the sky (atmosphere effect's model; manual override in its settings).
        overcast = sky_overcast(self.settings.atmosphere, self.weather_state.rate_mm_h)
        lighting = lighting_for_hour(self.settings.time_of_day.hour, overcast)
        raining = self.weather_state.rate_mm_h > 0.0
        camera = camera or self.camera()
        flash = self.storm.frame_view(self.settings, self.time_s, self.last_dt_s, camera.position,
                                      self.weather_state.rate_mm_h)
        headlights = raining or lighting.night_factor > 0.05
        if flash is not None:  # the lit cloud base brightens the sky, and with it the airlight and the ambient
            lighting = with_sky_light(lighting, flash.sky_cd_m2)
        return Frame(time_s=self.time_s, dt_s=self.last_dt_s, camera=camera, lighting=lighting,
                     world=self.world, ego=self.ego, vehicles=self.vehicles, weather=self.weather_state,
                     settings=self.settings, headlights_on=headlights, flash=flash, storm=self.storm)

    def render(self, camera: Camera | None = None, draw: bool = True) -> Frame:
        """The frame of the current state, rendered (``draw=False``: its simulations advance, nothing is drawn;
        see ``Renderer.render``)."""
        frame = self.frame(camera)
        self.renderer.render(frame, draw)
        return frame

    def image(self) -> np.ndarray:
        return self.renderer.image()

    def release(self):
        self.renderer.release()
