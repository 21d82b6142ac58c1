"""Windshield benchmark (issue 8): ``python -m rain_core.bench windshield [--quick] [--out DIR]``.

1. CPU: milliseconds per frame (1/30 s) of ``WindshieldSim.step`` against the number of drops on the glass,
   parked (drops mostly at rest), at 60 km/h and at 120 km/h (many drops running), wipers on low.
2. GPU: the windshield passes (water textures + the glass) against the water-texture resolution, and the error
   of each resolution against the finest, from one identical simulated state: RMS difference of the displayed
   frame (sRGB 0–1, over the whole frame) and of the water thickness texture averaged to 64² cells
   (relative L1). Run time against error.
3. GPU: the water-texture pass against the drop count at the default resolution.
4. The skip: a dry, clean glass (no rain, wipers on auto) runs no windshield pass at all.

On Mesa's llvmpipe the "GPU" times are the CPU emulating one: compare ratios, not absolute values.
Writes windshield.md (tables) and windshield.png (plots) into --out.
"""

from __future__ import annotations

import copy
import math
import time

import numpy as np

from rain_core.bench._common import markdown_table, parser, write_output

FPS = 30.0


def _fill(sim, inputs, target: int, limit_s: float = 30.0) -> None:
    """Run until ``target`` drops are on the glass (or ``limit_s`` of simulated time passed)."""
    for _ in range(int(limit_s * FPS)):
        sim.step(1.0 / FPS, inputs)
        if sim.count >= target:
            return


def cpu_cost(counts, repeat: int) -> list[tuple]:
    """(drops, parked ms, 60 km/h ms, 120 km/h ms) per frame, median of ``repeat`` frames."""
    from rain_core.effects.windshield import GlassInputs, WindshieldSim

    rows = []
    for n in counts:
        row = [n]
        for speed in (0.0, 60.0, 120.0):
            sim = WindshieldSim(seed=1)
            fill = GlassInputs.for_speed(60.0, 16.0, drop_budget=n)
            _fill(sim, fill, int(0.97 * n))
            inputs = GlassInputs.for_speed(speed, 4.0, drop_budget=n, wiper_mode="low")
            for _ in range(5):
                sim.step(1.0 / FPS, inputs)
            samples = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                sim.step(1.0 / FPS, inputs)
                samples.append(time.perf_counter() - t0)
            row.append(1e3 * float(np.median(samples)))
        rows.append(tuple(row))
    return rows


def _frame_passes(scene) -> float:
    """GPU (or wall) ms of the windshield's draw passes in the last frame."""
    total = 0.0
    for name, ran, cpu_ms, gpu_ms, *_ in scene.renderer.pass_table():
        if ran and name in ("windshield.prepare", "windshield.overlay"):
            total += gpu_ms if gpu_ms is not None else cpu_ms
    return total


def _render_state(ctx, base_sim, settings, resolution: int, size, frames: int):
    """Render ``frames`` frames from a copy of ``base_sim`` at a water-texture resolution; returns (median ms
    of
    the windshield passes, last image as float sRGB, the water thickness texture averaged to 64² cells)."""
    from rain_core.effects.windshield import FILM_CELLS, WindshieldEffect
    from rain_core.scene import Scene

    s = copy.deepcopy(settings)
    s.quality.windshield_resolution = resolution
    effect = WindshieldEffect(ctx, s, seed=1)
    effect.sim = copy.deepcopy(base_sim)
    scene = Scene(ctx, size, s, seed=1, effects=[effect])
    scene.ego.speed_m_s = 60.0 / 3.6
    scene.autopilot.target_speed_m_s = 60.0 / 3.6
    times = []
    for _ in range(frames):
        scene.step(1.0 / FPS)
        scene.render()
        times.append(_frame_passes(scene))
    image = scene.image().astype(np.float64) / 255.0
    n = effect.resolution
    water = np.frombuffer(effect.water_texture.read(), np.float16).reshape(n, n, 4)[..., 0].astype(np.float64)
    k = n // FILM_CELLS
    cells = water.reshape(FILM_CELLS, k, FILM_CELLS, k).mean(axis=(1, 3)) if k >= 1 else water
    scene.release()
    return float(np.median(times[1:] if len(times) > 1 else times)), image, cells


