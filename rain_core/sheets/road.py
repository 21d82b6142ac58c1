"""Contact sheet of the wet road: ``python -m rain_core.sheets road [--out DIR] [--size WxH]`` writes
DIR/road.png (default docs/sheets/road.png).

Rows: the driver's seat, the chase camera, and the debug view of the four regions (chase camera). Columns:
dry (sunny noon), wet (raining: full film, overcast), puddles (after the rain: the film drying, cracks and
puddles still full), night (wet street with puddles, 22 h). The debug row shows the flood levels rising:
cracks only, puddles at half level, puddles full, then the film dried off around the puddles that remain.
Rainy frames use an overcast sky (``lighting_for_hour(hour, overcast)``), as the atmosphere effect gives in
rain.
"""

from __future__ import annotations

import argparse
import dataclasses

from rain_core.effects.road import RoadEffect
from rain_core.gl import create_headless_context
from rain_core.lighting import lighting_for_hour
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value
from rain_core.sheets import DEFAULT_OUT, save_sheet

# name, hour, overcast, (wetness, cracks, puddles), debug view
STATES = {
    "dry": (12.0, 0.0, (0.0, 0.0, 0.0), False),
    "wet": (12.0, 0.75, (1.0, 0.3, 0.0), False),
    "puddles": (12.0, 0.6, (0.45, 0.8, 1.0), False),
    "night": (22.0, 0.6, (1.0, 0.8, 0.8), False),
    "regions: cracks": (12.0, 0.6, (1.0, 1.0, 0.0), True),
    "regions: puddles 1/2": (12.0, 0.6, (1.0, 1.0, 0.5), True),
    "regions: puddles full": (12.0, 0.6, (1.0, 1.0, 1.0), True),
    "regions: film dried": (12.0, 0.6, (0.0, 0.6, 1.0), True),
}
ROWS = (("driver", ("dry", "wet", "puddles", "night")),
        ("chase", ("dry", "wet", "puddles", "night")),
        ("chase", ("regions: cracks", "regions: puddles 1/2", "regions: puddles full", "regions: film dried")))


def render_frames(ctx, size: tuple[int, int]) -> tuple[list, list]:
    settings = Settings()
    set_value(settings, "road.puddle_amount", 0.8)
    set_value(settings, "road.reflection_scale", 0.5)
    scene = Scene(ctx, size, settings, seed=1, effects=[])
    scene.renderer.effects.append(RoadEffect(ctx, settings, shaders=scene.renderer.shaders))
    for _ in range(45):  # the chase rig settles behind the car
        scene.step(1 / 30)
    images, labels = [], []
    for mode, names in ROWS:
        for name in names:
            hour, overcast, levels, debug = STATES[name]
            set_value(settings, "time_of_day.hour", hour)
            for level, value in zip(("wetness", "cracks", "puddles"), levels, strict=True):
                set_value(settings, f"rain.{level}", value)
            set_value(settings, "road.debug_regions", debug)
            scene.step(0.0)  # the pinned levels reach the weather; nothing moves
            frame = scene.frame(scene.camera(mode))
            frame = dataclasses.replace(frame, lighting=lighting_for_hour(hour, overcast),
                                        headlights_on=levels[0] > 0 or hour > 19)
            scene.renderer.render(frame)
            images.append(scene.image())
            w, c, p = levels
            labels.append(f"{mode} - {name}  w{w:g} c{c:g} p{p:g}")
    scene.release()
    return images, labels


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets road", description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for road.png")
    p.add_argument("--size", default="320x180", help="frame size WxH in pixels")
    args = p.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    ctx = create_headless_context()
    with ctx:
        images, labels = render_frames(ctx, size)
    path = save_sheet(images, labels, "road", args.out, columns=4)
    print(f"wrote {path}")
    return 0
