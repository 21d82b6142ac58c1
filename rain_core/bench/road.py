"""Wet road cost and accuracy: the frame with the road effect disabled, dry, wet and flooded; the reflection
pass's cost against its resolution scale, and its image error against the full-resolution reflection.

``python -m rain_core.bench road [--quick] [--out DIR]`` prints the tables and writes DIR/road.md and DIR/road.png.

Timing is wall time around ``ctx.finish()`` (the GL work included): for the cases the minimum and median over
frames rendered in turn, for the reflection pass the median. On Mesa's llvmpipe the
GPU is emulated by the CPU: compare the ratios, not the milliseconds. Error: the final HDR frame at a scale
against the same frame at scale 1, relative RMS of luminance over the pixels the reflection changes (where
the scale-1 frame differs from the frame without reflections), and the PSNR of the displayed picture there.
"""

from __future__ import annotations

import math
import time

import numpy as np
from PIL import Image, ImageDraw

from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.effects.road import RoadEffect
from rain_core.gl import create_headless_context
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

LUMA = np.array([0.2126, 0.7152, 0.0722])
CASES = (
    # name, road.enabled, (wetness, cracks, puddles), reflections
    ("effect disabled (wet weather)", False, (1.0, 1.0, 1.0), True),
    ("dry road (effect on, inactive)", True, (0.0, 0.0, 0.0), True),
    ("wet, reflections off", True, (1.0, 0.0, 0.0), False),
    ("wet", True, (1.0, 0.0, 0.0), True),
    ("wet + cracks + puddles", True, (1.0, 1.0, 1.0), True),
)
SCALES = (0.125, 0.25, 0.5, 0.75, 1.0)


def _settings(hour: float, enabled: bool, levels, reflections: bool, scale: float = 0.5) -> Settings:
    s = Settings()
    set_value(s, "time_of_day.hour", hour)
    set_value(s, "camera.mode", "driver")
    for name, value in zip(("wetness", "cracks", "puddles"), levels, strict=True):
        set_value(s, f"rain.{name}", value)
    set_value(s, "road.enabled", enabled)
    set_value(s, "road.reflections", reflections)
    set_value(s, "road.reflection_scale", scale)
    set_value(s, "road.puddle_amount", 0.8)
    return s


def _timed_frame(ctx, scene: Scene) -> tuple[float, float | None]:
    """Wall ms of one rendered frame (GL work included) and the CPU ms of the road's prepare pass."""
    scene.step(1 / 30)
    ctx.finish()
    t0 = time.perf_counter()
    scene.render()
    ctx.finish()
    ms = (time.perf_counter() - t0) * 1e3
    stats = {name: cpu for name, ran, cpu, *_ in scene.renderer.pass_table() if ran}
    return ms, stats.get("road.prepare")


