"""Contact sheet of the label images: ``python -m rain_core.sheets labels [--out DIR] [--size WxH]`` writes
DIR/labels.png (default docs/sheets/labels.png).

Rows: the chase camera in heavy rain behind traffic on a street with puddles, and the driver's seat in moderate
rain with the wipers off. Columns: the frame, then each label image of it (rain_core.labels): depth (log
colours 1 m … 1 km, black = sky), classes, road water regions, rain streak coverage, spray opacity, glass water.
The float masks are shown as √value (faint streaks would otherwise not show at this size). A legend below gives
the class and region colours and the ramp.
"""

from __future__ import annotations

import argparse

import numpy as np
from PIL import Image, ImageDraw

from rain_core.gl import create_headless_context
from rain_core.labels import CLASS_IDS, ROAD_WATER_IDS, release_labels, render_label_images
from rain_core.labels.classes import CLASS_COLORS
from rain_core.labels.colors import (
    DEPTH_RANGE_M,
    ROAD_WATER_COLORS,
    class_colors,
    depth_colors,
    mask_colors,
    ramp,
    road_water_colors,
)
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value
from rain_core.sheets import DEFAULT_OUT, contact_sheet

_COMMON = {"rain.wetness": 1.0, "rain.cracks": 1.0, "rain.puddles": 0.8, "road.puddle_amount": 0.8,
           "time_of_day.hour": 16.0, "quality.ripple_grid": 128}
ROWS = (("chase", {"rain.rate_mm_h": 30.0, "traffic.count": 8, "camera.mode": "chase"}, 60),
        ("driver", {"rain.rate_mm_h": 8.0, "traffic.count": 8, "camera.mode": "driver", "wipers.mode": "off"}, 90))


def row_images(li, image) -> tuple[list, list]:
    m = li.masks
    images = [image, depth_colors(li.depth_m), class_colors(m["class"]), road_water_colors(m["road_water"]),
              mask_colors(np.sqrt(m["rain"])), mask_colors(np.sqrt(m["spray"])),
              mask_colors(np.sqrt(m["glass_water"]))]
    road = m["road_water"] != ROAD_WATER_IDS["not_road"]
    labels = ["frame", "depth (log 1 m-1 km)", "class", f"road water ({road.mean():.0%} road)",
              f"rain sqrt (mean {m['rain'].mean():.3f})", f"spray sqrt (mean {m['spray'].mean():.3f})",
              f"glass water sqrt (mean {m['glass_water'].mean():.3f})"]
    return images, labels


def legend(width: int) -> np.ndarray:
    """Swatches of the class and road-water colours, and the ramp, on one strip."""
    entries = [(f"{CLASS_IDS[n]} {n}", rgb) for n, rgb in CLASS_COLORS.items() if n != "unlabeled"]
    entries += [(f"{ROAD_WATER_IDS[n]} {n}", rgb) for n, rgb in ROAD_WATER_COLORS.items()]
    cell_w, cell_h = 150, 16
    per_row = max(1, width // cell_w)
    rows = -(-len(entries) // per_row) + 2
    img = Image.new("RGB", (width, rows * cell_h + 8), (24, 24, 24))
    draw = ImageDraw.Draw(img)
    for i, (text, rgb) in enumerate(entries):
        x, y = 4 + (i % per_row) * cell_w, 4 + (i // per_row) * cell_h
        draw.rectangle((x, y + 2, x + 12, y + 13), fill=tuple(rgb), outline=(90, 90, 90))
        draw.text((x + 17, y + 2), ("road water " if i >= len(CLASS_COLORS) - 1 else "class ") + text,
                  fill=(230, 230, 230))
    y = 4 + (rows - 2) * cell_h + 4
    bar_w = min(400, width - 300)
    bar = ramp(np.linspace(0.0, 1.0, bar_w))[None].repeat(10, axis=0)
    img.paste(Image.fromarray(bar), (4, y + 2))
    lo, hi = DEPTH_RANGE_M
    draw.text((bar_w + 10, y), f"ramp: masks 0 -> 1 (shown as sqrt), depth {lo:g} m -> {hi:g} m (log); "
              "black: 0 / sky / not road", fill=(230, 230, 230))
    return np.asarray(img)


def render_rows(ctx, size: tuple[int, int]) -> tuple[list, list]:
    images, labels = [], []
    for _name, values, steps in ROWS:
        settings = Settings()
        for key, value in {**_COMMON, **values}.items():
            set_value(settings, key, value)
        scene = Scene(ctx, size, settings, seed=2, gpu_timing=False)
        frame = None
        for _ in range(steps):
            scene.step(1 / 30)
            frame = scene.render()
        li = render_label_images(scene, frame)
        row, text = row_images(li, scene.image())
        images += row
        labels += [f"{_name}: {t}" if i == 0 else t for i, t in enumerate(text)]
        release_labels(scene)
        scene.release()
    return images, labels


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets labels", description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for labels.png")
    p.add_argument("--size", default="320x180", help="frame size WxH in pixels")
    args = p.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    if len(size) != 2 or min(size) <= 0:
        raise SystemExit(f"--size: expected WxH with positive integers, got {args.size!r}")
    ctx = create_headless_context()
    with ctx:
        images, labels = render_rows(ctx, size)
    sheet = contact_sheet(images, labels, columns=len(images) // len(ROWS))
    sheet = np.concatenate([sheet, legend(sheet.shape[1])], axis=0)
    from pathlib import Path

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "labels.png"
    Image.fromarray(sheet).save(path)
    print(f"wrote {path}")
    return 0