def gpu_resolution(ctx, resolutions, size, frames: int) -> list[tuple]:
    from rain_core.effects.windshield import GlassInputs, WindshieldSim
    from rain_core.settings import Settings

    settings = Settings()
    settings.rain.rate_mm_h = 4.0
    settings.wipers.mode = "off"
    base = WindshieldSim(seed=3)
    for _ in range(int(8 * FPS)):
        base.step(1.0 / FPS, GlassInputs.for_speed(60.0, 4.0))
    results = {r: _render_state(ctx, base, settings, r, size, frames) for r in resolutions}
    finest = max(resolutions)
    _, ref_img, ref_cells = results[finest]
    rows = []
    for r in resolutions:
        ms, img, cells = results[r]
        rms = float(np.sqrt(np.mean((img - ref_img) ** 2)))
        cells_err = float(np.abs(cells - ref_cells).sum() / max(np.abs(ref_cells).sum(), 1e-12))
        rows.append((r, ms, rms, cells_err))
    return rows


def gpu_drops(ctx, counts, size, frames: int) -> list[tuple]:
    """(drops, ms of the windshield passes) at the default 512² water texture."""
    from rain_core.effects.windshield import GlassInputs, WindshieldSim
    from rain_core.settings import Settings

    settings = Settings()
    settings.rain.rate_mm_h = 4.0
    settings.wipers.mode = "off"
    rows = []
    for n in counts:
        base = WindshieldSim(seed=4)
        settings.windshield.drop_budget = n
        _fill(base, GlassInputs.for_speed(60.0, 16.0, drop_budget=n), int(0.97 * n))
        ms, _, _ = _render_state(ctx, base, settings, 512, size, frames)
        rows.append((base.count, ms))
    return rows


def skip_check(ctx, size) -> tuple[bool, float]:
    """(whether any windshield pass ran, their cost in ms) for a dry glass without rain, wipers on auto."""
    from rain_core.effects.windshield import WindshieldEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = 0.0
    s.wipers.mode = "auto"
    scene = Scene(ctx, size, s, seed=1, effects=[WindshieldEffect(ctx, s)])
    scene.step(1.0 / FPS)
    scene.render()
    ran = [row for row in scene.renderer.pass_table() if row[0].startswith("windshield.") and row[1]]
    scene.release()
    return bool(ran), sum(r[2] for r in ran)


