"""The storm as weather (NumPy, no GL): which flash lights a frame, where its channel stands, how bright it is at
the eye and how much it brightens the cloud base. The Scene asks it once per frame and hands the result to the
lighting (the sky, and through it the airlight and the ambient light, brighten) and to the effects
(``Frame.flash``: the lightning effect draws the bolt and adds the flash to the light list).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core.effects.lightning.schedule import (
    NEAR_M,
    PEAK_CD,
    SPEED_OF_SOUND_M_S,
    Flash,
    FlashSchedule,
    auto_flashes_per_min,
    mean_intensity_cd,
)

BOLT_COLOR = np.array([0.88, 0.92, 1.2]) / np.mean([0.88, 0.92, 1.2])  # bluish white (hot channel, N II lines)
CLOUD_ALBEDO = 0.7  # of the cloud base lit by the channel (thick cloud, multiple scattering, little absorption)
LIT_CD = PEAK_CD * 1e-5  # below this shutter-mean intensity a flash is over for the picture
LIGHT_HEIGHT_SHARE = 0.3  # the street sees the channel as a point this far up it


@dataclass(frozen=True)
class FlashView:
    """A flash as one frame sees it. ground, top, light (m, world): where the channel meets the ground, the cloud
    base, and the point the street sees it as; intensity_cd: shutter-mean luminous intensity (× the user's
    intensity); transmittance: of the rain medium from the light point to the eye; sky_cd_m2 (RGB): the cloud
    base's added luminance (its light diffuses through the cloud and the rain rather than being lost)."""

    flash: Flash
    ground: np.ndarray
    top: np.ndarray
    light: np.ndarray
    intensity_cd: float
    transmittance: float
    sky_cd_m2: np.ndarray

    def illuminance_lux(self, eye) -> float:
        """The direct flash's illuminance (lux, perpendicular to the rays) at ``eye`` (m)."""
        d2 = float(np.sum((self.light - np.asarray(eye, dtype=np.float64)) ** 2))
        return self.intensity_cd * self.transmittance / max(d2, 1.0)


class Storm:
    """Lightning over the street: the schedule (seeded by ``seed``) and the flashes' anchors. ``view(...)`` per
    frame; ``last_flash``/``last_distance_m`` for the thunder delay."""

    def __init__(self, seed: int = 0):
        self.seed = int(seed)
        self._schedule: FlashSchedule | None = None
        self._anchors: dict[int, np.ndarray] = {}  # flash seed → the eye's ground point when first seen
        self.last_flash: Flash | None = None
        self.last_distance_m = 0.0
        self.time_s = 0.0

    @staticmethod
    def flashes_per_min(section, rate_mm_h: float) -> float:
        """The flash rate (1/min): ``section.flashes_per_min`` if set, else automatic from the rain rate (mm/h);
        0 with lightning off or at zero intensity."""
        if not section.enabled or section.intensity <= 0.0:
            return 0.0
        if section.flashes_per_min is not None:
            return float(section.flashes_per_min)
        return auto_flashes_per_min(rate_mm_h)

    def schedule(self, section, rate_mm_h: float) -> FlashSchedule | None:
        rate = self.flashes_per_min(section, rate_mm_h)
        if rate <= 0.0:
            self._schedule = None
            return None
        far = max(section.max_distance_km * 1000.0, NEAR_M)
        s = self._schedule
        if s is None or s.flashes_per_min != rate or s.far_m != far:
            s = self._schedule = FlashSchedule(rate, far, self.seed)
        return s

    def _ground(self, flash: Flash, eye: np.ndarray) -> np.ndarray:
        anchor = self._anchors.setdefault(flash.seed, np.array([eye[0], 0.0, eye[2]]))
        return anchor + flash.distance_m * np.array([math.cos(flash.bearing_rad), 0.0, math.sin(flash.bearing_rad)])

    def view(self, time_s: float, shutter_s: float, eye, rate_mm_h: float, section, medium_per_m: float,
             cloud_base_m: float) -> FlashView | None:
        """The flash lit during the shutter [time_s − shutter_s, time_s] (s) seen from ``eye`` (m), or None.
        ``section``: the lightning settings; ``medium_per_m``: the rain + haze extinction (1/m)."""
        self.time_s = time_s
        schedule = self.schedule(section, rate_mm_h)
        if schedule is None:
            return None
        eye = np.asarray(eye, dtype=np.float64)
        last = schedule.last_flash(time_s)
        if last is not None:
            self.last_flash = last
            self.last_distance_m = float(np.linalg.norm(self._ground(last, eye)[[0, 2]] - eye[[0, 2]]))
        lit = [(f, float(mean_intensity_cd(f, time_s - shutter_s, time_s)))
               for f in schedule.flashes_between(time_s - shutter_s, time_s)]
        lit = [(f, cd) for f, cd in lit if cd > LIT_CD]
        keep = {f.seed for f, _ in lit} | ({last.seed} if last is not None else set())
        self._anchors = {k: v for k, v in self._anchors.items() if k in keep}
        if not lit:
            return None
        flash, cd = max(lit, key=lambda item: item[1])
        cd *= section.intensity
        ground = self._ground(flash, eye)
        top = ground + np.array([0.0, cloud_base_m, 0.0])
        light = ground + np.array([0.0, LIGHT_HEIGHT_SHARE * cloud_base_m, 0.0])
        transmittance = math.exp(-medium_per_m * float(np.linalg.norm(light - eye)))
        # The cloud base over the eye, lit by the channel's top: ρ·E/π, E = I/d² (the light diffuses, not lost).
        sky = CLOUD_ALBEDO * cd / max(float(np.sum((top - eye) ** 2)), 1.0) / math.pi * BOLT_COLOR
        return FlashView(flash, ground, top, light, cd, transmittance, sky)

    def frame_view(self, settings, time_s: float, dt_s: float, eye, rate_mm_h: float) -> FlashView | None:
        """``view`` for a frame of ``settings`` (rain_core.settings.Settings) at time_s (s), dt_s (s) after the last:
        the shutter is the camera's exposure or the frame interval, whichever is longer (an eye integrates at
        least a frame), the medium the atmosphere's rain + haze."""
        from rain_core.effects.atmosphere.model import medium_extinction_per_m

        atm = settings.atmosphere
        medium = medium_extinction_per_m(rate_mm_h, atm.fog_scale, atm.haze_per_km) if atm.enabled else 0.0
        shutter = max(settings.camera.exposure_s, dt_s)
        return self.view(time_s, shutter, eye, rate_mm_h, settings.lightning, medium, atm.cloud_base_m)

    def describe(self) -> str:
        """The last flash's distance and its thunder (3 s per km)."""
        f = self.last_flash
        if f is None:
            return "no storm" if self._schedule is None else "no flash yet"
        delay = self.last_distance_m / SPEED_OF_SOUND_M_S
        heard = f.start_s + delay - self.time_s
        when = f"thunder in {heard:.1f} s" if heard > 0 else f"thunder {delay:.1f} s after it"
        return f"last flash {self.last_distance_m / 1000.0:.1f} km away: {when} (3 s/km)"
