"""Contact sheet of the rainbow: the bow at two sun elevations, at two rain rates, on the departing shower after
the rain, from the street, and none under a high sun. ``python -m rain_core.sheets rainbow`` writes
docs/sheets/rainbow.png.

The street runs north–south, so the antisolar point of a low sun lies across it, behind the façades: most views
look from above the roofs (a free camera at 40 m); one looks across the fuel station's open forecourt.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from rain_core.camera import look_at
from rain_core.gfx.context import create_headless_context
from rain_core.lighting import lighting_for_hour, sun_elevation_deg
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (480, 270)


def antisolar_camera(hour: float, eye, fov: float = 80.0, raise_deg: float = 20.0, far_m: float = 4000.0):
    """A camera at eye (m) facing the antisolar point's azimuth, raised by raise_deg (deg) above the horizon."""
    anti = -np.asarray(lighting_for_hour(hour).sun_direction, dtype=np.float64)
    anti[1] = 0.0
    anti /= np.linalg.norm(anti)
    eye = np.asarray(eye, dtype=np.float64)
    target = eye + anti * 100.0 + np.array([0.0, 100.0 * math.tan(math.radians(raise_deg)), 0.0])
    return look_at(eye, target, fov_y_deg=fov, far_m=far_m)


def render(ctx, hour: float, rate_mm_h: float, camera, after_rain_s: float = 0.0, size=SIZE) -> np.ndarray:
    """One frame (uint8 RGB) with every effect, at hour (h) and rate (mm/h); after_rain_s (s) > 0 renders that
    long after the rain stopped (the bow on the departing shower)."""
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    settings = Settings()
    settings.rain.rate_mm_h = rate_mm_h
    settings.time_of_day.hour = hour
    scene = Scene(ctx, size, settings, seed=1, gpu_timing=False)
    try:
        for _ in range(10):
            scene.step(1.0 / 30.0)
        if after_rain_s > 0.0:
            scene.render(camera)  # the rainbow sees the rain fall here once
            settings.rain.rate_mm_h = 0.0
            for _ in range(int(round(after_rain_s / 0.25))):
                scene.step(0.25)
        scene.render(camera)
        return scene.image()
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()


def views():
    roof = (-1.75, 40.0, 700.0)
    street = (-5.0, 1.3, 704.0)  # the −X kerb opposite the fuel station, looking east across its forecourt
    return [
        (f"sun {sun_elevation_deg(17.0):.0f} deg (17 h), 4 mm/h", 17.0, 4.0, antisolar_camera(17.0, roof), 0.0),
        (f"sun {sun_elevation_deg(16.0):.0f} deg (16 h), 4 mm/h", 16.0, 4.0, antisolar_camera(16.0, roof), 0.0),
        ("17 h, 1 mm/h: less overcast, clearer bow", 17.0, 1.0, antisolar_camera(17.0, roof), 0.0),
        ("17 h, 30 s after the rain (shower 300 m off)", 17.0, 4.0, antisolar_camera(17.0, roof), 30.0),
        ("17.5 h from the street, across the station", 17.5, 4.0,
         antisolar_camera(17.5, street, fov=70.0, raise_deg=18.0), 0.0),
        ("noon, 4 mm/h: sun 62 deg, no bow (pass idle)", 12.0, 4.0, antisolar_camera(12.0, roof, raise_deg=-10.0),
         0.0),
    ]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets rainbow", description=__doc__)
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/sheets)")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    images, labels = [], []
    for label, hour, rate, camera, after in views():
        images.append(render(ctx, hour, rate, camera, after))
        labels.append(label)
    path = save_sheet(images, labels, "rainbow", args.out, columns=3)
    print(path)
    return 0
