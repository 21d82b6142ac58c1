"""Contact sheet of the atmosphere effect: a night street (behind the car: lamp halos, light glow, its beams)
and the four-lane road by day (a high camera looking ~1 km down the straight: distance fading into rain-grey
sky), each at R = 0, 2, 10 and 50 mm/h. ``python -m rain_core.sheets atmosphere`` writes
docs/sheets/atmosphere.png.

The sky is rain-grey through ``lighting_for_hour(hour, sky_overcast(...))``, built here as the Scene does it.
"""

from __future__ import annotations

import argparse

import numpy as np

from rain_core.camera import look_at
from rain_core.effects.atmosphere import AtmosphereEffect, sky_overcast
from rain_core.gfx.context import create_headless_context
from rain_core.lighting import lighting_for_hour
from rain_core.sheets import DEFAULT_OUT, save_sheet

RATES_MM_H = (0.0, 2.0, 10.0, 50.0)
SIZE = (320, 180)


def render(ctx, rate_mm_h: float, view: str, size=SIZE) -> np.ndarray:
    """One frame (uint8 RGB) of ``view`` ("night street" or "road by day") at rain rate R (mm/h)."""
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    settings = Settings()
    settings.rain.rate_mm_h = rate_mm_h
    night = view == "night street"
    settings.time_of_day.hour = 22.0 if night else 15.0
    scene = Scene(ctx, size, settings, seed=1, effects=[AtmosphereEffect(ctx)])
    for _ in range(30):
        scene.step(1.0 / 30.0)
    if night:  # behind and to the left of the car, so its beams are seen from the side, not hidden by it
        eye = scene.ego.position + np.array([-4.5, 2.5, 8.0])
        camera = look_at(eye, scene.ego.position + scene.ego.forward() * 18.0 + np.array([0.0, 0.5, 0.0]),
                         fov_y_deg=55.0)
    else:
        eye = scene.ego.position + np.array([-2.0, 7.0, 12.0])
        camera = look_at(eye, eye + np.array([0.6, -2.5, -100.0]), fov_y_deg=45.0, far_m=3000.0)
    frame = scene.frame(camera)
    frame.lighting = lighting_for_hour(settings.time_of_day.hour, sky_overcast(settings.atmosphere, rate_mm_h))
    scene.renderer.render(frame)
    image = scene.image()
    scene.release()
    ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
    return image


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets atmosphere", description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for atmosphere.png")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    images, labels = [], []
    for view in ("night street", "road by day"):
        for rate in RATES_MM_H:
            images.append(render(ctx, rate, view))
            labels.append(f"{view}, R = {rate:g} mm/h")
    path = save_sheet(images, labels, "atmosphere", args.out, columns=len(RATES_MM_H))
    print(f"wrote {path}")
    return 0
