"""Contact sheet of the rainfall effect: ``python -m rain_core.sheets rainfall`` writes docs/sheets/rainfall.png.

Frames from the driver's seat: light (0.5), moderate (2), heavy (8) and extreme (80 mm/h) rain, by day and by
night, parked and at 100 km/h, with the default particle budget and the 1/60 s exposure. The other registered
effects (wet road, spray, ripples, atmosphere) draw too, so the streaks are seen as they are in the app.

Drops are far below a pixel wide, so a streak's opacity grows with the resolution (its light is fixed, its
width is the 1 px floor): at 320×180 daytime rain is faint. The last row therefore shows 320×180 crops at 1:1
of 1280×720 frames (the façade and tree on the right), which is what a window shows.
"""

from __future__ import annotations

import argparse

from rain_core.sheets import DEFAULT_OUT, save_sheet

FRAME_SIZE = (320, 180)
DT_S = 1.0 / 30.0
RATES = (("light", 0.5), ("moderate", 2.0), ("heavy", 8.0), ("extreme", 80.0))
ROWS = (("day", 12.0, 0.0), ("day", 12.0, 100.0), ("night", 22.5, 0.0), ("night", 22.5, 100.0))
DETAIL_SIZE = (1280, 720)
DETAIL_CROP = (880, 110)  # px, top-left corner of the 1:1 crop (the right-hand façade and tree)
DETAILS = (("moderate", 2.0, "day", 12.0, 0.0), ("heavy", 8.0, "day", 12.0, 0.0), ("heavy", 8.0, "day", 12.0, 100.0),
           ("extreme", 80.0, "day", 12.0, 0.0))


def rain_scene(ctx, size, settings, seed: int = 1):
    """A Scene with the registered effects and a RainfallEffect (replacing a registered one) before the
    atmosphere's post pass. Returns (scene, rainfall effect)."""
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.scene import Scene, default_effects

    effect = RainfallEffect(ctx, settings=settings, seed=seed)
    others = [e for e in default_effects(ctx, settings) if getattr(e, "name", "") != "rainfall"]
    at = next((i for i, e in enumerate(others) if getattr(e, "name", "") == "atmosphere"), len(others))
    return Scene(ctx, size, settings, seed=seed, effects=[*others[:at], effect, *others[at:]]), effect


def driver_frame(ctx, size, rate: float, hour: float, kmh: float):
    """The driver's view (uint8 image) after a few frames of rain at rate (mm/h), hour (h), speed (km/h)."""
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate
    s.rain.wetness = 1.0
    s.rain.cracks = 1.0
    s.rain.puddles = 0.5
    s.time_of_day.hour = hour
    s.camera.mode = "driver"
    scene, _ = rain_scene(ctx, size, s)
    speed = kmh / 3.6
    for _ in range(6):
        scene.ego.speed_m_s = speed
        scene.step(DT_S)
    scene.ego.speed_m_s = speed
    scene.render()
    image = scene.image()
    scene.release()
    return image


def render_frames(ctx, size=FRAME_SIZE) -> tuple[list, list[str]]:
    images, labels = [], []
    for when, hour, kmh in ROWS:
        for name, rate in RATES:
            images.append(driver_frame(ctx, size, rate, hour, kmh))
            labels.append(f"{name} {rate:g} mm/h, {when}, {kmh:.0f} km/h")
    x0, y0 = DETAIL_CROP
    for name, rate, when, hour, kmh in DETAILS:
        full = driver_frame(ctx, DETAIL_SIZE, rate, hour, kmh)
        images.append(full[y0: y0 + size[1], x0: x0 + size[0]])
        labels.append(f"1:1 of {DETAIL_SIZE[0]}x{DETAIL_SIZE[1]}: {name}, {when}, {kmh:.0f} km/h")
    return images, labels


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.sheets rainfall", description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(DEFAULT_OUT), help="folder for rainfall.png")
    args = p.parse_args(argv)
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    images, labels = render_frames(ctx)
    path = save_sheet(images, labels, "rainfall", args.out, columns=len(RATES))
    print(f"wrote {path}")
    ctx.release()
    return 0
