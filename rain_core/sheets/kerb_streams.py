"""Contact sheet of the kerb streams: the same stretch of kerb, 40 m upstream of a drain inlet, at 2, 8, 30 and
80 mm/h, with the streams (bottom row) and without (top row): the water along the kerb widens with the rate
(HEC-22 spread T ∝ (i·L)^(3/8)). ``python -m rain_core.sheets kerb_streams`` writes docs/sheets/kerb_streams.png.
"""

from __future__ import annotations

import argparse

import numpy as np

from rain_core.camera import look_at
from rain_core.gfx.context import create_headless_context
from rain_core.gutter import spread_coefficient
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (320, 180)
RATES_MM_H = (2.0, 8.0, 30.0, 80.0)
EYE, TARGET = np.array([4.0, 1.6, 520.0]), np.array([7.0, 0.0, 500.0])


def render(ctx, rate_mm_h: float, streams: bool, size=SIZE) -> np.ndarray:
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate_mm_h
    s.time_of_day.hour = 15.0
    s.traffic.count = 0
    s.road.kerb_streams = streams
    scene = Scene(ctx, size, s, seed=1, gpu_timing=False)
    try:
        for _ in range(60):  # 15 s: the road is wet through
            scene.step(0.25)
        scene.render(look_at(EYE, TARGET, fov_y_deg=50.0))
        return scene.image()
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets kerb_streams", description=__doc__)
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/sheets)")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    images, labels = [], []
    for streams in (False, True):
        for rate in RATES_MM_H:
            images.append(render(ctx, rate, streams))
            spread = spread_coefficient(rate) * 20.0**0.375
            labels.append(f"{rate:g} mm/h, " + (f"streams: {spread:.2f} m wide here" if streams else "no streams"))
    print(save_sheet(images, labels, "kerb_streams", args.out, columns=4))
    return 0
