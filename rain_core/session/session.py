"""``Session``: the scripting API — a street in rain, stepped in seconds, captured with its ground truth.

```python
from rain_core import Session, Weather

with Session(size=(320, 180), seed=1, camera="driver") as sim:
    sim.set_weather(Weather(rain_mm_h=8.0, hour=18.5, wind_m_s=3.0))
    for _ in range(30):
        sim.step(1 / 30)
    cap = sim.capture(labels=True)     # cap.rgb, cap.depth_m, cap.masks, cap.labels
```

A thin owner of a ``rain_core.scene.Scene`` (``sim.scene``) and, unless one is given, its headless EGL context.
Every step runs the renderer: the effects (spray, ripples, the water on the glass) advance in its updates and in
the GL stages that carry their state. ``step(dt_s, draw=False)`` runs only those, for a step whose picture is
not kept (``sim.step(1 / 30, draw=i == 29)`` in the loop above keeps the last): the same simulation, no picture.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from rain_core import checks
from rain_core.camera import Camera
from rain_core.checks import MAX_FRAME_DT_S
from rain_core.session.capture import Capture, camera_intrinsics, camera_to_world
from rain_core.session.offline import Accumulator, check_subframes
from rain_core.session.weather import Weather
from rain_core.settings import Settings, field_info, load_scenario, set_value

CAMERAS = ("driver", "chase", "glass")
MIN_SIZE, MAX_SIZE = 16, 8192  # pixels per side, as the command line's --size
MAX_SEED = 2**31 - 1
MAX_STEP_S = 3600.0  # s, longest single step() (sub-stepped by MAX_FRAME_DT_S, one render each)


_LUMA = (0.2126, 0.7152, 0.0722)  # Rec. 709 luminance weights


def check_size(size) -> tuple[int, int]:
    """(W, H) in pixels, each an int in [MIN_SIZE, MAX_SIZE]; ValueError naming ``size`` otherwise."""
    ok = isinstance(size, tuple | list) and len(size) == 2 and all(
        isinstance(v, int | np.integer) and not isinstance(v, bool) and MIN_SIZE <= v <= MAX_SIZE for v in size)
    if not ok:
        raise ValueError(f"size must be (width, height) in pixels, each an integer in [{MIN_SIZE}, {MAX_SIZE}], "
                         f"got {checks.quote(size)}")
    return int(size[0]), int(size[1])


def check_seed(seed) -> int:
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be an integer in [0, {MAX_SEED}], got {checks.quote(seed)}")
    return int(seed)


def check_camera(camera) -> str | Camera:
    if isinstance(camera, Camera) or camera in CAMERAS:
        return camera
    raise ValueError(f"camera must be one of {', '.join(CAMERAS)} or a rain_core.camera.Camera, "
                     f"got {checks.quote(camera)}")


class Session:
    """One street, one ego car on autopilot, the rain effects, rendered offscreen.

    size: (W, H) pixels, each in [16, 8192]. seed: world, traffic and rain seed in [0, 2³¹−1]. camera: "driver"
    (in the cabin, through the glass), "chase" (behind the car) or a fixed rain_core.camera.Camera. settings: a
    Settings to start from (copied; ``sim.settings`` is the live one). scenario: a TOML scenario file applied on
    top of ``settings``. ctx: a moderngl context to render with (default: a new headless EGL one, released
    with the session). Bad arguments raise ValueError naming the argument and its range.
    """

    def __init__(self, size=(1280, 720), seed: int = 1, camera="driver", settings: Settings | None = None,
                 scenario: str | Path | None = None, ctx=None, gpu_timing: bool = False):
        size, seed, camera = check_size(size), check_seed(seed), check_camera(camera)
        if settings is not None and not isinstance(settings, Settings):
            raise ValueError(f"settings must be a rain_core.settings.Settings or None, "
                             f"got {type(settings).__name__}")
        settings = settings.copy() if settings is not None else Settings()
        if scenario is not None:
            settings = load_scenario(scenario, base=settings)
        self._fixed_camera = camera if isinstance(camera, Camera) else None
        if self._fixed_camera is None:
            set_value(settings, "camera.mode", camera)
        self._own_ctx = ctx is None
        if ctx is None:
            from rain_core.gfx.context import create_headless_context

            ctx = create_headless_context()
        from rain_core.scene import Scene

        try:
            self.scene = Scene(ctx, size, settings=settings, seed=seed, gpu_timing=gpu_timing)
        except BaseException:
            if self._own_ctx:
                ctx.release()
            raise
        self.ctx = ctx
        self.size = size
        self.seed = seed
        self.frame_index = 0  # step() calls so far
        self._frame = None  # the Frame last rendered
        self._rgb = None  # the averaged picture of an offline-quality step (None: the last render)
        self._undrawn = False  # the last step was not drawn (step(draw=False)): nothing to capture
        self._closed = False

    # --- context manager ------------------------------------------------------------------------------------
    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Release the scene's GL objects (and the context if the session made it). Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        if "rain_core.labels" in sys.modules:  # labels ran only if capture(labels=True) imported them
            sys.modules["rain_core.labels"].release_labels(self.scene)
        self.scene.release()
        if self._own_ctx:
            self.ctx.release()

    def _check_open(self):
        if self._closed:
            raise RuntimeError("this Session is closed (use it inside its with block)")

    # --- weather --------------------------------------------------------------------------------------------
    @property
    def settings(self) -> Settings:
        """The live settings (edit with rain_core.settings.set_value; they apply on the next step)."""
        return self.scene.settings

    @property
    def weather(self) -> Weather:
        """The weather the settings describe now."""
        return Weather.from_settings(self.scene.settings)

    def set_weather(self, weather: Weather) -> None:
        """Apply the set fields of ``weather`` (see Weather); they take effect from the next step."""
        if not isinstance(weather, Weather):
            raise ValueError(f"weather must be a rain_core.Weather, got {type(weather).__name__}")
        weather.apply(self.scene.settings)

    # --- time -----------------------------------------------------------------------------------------------
    def _camera(self) -> Camera | None:
        return self._fixed_camera  # None: the scene's camera mode (driver or chase)

    def step(self, dt_s: float, drive=None, subframes: int = 1, draw: bool = True) -> None:
        """Advance by ``dt_s`` seconds in [0, 3600] and render. ``drive``: an object with throttle, brake (0…1),
        steer (−1…1) and reverse (bool), e.g. app.controls.DriveInput; None lets the autopilot drive. A step
        longer than MAX_FRAME_DT_S (0.25 s) is split into equal sub-steps, each rendered.

        ``subframes`` N in [1, 256] > 1: offline quality (rain_core.session.offline) — the last
        min(camera.exposure_s, dt_s) seconds are stepped in N sub-steps whose pictures are averaged.

        ``draw=False``: a step nobody looks at (a run that keeps only its last picture). The simulations, and what
        the GPU holds of them, advance as in a drawn step, in the same sub-steps; no picture is made, and
        ``capture`` refuses until a drawn step. The next drawn step's automatic exposure adapts over the whole
        time since the last drawn one, towards what it sees then."""
        self._check_open()
        dt = checks.number("dt_s", dt_s, 0.0, MAX_STEP_S, "s")
        subframes = check_subframes(subframes)
        if not isinstance(draw, bool):
            raise ValueError(f"draw must be True or False, got {draw!r}")
        self._rgb = None
        shutter = min(self.scene.settings.camera.exposure_s, dt) if subframes > 1 else 0.0
        if subframes == 1 or dt > shutter:
            self._advance(dt - shutter, drive, draw)
        if subframes > 1:
            self._rgb = self._shutter(shutter, subframes, drive, draw)
        self._undrawn = not draw
        self.frame_index += 1

    def _advance(self, dt: float, drive, draw: bool = True) -> None:
        substeps = max(1, math.ceil(dt / MAX_FRAME_DT_S))
        for _ in range(substeps):
            self.scene.step(dt / substeps, drive)
            self._frame = self.scene.render(self._camera(), draw)

    def _shutter(self, shutter_s: float, subframes: int, drive, draw: bool = True) -> np.ndarray | None:
        camera = self.scene.settings.camera
        exposure = camera.exposure_s
        lo = field_info("camera.exposure_s").range[0]
        acc = Accumulator()
        try:
            camera.exposure_s = max(exposure / subframes, lo)  # each sub-frame's streaks cover only its slice
            for _ in range(subframes):
                self.scene.step(shutter_s / subframes, drive)
                self._frame = self.scene.render(self._camera(), draw)
                if draw:
                    acc.add(self.scene.image())
        finally:
            camera.exposure_s = exposure
        return acc.result() if draw else None

    @property
    def time_s(self) -> float:
        """Simulated time since the start, s."""
        return self.scene.time_s

    # --- output ---------------------------------------------------------------------------------------------
    def render(self) -> Capture:
        """The picture of the last step (rendered now if nothing was yet), without label images."""
        return self.capture(labels=False)

    def capture(self, labels: bool = False, masks=None) -> Capture:
        """The last step's frame (after an offline-quality step: the sub-frames' average; the label images and
        labels are those of its last sub-frame). ``labels=True`` adds depth_m and the masks (``masks``: which of
        rain_core.labels.MASK_NAMES, None for all) and the class table in ``labels["class_ids"]``.

        ``Capture.labels`` (always): rain_mm_h, wetness, cracks, puddles (0…1), visibility_m (5 % contrast),
        wind_m_s (mean), wind_direction_deg, wind_velocity_m_s (gusting, world x, y, z), hour, ego_speed_m_s,
        wiper_mode (the setting), wiper_angle_rad (each blade, rad; empty without the windshield effect),
        camera_mode, fov_y_deg, camera_intrinsics (3×3, px), camera_to_world (4×4; conventions in
        rain_core.session.capture), seed, time_s, frame (step count), lightning_lux and lightning_sky_cd_m2 (the
        flash lit in this frame's shutter: its direct illuminance at the camera, lux, and the luminance it adds
        to the cloud base, cd/m²; 0 between flashes), exposure_ev100 (the exposure the frame was displayed at,
        after the automatic exposure's adaptation)."""
        self._check_open()
        if self._undrawn:
            raise ValueError("the last step was not drawn (step(..., draw=False)): capture after a step with "
                             "draw=True")
        if self._frame is None:
            self._frame = self.scene.render(self._camera())
        rgb = self._rgb if self._rgb is not None else self.scene.image()
        cap = Capture(rgb=rgb, labels=self._labels(self._frame))
        if labels:
            from rain_core.labels import ROAD_WATER_IDS, render_label_images

            images = render_label_images(self.scene, self._frame, masks)
            cap.depth_m, cap.masks = images.depth_m, images.masks
            cap.labels["class_ids"] = dict(images.class_ids)
            cap.labels["road_water_ids"] = dict(ROAD_WATER_IDS)
        return cap

    def _labels(self, frame) -> dict:
        from rain_core.effects.atmosphere.model import extinction_per_m, visibility_m

        scene, settings = self.scene, self.scene.settings
        state = scene.weather_state
        atm = settings.atmosphere
        beta = extinction_per_m(state.rate_mm_h, atm.fog_scale if atm.enabled else 0.0,
                                atm.haze_per_km if atm.enabled else 0.0)
        glass = next((e for e in scene.effects if getattr(e, "name", "") == "windshield"), None)
        angles = [float(a) for a in glass.sim.blade_angles()] if glass is not None else []
        cam = frame.camera
        return {
            "rain_mm_h": float(state.rate_mm_h), "wetness": float(state.wetness), "cracks": float(state.cracks),
            "puddles": float(state.puddles), "visibility_m": float(visibility_m(beta)),
            "wind_m_s": float(state.wind.speed_m_s), "wind_direction_deg": float(settings.wind.direction_deg),
            "wind_velocity_m_s": [float(v) for v in state.wind.velocity_m_s],
            "hour": float(settings.time_of_day.hour), "ego_speed_m_s": float(scene.ego.speed_m_s),
            "wiper_mode": settings.wipers.mode, "wiper_angle_rad": angles,
            "camera_mode": "fixed" if self._fixed_camera is not None else settings.camera.mode,
            "fov_y_deg": float(cam.fov_y_deg), "camera_intrinsics": camera_intrinsics(cam.fov_y_deg, self.size),
            "camera_to_world": camera_to_world(cam), "seed": self.seed, "time_s": float(scene.time_s),
            "frame": self.frame_index,
            # The lightning flash lit during this frame's shutter (0 between flashes): its direct illuminance at
            # the camera (lux, after the rain's extinction) and the luminance it adds to the cloud base (cd/m²).
            "lightning_lux": float(frame.flash.illuminance_lux(cam.position)) if frame.flash is not None else 0.0,
            "lightning_sky_cd_m2": float(frame.flash.sky_cd_m2 @ _LUMA) if frame.flash is not None else 0.0,
            # The exposure the frame was displayed at (the hour's meter less the eye's adaptation): a tone-map
            # input x (linear, before the ACES curve) is a scene luminance of x·1.2·2^EV100 cd/m².
            "exposure_ev100": scene.renderer.display_ev100(frame.lighting),
        }
