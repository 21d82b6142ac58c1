"""Drips benchmark: the drips' cost under the bridge in the rain, after it while the deck drains, and on a dry
day (nothing runs), plus the one-off search of the world's drip sites.

``python -m rain_core.bench drips [--quick] [--out DIR]`` prints the tables and writes DIR/drips.md. On llvmpipe
(CPU-emulated GL) compare ratios, not absolute milliseconds.
"""

from __future__ import annotations

import statistics
import time

from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.camera import look_at
from rain_core.effects.drips.edges import find_drip_sites
from rain_core.gfx.context import create_headless_context
from rain_core.settings import Settings
from rain_core.sheets.drips import BRIDGE


def _case(ctx, rate: float, after_s: float, frames: int, size) -> dict[str, float]:
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = rate
    s.traffic.count = 0
    scene = Scene(ctx, size, s, seed=1, gpu_timing=True)
    camera = look_at(BRIDGE[0], BRIDGE[1], fov_y_deg=60.0)
    times: dict[str, list[float]] = {}
    try:
        scene.step(1.0 / 30.0)
        scene.render(camera)
        if after_s > 0.0:
            s.rain.rate_mm_h = 0.0
            for _ in range(int(after_s / 0.25)):
                scene.step(0.25)
        for i in range(frames + 2):
            scene.step(1.0 / 30.0)
            scene.render(camera)
            ctx.finish()
            if i < 2:
                continue
            for p in scene.renderer.stats:
                if p.ran:
                    times.setdefault(p.name, []).append(p.gpu_ms if p.gpu_ms is not None else p.cpu_ms)
                    times.setdefault(p.name + " (cpu)", []).append(p.cpu_ms)
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()
    return {k: statistics.median(v) for k, v in times.items()}


def main(argv=None) -> int:
    args = parser("drips", __doc__).parse_args(argv)
    frames, size = (3, (320, 180)) if args.quick else (10, (640, 360))
    ctx = create_headless_context()
    rows = []
    for label, rate, after in (("8 mm/h under the bridge", 8.0, 0.0), ("2 min after the rain", 8.0, 120.0),
                               ("dry day", 0.0, 0.0)):
        t = _case(ctx, rate, after, frames, size)
        drips = t.get("drips.transparent", 0.0)
        cpu = t.get("drips.observe (cpu)", 0.0) + t.get("drips.update (cpu)", 0.0)
        total = sum(v for k, v in t.items() if not k.endswith(" (cpu)"))
        rows.append((label, "yes" if "drips.transparent" in t else "skipped", drips, cpu, total))
    cost = markdown_table(["case", "drips pass", "pass ms", "CPU ms (observe + update)", "all passes ms"], rows)
    from rain_core.world import build_world

    world = build_world(1)
    m = world.occluder_map
    t0 = time.perf_counter()
    sites = find_drip_sites(m.grid, m.x0_m, m.cell_m, 1)
    search_ms = (time.perf_counter() - t0) * 1e3
    md = (f"# Drips\n\nFrames at {size[0]}×{size[1]} (llvmpipe: ratios):\n\n{cost}\n\n"
          f"Finding the drip sites of a world (once per world, on the first rainy frame): {search_ms:.0f} ms, "
          f"{len(sites)} sites over the street on {len(sites.area_m2)} low roofs.\n")
    print(md)
    write_output(args.out, "drips", md)
    return 0
