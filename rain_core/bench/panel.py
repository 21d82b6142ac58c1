"""The Rain Manager's share of the window's frame: ``python -m rain_core.bench panel [--quick] [--size 1280x720]``.

The window's frame is ``bench frame``'s (the scene's step and its passes) plus the app's panel
(``app.panel.RainManagerPanel``): its widgets built through ImGui, each reading its setting by path, then drawn
over the frame. This bench draws the panel over a heavy-rain frame (``frame.heavy_rain_case``: 8 mm/h, 100 km/h,
10,000 streaks; the scene drawn small, at 320×180, as it is not what is measured) in three states:

* **hidden**: Tab hid it (what is left: ImGui's frame, and its draw with nothing in it);
* **rain**: as the window opens, the Rain section open;
* **every section**: every header and tree open, the performance table among them.

Per state, over ``--frames`` frames after ``--warmup``: the panel's CPU ms per frame outside the GL driver
(``frame.GLCounter`` on the main thread's clock, as ``bench frame`` takes it), its GL calls and the ms inside
them, and the KB of vertices and indices it uploads. As in the window, the panel is drawn right behind the
frame's draws, which Mesa's driver thread may still be handing to the driver: a call that waits for that thread
shows in the ms inside GL (on llvmpipe the main thread then does the frame's vertex work itself). The panel is
drawn at ``--size``, the window's size, so its docked width is a quarter of that (at most 480 px). The app
imports ``imgui_bundle``, a dependency of the package; the core imports nothing of the app but here.
"""

from __future__ import annotations

import argparse
import statistics
import sys

from rain_core.bench._common import headless_run, markdown_table, write_tables
from rain_core.bench.frame import CLOCKS, GLCounter, gl_description, heavy_rain_case, parse_size

STATES = ("hidden", "rain", "every section")
SCENE_SIZE = (320, 180)  # px: the scene under the panel (its cost is bench frame's)
BUDGET = 10_000
SPEED_KMH = 100.0
DT_S = 1.0 / 60.0


def measure_state(ctx, state: str, size=(1280, 720), frames: int = 60, warmup: int = 10) -> dict:
    """The panel in ``state`` (one of STATES) at window ``size`` (px) over a heavy-rain scene: medians over
    ``frames`` drawn frames after ``warmup``. Returns {"state", "cpu_ms" (outside GL), "gl_ms", "gl_calls",
    "upload_kb", "cpu_ms_all" (with the GL calls), "sections" (the headers open)}."""
    from app.panel import RainManagerPanel

    if state not in STATES:
        raise ValueError(f"state must be one of {', '.join(STATES)}, got {state!r}")
    scene, drive = heavy_rain_case(ctx, SCENE_SIZE, BUDGET, SPEED_KMH)
    panel = RainManagerPanel(ctx, size, scene, expand_all=state == "every section")
    panel.visible = state != "hidden"
    target = ctx.simple_framebuffer(size)
    counter = GLCounter()
    clock = CLOCKS[counter.clock]
    rows = []
    try:
        with counter:
            for k in range(warmup + frames):
                counter.bucket = "scene"
                scene.step(DT_S, drive)
                scene.render()  # not finished: the panel is drawn behind the frame's draws, as in the window
                counter.tallies.pop("panel", None)
                counter.bucket = "panel"
                t0 = clock()
                panel.draw(DT_S, target)
                spent = clock() - t0
                counter.bucket = "finish"
                ctx.finish()
                if k >= warmup:
                    tally = counter.tallies["panel"]
                    inside = tally.ns + tally.calls * counter.overhead_ns
                    rows.append({"cpu_ms": (spent - inside) * 1e-6, "gl_ms": tally.ns * 1e-6, "gl_calls": tally.calls,
                                 "upload_kb": tally.upload_bytes / 1024.0, "cpu_ms_all": spent * 1e-6})
        sections = list(panel.open_sections)
    finally:
        panel.layer.shutdown()
        target.release()
        scene.release()
    result = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
    return {"state": state, **result, "sections": sections}


def table(results: list[dict]) -> str:
    return markdown_table(
        ["panel", "headers open", "CPU ms outside GL", "GL calls", "ms inside GL", "upload KB", "CPU ms with GL"],
        [[r["state"], len(r["sections"]), round(r["cpu_ms"], 3), round(r["gl_calls"]), round(r["gl_ms"], 3),
          round(r["upload_kb"], 1), round(r["cpu_ms_all"], 3)] for r in results])


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m rain_core.bench panel",
                                description="The Rain Manager's CPU ms per frame (issue 13)")
    p.add_argument("--out", default="bench_out", help="folder for panel.md and panel.json")
    p.add_argument("--quick", action="store_true", help="a few frames per state (smoke tests)")
    p.add_argument("--size", type=parse_size, default=(1280, 720), help="window size WxH in px (default 1280x720)")
    p.add_argument("--frames", type=int, default=60, help="frames timed per state (default 60)")
    p.add_argument("--warmup", type=int, default=10, help="frames drawn first, untimed (default 10)")
    args = p.parse_args(argv)
    if args.frames < 1:
        p.error(f"--frames must be at least 1, got {args.frames}")
    if args.warmup < 0:
        p.error(f"--warmup must be at least 0, got {args.warmup}")
    if args.quick:
        args.frames, args.warmup = min(args.frames, 3), min(args.warmup, 2)
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    with headless_run(args.out) as (out, ctx):
        head = (f"# The Rain Manager's CPU per frame\n\nWindow {args.size[0]}x{args.size[1]}, over a heavy-rain frame "
                f"({SPEED_KMH:.0f} km/h); medians of {args.frames} frames after {args.warmup}; {gl_description(ctx)}.")
        print(head, flush=True)
        results = [measure_state(ctx, state, args.size, args.frames, args.warmup) for state in STATES]
    print("\n" + table(results))
    write_tables(out, "panel", head + "\n\n" + table(results), results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