def _reflection_pass_ms(ctx, scene: Scene, effect: RoadEffect, repeat: int) -> float:
    """Median wall ms of the reflection pass alone (ctx.finish() before and after)."""
    frame = scene.frame()
    rc = scene.renderer.render_context(frame)
    rc.active = tuple(e for e in scene.renderer.effects if e.active(frame))  # what the mirror view draws
    effect.update(frame, rc)
    samples = []
    for _ in range(repeat + 1):
        ctx.finish()
        t0 = time.perf_counter()
        effect.render("prepare", rc)
        ctx.finish()
        samples.append((time.perf_counter() - t0) * 1e3)
    samples = sorted(samples[1:])
    return samples[len(samples) // 2]


def _display(hdr: np.ndarray) -> np.ndarray:
    x = np.maximum(hdr, 0.0)
    aces = np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    return np.where(aces <= 0.0031308, 12.92 * aces, 1.055 * aces ** (1 / 2.4) - 0.055) * 255.0


def cost_table(ctx, size, frames: int, hour: float) -> tuple[str, list]:
    """Frame cost per case. The cases are rendered in turn, frame after frame, so a burst of load elsewhere on
    the machine hits them alike; the minimum over frames is the least disturbed measurement."""
    scenes = []
    for _name, enabled, levels, reflections in CASES:
        settings = _settings(hour, enabled, levels, reflections)
        scene = Scene(ctx, size, settings, seed=1, effects=[], gpu_timing=False)
        scene.renderer.effects.append(RoadEffect(ctx, settings, shaders=scene.renderer.shaders))
        for _ in range(20):
            scene.step(1 / 30)
        _timed_frame(ctx, scene)  # warm-up: buffers, shader variants
        scenes.append(scene)
    times = [[] for _ in CASES]
    prepare = [[] for _ in CASES]
    for _ in range(frames):
        for i, scene in enumerate(scenes):
            ms, prep = _timed_frame(ctx, scene)
            times[i].append(ms)
            if prep is not None:
                prepare[i].append(prep)
    for scene in scenes:
        scene.release()
    ctx.detect_framebuffer(0).use()
    base = min(times[0])
    rows, data = [], []
    for (name, *_), ts, ps in zip(CASES, times, prepare, strict=True):
        best, median = min(ts), sorted(ts)[len(ts) // 2]
        rows.append((name, f"{best:.1f}", f"{median:.1f}", f"{best / base:.2f}",
                     f"{min(ps):.1f}" if ps else "-"))
        data.append((name, best))
    table = markdown_table(["case", "frame ms, min", "median", "min × disabled", "road.prepare ms (CPU side)"],
                           rows)
    return table, data


def scale_table(ctx, size, repeat: int, hour: float) -> tuple[str, list]:
    settings = _settings(hour, True, (1.0, 1.0, 1.0), True, 1.0)
    scene = Scene(ctx, size, settings, seed=1, effects=[], gpu_timing=False)
    effect = RoadEffect(ctx, settings, shaders=scene.renderer.shaders)
    scene.renderer.effects.append(effect)
    for _ in range(20):
        scene.step(1 / 30)
    frame = scene.frame()

    def render(scale: float | None) -> np.ndarray:
        set_value(settings, "road.reflections", scale is not None)
        if scale is not None:
            set_value(settings, "road.reflection_scale", scale)
        scene.renderer.render(frame)
        return scene.renderer.hdr_image()

    reference = render(1.0)
    without = render(None)
    lum_ref = reference @ LUMA
    mask = np.abs(lum_ref - without @ LUMA) > 0.01 * max(float(lum_ref.mean()), 1e-6)
    disp_ref = _display(reference)
    rows, data = [], []
    for scale in SCALES:
        image = render(scale)
        ms = _reflection_pass_ms(ctx, scene, effect, repeat)
        lum = image @ LUMA
        rel = float(np.sqrt(np.mean((lum - lum_ref)[mask] ** 2)) / lum_ref[mask].mean()) if mask.any() else 0.0
        mse = float(np.mean((_display(image) - disp_ref)[mask] ** 2)) if mask.any() else 0.0
        psnr = math.inf if mse == 0 else 10 * math.log10(255.0**2 / mse)
        px = effect._reflection.size
        rows.append((f"{scale:g}", f"{px[0]}×{px[1]}", f"{ms:.1f}", f"{rel:.4f}",
                     "∞" if math.isinf(psnr) else f"{psnr:.1f}"))
        data.append((scale, ms, rel))
    scene.release()
    ctx.detect_framebuffer(0).use()
    table = markdown_table(["reflection scale", "texture", "reflection pass ms (llvmpipe)",
                            "rel. RMS luminance error", "PSNR dB (display)"], rows)
    note = (f"{int(mask.sum())} of {mask.size} pixels show the reflection (where the frame without "
            "reflections differs by > 1 % of the mean).")
    return table + "\n\n" + note, data


def plot(cost: list, scales: list, path) -> None:
    w, h = 900, 380
    img = Image.new("RGB", (w, h), (255, 255, 255))
    d = ImageDraw.Draw(img)
    # Left: frame cost per case (bars).
    d.text((20, 8), "frame cost (ms, llvmpipe)", fill=(0, 0, 0))
    top = max(ms for _, ms in cost)
    for i, (name, ms) in enumerate(cost):
        y = 40 + i * 60
        d.rectangle((20, y, 20 + int(380 * ms / top), y + 24), fill=(70, 110, 180))
        d.text((24, y + 28), f"{name}: {ms:.1f}", fill=(0, 0, 0))
    # Right: reflection pass cost vs error per scale.
    x0, y0, pw, ph = 500, 40, 360, 280
    d.text((x0, 8), "reflection scale: pass ms (x) vs rel. error (y)", fill=(0, 0, 0))
    d.rectangle((x0, y0, x0 + pw, y0 + ph), outline=(0, 0, 0))
    max_ms = max(ms for _, ms, _ in scales) or 1.0
    max_err = max(err for _, _, err in scales) or 1.0
    pts = []
    for scale, ms, err in scales:
        px = x0 + 10 + (pw - 20) * ms / max_ms
        py = y0 + ph - 10 - (ph - 20) * err / max_err
        pts.append((px, py))
        d.ellipse((px - 4, py - 4, px + 4, py + 4), fill=(200, 60, 40))
        d.text((px + 6, py - 12), f"{scale:g}", fill=(0, 0, 0))
    d.line(pts, fill=(200, 60, 40), width=2)
    d.text((x0, y0 + ph + 6), f"0 … {max_ms:.0f} ms", fill=(0, 0, 0))
    d.text((x0 + pw - 120, y0 + ph + 6), f"error 0 … {max_err:.3f}", fill=(0, 0, 0))
    img.save(path)


def main(argv=None, ctx=None) -> int:
    """Run the benchmark (``ctx``: an existing context to use, e.g. the tests'; default: a new headless one)."""
    args = parser("road", __doc__.splitlines()[0]).parse_args(argv)
    size = (320, 180) if args.quick else (640, 360)
    frames = 3 if args.quick else 10
    ctx = ctx if ctx is not None else create_headless_context()
    with ctx:
        cost, cost_data = cost_table(ctx, size, frames, 12.0)
        scales, scale_data = scale_table(ctx, size, 2 if args.quick else 5, 12.0)
    md = (f"# Wet road benchmark\n\nDriver camera, noon, {size[0]}×{size[1]}, {frames} frames per case; "
          "wall time with ctx.finish() (llvmpipe: compare ratios).\n\n## Frame cost\n\n" + cost +
          "\n\n## Reflection resolution: cost vs error (scene fully flooded, reference = scale 1)\n\n" + scales)
    print(md)
    target = write_output(args.out, "road", md)
    plot(cost_data, scale_data, target.with_suffix(".png"))
    print(f"\nwrote {target} and {target.with_suffix('.png')}")
    return 0
