"""Contact sheet of lightning: one flash frame by frame (30 frames/s) at night from above the roofs, facing the bolt,
then the same flash from the street by night and at dusk, at the hour's fixed exposure. ``python -m rain_core.sheets
lightning`` writes docs/sheets/lightning.png. The return strokes (40–80 ms apart) land in separate frames and the
continuing current glows between them: the flicker of a real flash.
"""

from __future__ import annotations

import argparse

import numpy as np

from rain_core.camera import look_at
from rain_core.effects.lightning.schedule import FlashSchedule, mean_intensity_cd
from rain_core.gfx.context import create_headless_context
from rain_core.sheets import DEFAULT_OUT, save_sheet

SIZE = (320, 180)
SEED = 145  # its storm (10 flashes/min) strikes 620 m away 3.2 s in
FPS = 30.0


def near_flash(seed: int = SEED):
    schedule = FlashSchedule(10.0, 8000.0, seed)
    return next(f for b in range(10) for f in schedule.block(b) if f.distance_m < 1500.0)


def render_sequence(ctx, hour: float, eye_height_m: float, times, size=SIZE) -> list[np.ndarray]:
    """Frames (uint8 RGB) at ``times`` (s, increasing) of a 20 mm/h storm at ``hour``, facing the flash."""
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = 20.0
    s.time_of_day.hour = hour
    s.lightning.flashes_per_min = 10.0
    # A fixed exposure (the hour's meter), as a photographer shoots lightning: an eye adapted to the dark street
    # is blinded by the flash and the frames would be white.
    s.camera.auto_exposure = False
    scene = Scene(ctx, size, s, seed=SEED, gpu_timing=False)
    flash = near_flash()
    bearing = np.array([np.cos(flash.bearing_rad), 0.0, np.sin(flash.bearing_rad)])
    images = []
    try:
        for t in times:
            while scene.time_s < t - 1e-9:
                scene.step(min(1.0 / FPS, t - scene.time_s))
            eye = np.array([scene.ego.position[0] - 4.0, eye_height_m, scene.ego.position[2]])
            camera = look_at(eye, eye + bearing * 100.0 + np.array([0.0, 14.0, 0.0]), fov_y_deg=70.0)
            scene.render(camera)
            images.append(scene.image())
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()
    return images


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets lightning", description=__doc__)
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output folder (default docs/sheets)")
    args = p.parse_args(argv)
    ctx = create_headless_context()
    flash = near_flash()
    # Frames ending just before the flash, then every frame while it lasts.
    ends = flash.start_s - 1.0 / FPS + np.arange(9) / FPS + 0.005
    images = render_sequence(ctx, 22.0, 40.0, ends)
    labels = []
    for t in ends:
        cd = float(mean_intensity_cd(flash, t - 1.0 / FPS, t))
        labels.append(f"night, t = {1000 * (t - flash.start_s):+.0f} ms, {cd / 1e6:.0f} Mcd")
    peak = ends[1:3]
    images += render_sequence(ctx, 22.0, 1.6, peak[:1]) + render_sequence(ctx, 19.5, 1.6, peak[:1])
    labels += ["from the street, night (same flash)", "from the street, dusk 19.5 h"]
    print(save_sheet(images, labels, "lightning", args.out, columns=4))
    return 0