def _plot(path, cpu_rows, res_rows, drop_rows) -> None:
    from PIL import Image, ImageDraw

    w, h = 960, 360
    img = Image.new("RGB", (w, h), (255, 255, 255))
    d = ImageDraw.Draw(img)
    panels = [
        (20, "CPU ms/frame vs drops (log-log)"),
        (340, "frame RMS error vs GPU ms (log y)"),
        (660, "GPU ms vs drops (512 px texture)"),
    ]
    for x0, title in panels:
        d.rectangle([x0 + 30, 40, x0 + 290, 320], outline=(0, 0, 0))
        d.text((x0 + 30, 15), title, fill=(0, 0, 0))

    def scale(values, lo_px, hi_px, log=False):
        v = np.log10(np.maximum(np.asarray(values, float), 1e-9)) if log else np.asarray(values, float)
        lo, hi = float(v.min()), float(v.max())
        span = hi - lo if hi > lo else 1.0
        return lo_px + (v - lo) / span * (hi_px - lo_px)

    colors = [(200, 40, 40), (40, 120, 200), (40, 160, 60)]
    if cpu_rows:
        counts = [r[0] for r in cpu_rows]
        all_ms = [m for r in cpu_rows for m in r[1:]]
        xs = scale(counts, 70, 300, log=True)
        ys_all = scale(all_ms, 310, 50, log=True)
        for j, (label, color) in enumerate(zip(("parked", "60 km/h", "120 km/h"), colors, strict=True)):
            ys = ys_all[j::3]
            d.line(list(zip(xs.tolist(), ys.tolist(), strict=True)), fill=color, width=2)
            d.text((60, 50 + 14 * j), label, fill=color)
        for c, x in zip(counts, xs, strict=True):
            d.text((x - 10, 322), str(c), fill=(0, 0, 0))
        d.text((22, 42), f"{max(all_ms):.1f} ms", fill=(0, 0, 0))
        d.text((22, 300), f"{min(all_ms):.1f} ms", fill=(0, 0, 0))
    if res_rows:
        ms = [r[1] for r in res_rows]
        err = [max(r[2], 1e-4) for r in res_rows]
        xs, ys = scale(ms, 390, 610), scale(err, 310, 50, log=True)
        d.line(list(zip(xs.tolist(), ys.tolist(), strict=True)), fill=colors[1], width=2)
        for r, x, y in zip(res_rows, xs, ys, strict=True):
            d.ellipse([x - 3, y - 3, x + 3, y + 3], fill=colors[0])
            ref = " (reference)" if r[2] == 0 else f" {r[2]:.3f}"
            d.text((x + 4, y - 12), f"{r[0]} px{ref}", fill=(0, 0, 0))
        d.text((372, 322), f"{min(ms):.0f} ms", fill=(0, 0, 0))
        d.text((580, 322), f"{max(ms):.0f} ms", fill=(0, 0, 0))
    if drop_rows:
        xs = scale([r[0] for r in drop_rows], 710, 940)
        ys = scale([r[1] for r in drop_rows], 310, 50)
        d.line(list(zip(xs.tolist(), ys.tolist(), strict=True)), fill=colors[2], width=2)
        for r, x, y in zip(drop_rows, xs, ys, strict=True):
            d.text((x - 10, y - 14), f"{r[1]:.0f} ms", fill=(0, 0, 0))
    img.save(path)


def main(argv=None) -> int:
    p = parser("windshield", __doc__.splitlines()[0])
    args = p.parse_args(argv)
    quick = args.quick
    counts = (2000, 10000) if quick else (500, 2000, 5000, 10000)
    cpu_rows = cpu_cost(counts, repeat=10 if quick else 40)
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    size = (320, 180) if quick else (640, 360)
    resolutions = (128, 256, 512, 1024) if quick else (128, 256, 512, 1024, 2048)
    res_rows = gpu_resolution(ctx, resolutions, size, frames=3 if quick else 6)
    drop_rows = gpu_drops(ctx, (500, 5000) if quick else (500, 2000, 5000, 10000), size, frames=3)
    ran, skip_ms = skip_check(ctx, size)
    md = [
        "# Windshield benchmark",
        "",
        "CPU: WindshieldSim.step per 1/30 s frame, wipers low, 4 mm/h (median ms).",
        "",
        markdown_table(("drops", "parked ms", "60 km/h ms", "120 km/h ms"), cpu_rows),
        "",
        f"GPU: the windshield passes against the water-texture resolution ({size[0]}×{size[1]} frame, "
        f"error against {max(resolutions)}²).",
        "",
        markdown_table(("resolution", "passes ms", "frame RMS (sRGB)", "thickness L1 (rel.)"), res_rows),
        "",
        "GPU: the windshield passes against the drop count (512²).",
        "",
        markdown_table(("drops", "passes ms"), drop_rows),
        "",
        f"Dry glass, no rain, wipers auto: windshield passes run: {ran} ({skip_ms:.3f} ms).",
        "",
        "On llvmpipe the GPU column is the CPU emulating a GPU: compare ratios.",
    ]
    text = "\n".join(md)
    print(text)
    write_output(args.out, "windshield", text)
    from pathlib import Path

    _plot(Path(args.out) / "windshield.png", cpu_rows, res_rows, drop_rows)
    ctx.release()
    return 0 if not ran and math.isfinite(skip_ms) else 1
