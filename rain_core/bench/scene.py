"""Whole frames: what each weather costs, and what skipping saves.

``python -m rain_core.bench scene`` renders the default street with every effect registered, for a dry clear day
up to heavy rain at night, from the driver's seat and the chase camera. It prints the median frame time, the
passes that ran and their cost (GPU time where the driver gives it, else CPU), and the passes that were skipped.
On llvmpipe the GPU is emulated on the CPU: compare the ratios between rows, not the milliseconds.
"""

from __future__ import annotations

import statistics
import time

from PIL import Image, ImageDraw

from rain_core.bench._common import markdown_table, parser, write_output

CASES = (  # label, rain mm/h, hour, pinned (wetness, cracks, puddles) or None for the weather's own
    ("dry, clear noon", 0.0, 12.0, (0.0, 0.0, 0.0)),
    ("wet road, no rain", 0.0, 12.0, (1.0, 0.0, 0.0)),
    ("light rain 0.5 mm/h", 0.5, 12.0, (0.6, 0.2, 0.1)),
    ("heavy rain 8 mm/h", 8.0, 12.0, (1.0, 1.0, 1.0)),
    ("heavy rain, night", 8.0, 22.0, (1.0, 1.0, 1.0)),
)


def _settings(rate: float, hour: float, levels, camera: str, effects_on: bool = True):
    from rain_core.settings import Settings, set_value

    settings = Settings()
    set_value(settings, "rain.rate_mm_h", rate)
    set_value(settings, "time_of_day.hour", hour)
    set_value(settings, "camera.mode", camera)
    for name, value in zip(("wetness", "cracks", "puddles"), levels, strict=True):
        set_value(settings, f"rain.{name}", value)
    if not effects_on:
        for section in ("road", "ripples", "rainfall", "spray", "windshield", "atmosphere"):
            if hasattr(getattr(settings, section), "enabled"):
                set_value(settings, f"{section}.enabled", False)
    return settings


def measure(ctx, settings, size, frames: int, warmup: int) -> dict:
    from rain_core.scene import Scene

    scene = Scene(ctx, size, settings=settings, seed=1, gpu_timing=True)  # per-pass GPU ms (a frame late)
    times, passes = [], {}
    for i in range(warmup + frames):
        scene.step(1 / 30)
        t0 = time.perf_counter()
        scene.render()
        ctx.finish()
        if i >= warmup:
            times.append((time.perf_counter() - t0) * 1e3)
            for name, ran, cpu_ms, gpu_ms, _note in scene.renderer.pass_table():
                if ran:
                    passes.setdefault(name, []).append(gpu_ms if gpu_ms is not None else cpu_ms)
                else:
                    passes.setdefault(name, None)
    scene.release()
    ran = {k: statistics.median(v) for k, v in passes.items() if v}
    skipped = sorted(k for k, v in passes.items() if v is None)
    return {"frame_ms": statistics.median(times), "ran": ran, "skipped": skipped}


def bar_chart(path, rows: list[tuple[str, float]], title: str) -> None:
    """A horizontal bar chart (PIL; matplotlib is not a dependency)."""
    width, bar_h, left = 760, 22, 300
    height = 40 + bar_h * len(rows) + 20
    img = Image.new("RGB", (width, height), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    draw.text((10, 10), title, fill=(0, 0, 0))
    top = max(v for _, v in rows) or 1.0
    for i, (label, value) in enumerate(rows):
        y = 40 + i * bar_h
        draw.text((10, y + 5), label, fill=(0, 0, 0))
        draw.rectangle([left, y + 3, left + (width - left - 80) * value / top, y + bar_h - 3], fill=(70, 110, 180))
        draw.text((left + (width - left - 80) * value / top + 6, y + 5), f"{value:.0f} ms", fill=(0, 0, 0))
    img.save(path)


def main(argv=None) -> int:
    p = parser("scene", __doc__.splitlines()[0])
    p.add_argument("--size", default="640x360", help="frame size WxH")
    args = p.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    frames, warmup = (3, 2) if args.quick else (12, 6)
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    rows, chart = [], []
    for camera in ("driver", "chase"):
        cases = [(label, rate, hour, levels, True) for label, rate, hour, levels in CASES]
        cases.append(("heavy rain, every effect off", 8.0, 12.0, (1.0, 1.0, 1.0), False))
        for label, rate, hour, levels, on in cases:
            result = measure(ctx, _settings(rate, hour, levels, camera, on), size, frames, warmup)
            ran = ", ".join(f"{k} {v:.1f}" for k, v in sorted(result["ran"].items(), key=lambda kv: -kv[1]))
            rows.append((camera, label, result["frame_ms"], ran, ", ".join(result["skipped"]) or "-"))
            chart.append((f"{camera}: {label}", result["frame_ms"]))
            print(f"{camera:6s} {label:32s} {result['frame_ms']:8.1f} ms   skipped: {rows[-1][4]}", flush=True)
    md = (f"# Whole frames, {size[0]}x{size[1]}, llvmpipe unless stated\n\n"
          + markdown_table(("camera", "case", "frame ms (median)", "passes that ran (ms)", "skipped"), rows))
    print()
    print(md)
    path = write_output(args.out, "scene", md)
    bar_chart(path.with_suffix(".png"), chart, f"frame time by weather, {size[0]}x{size[1]}")
    print(f"\nwrote {path} and {path.with_suffix('.png')}")
    return 0
