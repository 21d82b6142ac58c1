"""Contact sheet of the driving view (issue 17): the driver's seat by day, at dusk and at night, before (60°
pitched 4° down, the hour's meter) and after (40° level, automatic exposure); the left door mirror showing the
street behind in a wide driver view; and the street from the chase camera in the rain.
``python -m rain_core.sheets driving`` writes docs/sheets/driving.png.
"""

from __future__ import annotations

import argparse

import numpy as np

from rain_core.gfx.context import create_headless_context
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (480, 270)
BEFORE = {"camera.driver_fov_deg": 60.0, "camera.driver_pitch_deg": -4.0, "camera.auto_exposure": False,
          "camera.mirrors": False}
HOURS = (("day", 13.0), ("dusk", 19.0), ("night", 22.5))


def render(ctx, values: dict, seconds: float = 3.0, size=SIZE) -> np.ndarray:
    """One frame (uint8 RGB) after ``seconds`` (s) of driving in moderate rain with the settings ``values``."""
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in {"rain.rate_mm_h": 4.0, "traffic.count": 8, **values}.items():
        set_value(settings, path, value)
    scene = Scene(ctx, size, settings, seed=1, gpu_timing=False)
    try:
        for _ in range(int(round(seconds * 10))):  # 10 frames/s: the exposure adapts over the drive
            scene.step(0.1)
            scene.render()
        return scene.image()
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets driving", description=__doc__)
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/sheets)")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    images, labels = [], []
    for name, hour in HOURS:
        images.append(render(ctx, {**BEFORE, "time_of_day.hour": hour}))
        labels.append(f"before: {name} {hour:g} h, 60 deg, -4 deg, hour's meter")
        images.append(render(ctx, {"time_of_day.hour": hour}))
        labels.append(f"after: {name} {hour:g} h, 40 deg level, auto exposure")
    images.append(render(ctx, {"time_of_day.hour": 13.0, "camera.driver_fov_deg": 75.0}))
    labels.append("door mirror in view (75 deg): the street behind")
    images.append(render(ctx, {"time_of_day.hour": 17.5, "camera.mode": "chase", "rain.rate_mm_h": 8.0}))
    labels.append("chase, 8 mm/h, 17.5 h: the street")
    print(save_sheet(images, labels, "driving", args.out, columns=2))
    return 0
