"""Contact sheet of dripping edges: the bridge deck in the rain and after it (the deck drains for minutes, the
streams thin to single drops), the fuel-station canopy, and the bridge at night with its lamps.
``python -m rain_core.sheets drips`` writes docs/sheets/drips.png.
"""

from __future__ import annotations

import argparse

import numpy as np

from rain_core.camera import look_at
from rain_core.gfx.context import create_headless_context
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (320, 180)
BRIDGE = (np.array([-3.5, 1.6, 313.0]), np.array([0.0, 3.5, 300.0]))
CANOPY = (np.array([0.5, 1.6, 716.0]), np.array([8.0, 3.2, 704.0]))


def render(ctx, rate_mm_h: float, view, after_rain_s: float = 0.0, hour: float = 15.0, size=SIZE) -> np.ndarray:
    """One frame (uint8 RGB) with every effect; after_rain_s (s) > 0: that long after the rain stopped."""
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate_mm_h
    s.time_of_day.hour = hour
    s.traffic.count = 0
    s.atmosphere.sky_darkening = 0.7  # the cloud stays when the rain stops: the same light before and after
    scene = Scene(ctx, size, s, seed=1, gpu_timing=False)
    camera = look_at(view[0], view[1], fov_y_deg=60.0)
    try:
        scene.step(1.0 / 30.0)
        scene.render(camera)
        if after_rain_s > 0.0:
            s.rain.rate_mm_h = 0.0
            for _ in range(int(round(after_rain_s / 0.25))):
                scene.step(0.25)
            scene.render(camera)
        return scene.image()
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets drips", description=__doc__)
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/sheets)")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    cases = [("bridge deck, 8 mm/h", 8.0, BRIDGE, 0.0), ("bridge, 1 min after the rain", 8.0, BRIDGE, 60.0),
             ("bridge, 5 min after", 8.0, BRIDGE, 300.0), ("bridge, 20 min after", 8.0, BRIDGE, 1200.0),
             ("fuel-station canopy, 4 mm/h", 4.0, CANOPY, 0.0), ("bridge at night, 8 mm/h (lamps)", 8.0, BRIDGE, 0.0)]
    images = [render(ctx, rate, view, after, hour=22.0 if "night" in label else 15.0)
              for label, rate, view, after in cases]
    print(save_sheet(images, [c[0] for c in cases], "drips", args.out, columns=3))
    return 0
