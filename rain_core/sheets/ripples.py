"""The ego car driving through puddles in light rain: frames from a camera beside the car (top rows) and the
simulated height field at the same moments (bottom rows; red above rest, blue below, scaled per frame).

``python -m rain_core.sheets ripples`` writes docs/sheets/ripples.png. Look for: a wake spreading behind each
wheel where the tyres cross water, and raindrop rings with no regular pattern.
"""

from __future__ import annotations

import argparse

import numpy as np
from PIL import Image

from rain_core.sheets import DEFAULT_OUT, save_sheet


def height_picture(height: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Heights (m) → uint8 RGB: red above rest, blue below, scaled to the 99.5th percentile of |h|; rows are +Z,
    so the car (driving −Z) moves up the picture."""
    # A robust scale: a few tall drop dents must not hide the wakes (they saturate instead).
    scale = max(float(np.percentile(np.abs(height), 99.5)), 1e-12)
    v = np.clip(height / scale, -1.0, 1.0)
    rgb = np.zeros((*v.shape, 3), np.uint8)
    rgb[..., 0] = (np.sqrt(np.maximum(v, 0)) * 255).astype(np.uint8)
    rgb[..., 2] = (np.sqrt(np.maximum(-v, 0)) * 255).astype(np.uint8)
    rgb[..., 1] = 25
    return np.asarray(Image.fromarray(rgb).resize(size, Image.NEAREST))


def render(ctx, size=(320, 180), frames: int = 6, every_s: float = 0.5):
    from rain_core.camera import look_at
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in (("rain.rate_mm_h", 1.0), ("rain.wetness", 1.0), ("rain.cracks", 1.0),
                        ("rain.puddles", 1.0), ("road.puddle_amount", 1.0), ("time_of_day.hour", 12.0),
                        ("traffic.count", 0)):
        set_value(settings, path, value)
    scene = Scene(ctx, size, settings=settings, seed=3)
    scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 8.3  # 30 km/h
    ripples = next(e for e in scene.effects if e.name == "ripples")
    views, fields, labels = [], [], []
    steps = round(every_s * 30)
    for i in range(frames):
        for _ in range(steps):
            scene.step(1 / 30)
            scene.render()
        ego = scene.ego
        # Behind, to the right and above: looking down at the water the wheels have just crossed.
        eye = ego.position + ego.right() * 3.0 - ego.forward() * 9.0 + np.array([0.0, 4.0, 0.0])
        scene.render(look_at(eye, ego.position - ego.forward() * 3.0, fov_y_deg=55))
        views.append(scene.image())
        field = ripples.field
        fields.append(height_picture(field.height, size))
        t = (i + 1) * every_s
        labels.append(f"t={t:.1f} s, {ego.speed_m_s * 3.6:.0f} km/h, 1 mm/h")
    extent = ripples.field.extent_m  # read before release: the field goes with the scene
    scene.release()
    return views + fields, labels + [f"height field {extent:.0f} m, car at centre, t={(i + 1) * every_s:.1f} s"
                                     for i in range(frames)]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets ripples", description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for ripples.png")
    args = p.parse_args(argv)
    from rain_core.gl import create_headless_context

    images, labels = render(create_headless_context())
    path = save_sheet(images, labels, "ripples", args.out, columns=3)
    print(f"wrote {path}")
    return 0
