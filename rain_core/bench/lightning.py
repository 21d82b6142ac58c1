"""Lightning benchmark: what a storm costs per frame — a frame with a flash lit (the bolt pass, the flash in the
light list, the lit sky) against the frames between flashes and a scene without a storm, and the CPU cost of the
schedule and the bolt's geometry.

``python -m rain_core.bench lightning [--quick] [--out DIR]`` prints the tables and writes DIR/lightning.md. On
llvmpipe (CPU-emulated GL) compare ratios, not absolute milliseconds.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from rain_core.bench._common import markdown_table, parser, time_call, write_output
from rain_core.effects.lightning.bolt import bolt_segments
from rain_core.effects.lightning.storm import Storm
from rain_core.gfx.context import create_headless_context
from rain_core.settings import Settings
from rain_core.sheets.lightning import SEED, near_flash


def _frames(ctx, case: str, frames: int, size) -> tuple[bool, float, float, float]:
    """(lightning pass ran, its ms, the scene pass ms, all passes ms), medians over frames at the case's time."""
    from rain_core.scene import Scene

    s = Settings()
    s.rain.rate_mm_h = 20.0
    s.time_of_day.hour = 22.0
    s.lightning.flashes_per_min = 0.0 if case == "no storm" else 10.0
    scene = Scene(ctx, size, s, seed=SEED, gpu_timing=True)
    flash = near_flash()
    t = flash.start_s + 0.045 if case == "flash lit" else flash.start_s - 1.0
    while scene.time_s < t - 1e-9:
        scene.step(min(0.25, t - scene.time_s))
    times: dict[str, list[float]] = {}
    try:
        for i in range(frames + 2):
            scene.render()  # time frozen: the same frame each time
            ctx.finish()
            if i < 2:
                continue
            for p in scene.renderer.stats:
                if p.ran:
                    times.setdefault(p.name, []).append(p.gpu_ms if p.gpu_ms is not None else p.cpu_ms)
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()
    med = {k: statistics.median(v) for k, v in times.items()}
    lit = "lightning.transparent" in med
    return lit, med.get("lightning.transparent", 0.0), med.get("scene", 0.0), sum(med.values())


def main(argv=None) -> int:
    args = parser("lightning", __doc__).parse_args(argv)
    frames, size = (3, (320, 180)) if args.quick else (10, (640, 360))
    ctx = create_headless_context()
    rows = []
    for case in ("flash lit", "between flashes", "no storm"):
        lit, bolt, scene_ms, total = _frames(ctx, case, frames, size)
        rows.append((case, "yes" if lit else "skipped", bolt, scene_ms, total))
    cost = markdown_table(["frame", "lightning pass", "bolt ms", "scene pass ms", "all passes ms"], rows)
    s = Settings()
    s.lightning.flashes_per_min = 10.0
    storm = Storm(seed=SEED)
    clock = [0.0]

    def view():
        clock[0] += 1.0 / 30.0
        storm.frame_view(s, clock[0], 1.0 / 30.0, np.zeros(3), 20.0)

    view_ms = time_call(view, repeat=200) * 1e3
    f = near_flash()
    t0 = time.perf_counter()
    segments, _ = bolt_segments([0.0, 1500.0, 0.0], [0.0, 0.0, 0.0], f.seed)
    bolt_ms = (time.perf_counter() - t0) * 1e3
    cpu = markdown_table(["CPU work", "ms"], [("storm.frame_view per frame", view_ms),
                                               (f"bolt geometry, once per flash ({len(segments)} segments)", bolt_ms)])
    md = f"# Lightning\n\nFrames at {size[0]}×{size[1]}, 20 mm/h at night (llvmpipe: ratios):\n\n{cost}\n\n{cpu}\n"
    print(md)
    write_output(args.out, "lightning", md)
    return 0
