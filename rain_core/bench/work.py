"""The GPU's work in a heavy-rain frame, counted rather than timed: fragments and primitives per pass.

``python -m rain_core.bench work [--quick] [--size 1920x1080] [--budgets 50000,1000000] [--speeds 0,100]``

Timings need the GPU they are taken on; counts do not. Each pass of a drawn frame runs inside one GL query of
two counters:

* **fragments**: ``GL_SAMPLES_PASSED``, the fragments the pass wrote (each layer of a blended one counts; a
  fragment the depth test or a ``discard`` dropped does not). In "screens", fragments ÷ (width × height): a
  full-screen pass is 1, the streaks' overdraw what it is. This is the pass's fill, what a GPU's ROPs spend.
  The passes into targets of their own (the shadow map, the ripples' grid, the glass's film) keep their size at
  any display size.
* **primitives**: ``GL_PRIMITIVES_GENERATED``, the points, lines and triangles its vertex stage assembled
  (transform feedback's too). The streaks: one point per drop instance (their record pass) and two triangles
  per instance (their quads).

The rasteriser's rules are exact in GL (pixel centres, the top-left rule), so llvmpipe counts what any GPU would
do with the same draws: the frame's GPU work at the display's size, measured without a GPU. Shader cost per
fragment is not in them (the windshield's glass and the atmosphere's in-scatter are one screen each, but their
fragments are heavy): ``bench frame --pass-wall`` times that on llvmpipe, and on a GPU ``bench frame --size
1920x1080`` times it all.

Each case is ``bench frame``'s (heavy rain 8 mm/h, wetness, cracks and puddles at 1, the driver camera, noon,
parked or at 100 km/h): ``--warmup`` frames stepped undrawn (the simulations and their state stages), then
``--frames`` drawn ones; per pass the median over the drawn frames. "rain" adds up the rain's own effects
(``frame.RAIN_EFFECTS``).
"""

from __future__ import annotations

import argparse
import statistics
import sys

from rain_core.bench._common import headless_run, write_tables
from rain_core.bench.frame import (
    RAIN_EFFECTS,
    RAIN_MM_H,
    SPEEDS_KMH,
    _effect_of,
    check_overrides,
    gl_description,
    heavy_rain_case,
    parse_budgets,
    parse_override,
    parse_size,
)

BUDGETS = (50_000, 1_000_000)
DT_S = 1.0 / 30.0  # the recording's step
RAIN_ROW = "rain: " + " + ".join(RAIN_EFFECTS)
FRAME_ROW = "whole frame"


def count_case(ctx, size=(1920, 1080), budget: int = 50_000, speed_kmh: float = 0.0, frames: int = 2,
               warmup: int = 30, seed: int = 1, overrides=()) -> dict:
    """Step ``warmup`` undrawn frames of ``DT_S`` s, then draw ``frames`` (size in px, streak budget, ego speed in
    km/h) and count each pass's fragments and primitives. Returns {"rows": {name: {"fragments", "primitives",
    "screens"}} (passes in order, then "effect: NAME", the rain's sum and the whole frame; medians over the drawn
    frames), "passes": [...], "streak_instances": the rainfall's drop instances, ...}."""
    from rain_core.gfx.renderer import Renderer
    queries: dict[str, object] = {}
    counts: dict[str, list[tuple[int, int]]] = {}
    order: list[str] = []
    counting = [False]
    original_timed = Renderer._timed

    def timed(self, name, fn):
        if not counting[0]:
            return original_timed(self, name, fn)
        query = queries.get(name)
        if query is None:
            query = queries[name] = ctx.query(samples=True, primitives=True)

        def run():
            with query:
                fn()

        original_timed(self, name, run)
        if self.stats and self.stats[-1].name == name and self.stats[-1].ran:
            if name not in counts:
                order.append(name)
            counts.setdefault(name, []).append((int(query.samples), int(query.primitives)))

    Renderer._timed = timed
    scene = None
    try:
        scene, drive = heavy_rain_case(ctx, size, budget, speed_kmh, seed, overrides)
        for _ in range(warmup):
            scene.step(DT_S, drive)
            scene.render(draw=False)
        counting[0] = True
        for _ in range(frames):
            scene.step(DT_S, drive)
            scene.render()
        counting[0] = False
        rainfall = next((e for e in scene.effects if e.name == "rainfall"), None)
        instances = int(rainfall.sim.capacity) if getattr(rainfall, "sim", None) is not None else 0
        splashes = int(rainfall.sim.splash_capacity) if instances else 0
    finally:
        Renderer._timed = original_timed  # (moderngl's queries have no release: they go with the context)
        if scene is not None:
            scene.release()
    pixels = float(size[0] * size[1])

    def row(fragments: float, primitives: float) -> dict:
        return {"fragments": fragments, "primitives": primitives, "screens": fragments / pixels}

    rows = {}
    for name in order:  # a pass missing from a frame (e.g. a skipped one) counts 0 there
        per_frame = counts[name] + [(0, 0)] * (frames - len(counts[name]))
        rows[name] = row(statistics.median(f for f, _ in per_frame), statistics.median(p for _, p in per_frame))
    totals: dict[str, list[float]] = {}
    for name, values in rows.items():
        effect = _effect_of(name)
        keys = [FRAME_ROW] + [f"effect: {effect}"] * (effect != name) + [RAIN_ROW] * (effect in RAIN_EFFECTS)
        for key in keys:
            acc = totals.setdefault(key, [0.0, 0.0])
            acc[0] += values["fragments"]
            acc[1] += values["primitives"]
    for key in sorted(k for k in totals if k.startswith("effect: ")) + [RAIN_ROW, FRAME_ROW]:
        rows[key] = row(*totals.get(key, (0.0, 0.0)))
    return {"size": tuple(size), "budget": int(budget), "speed_kmh": float(speed_kmh), "frames": int(frames),
            "warmup": int(warmup), "passes": order, "rows": rows, "streak_instances": instances,
            "splash_instances": splashes}


def case_label(result: dict) -> str:
    return f"{result['speed_kmh']:g} km/h, budget {result['budget']:,}"


def case_table(result: dict) -> str:
    lines = ["| pass | fragments (M) | screens | primitives |", "|---|---|---|---|"]
    for name, r in result["rows"].items():
        if not (r["fragments"] or r["primitives"] or name in (RAIN_ROW, FRAME_ROW)):
            continue  # a pass without draws (an update, an upload): in the JSON only
        bold = "**" if name in (RAIN_ROW, FRAME_ROW) else ""
        lines.append(f"| {bold}{name}{bold} | {r['fragments'] / 1e6:.3f} | {r['screens']:.2f} | "
                     f"{r['primitives']:,.0f} |")
    return "\n".join(lines)


def summary_table(results: list[dict]) -> str:
    lines = ["| km/h | streak budget | drop instances | streaks: fragments (M) | streaks: primitives | "
             "rain: fragments (M) | rain: screens | frame: fragments (M) | frame: screens | frame: primitives |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        rows = r["rows"]
        streaks = rows.get("rainfall.transparent", {"fragments": 0.0, "primitives": 0.0})
        rain, frame = rows[RAIN_ROW], rows[FRAME_ROW]
        lines.append(f"| {r['speed_kmh']:g} | {r['budget']:,} | {r['streak_instances']:,} | "
                     f"{streaks['fragments'] / 1e6:.2f} | {streaks['primitives']:,.0f} | "
                     f"{rain['fragments'] / 1e6:.2f} | {rain['screens']:.2f} | {frame['fragments'] / 1e6:.2f} | "
                     f"{frame['screens']:.2f} | {frame['primitives']:,.0f} |")
    return "\n".join(lines)


def header(args, renderer: str) -> str:
    return (f"# The GPU's work in a frame at heavy rain ({RAIN_MM_H:g} mm/h, wetness/cracks/puddles 1, driver "
            f"camera, noon), {args.size[0]}x{args.size[1]}"
            + "".join(f", {path} = {value!r}" for path, value in args.overrides) + "\n\n"
            f"GL: {renderer}. Counted by GL queries around each pass: fragments = GL_SAMPLES_PASSED (written, "
            "blended layers each; not those the depth test or a discard dropped), screens = fragments / (width x "
            "height; the passes into their own targets, the shadow map and the ripples' and the glass's textures, "
            "keep their size at any display size), primitives = GL_PRIMITIVES_GENERATED (transform feedback's "
            "included). Machine-independent (GL's rasterisation rules are exact); a fragment's shader cost is not "
            "in them; passes that draw nothing are left out of the tables. "
            f"{args.warmup} undrawn frames of {DT_S:.4g} s, then the median of {args.frames} drawn.\n")


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m rain_core.bench work", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="bench_out", help="folder for work.md and work.json")
    p.add_argument("--quick", action="store_true", help="320x180, budget 10k at 100 km/h, 1 frame after 4")
    p.add_argument("--size", type=parse_size, default=None, help="frame size WxH (default 1920x1080)")
    p.add_argument("--budgets", type=parse_budgets, default=None, help="streak budgets (default 50000,1000000)")
    p.add_argument("--speeds", default=None, help="ego speeds in km/h, e.g. 0,100 (default both)")
    p.add_argument("--frames", type=int, default=None, help="drawn frames per case, their median (default 2)")
    p.add_argument("--warmup", type=int, default=None, help="undrawn frames before them (default 30: 1 s)")
    p.add_argument("--set", dest="overrides", type=parse_override, action="append", default=[],
                   metavar="PATH=VALUE", help="a setting on top of the heavy-rain ones, by its settings path "
                                              "(repeatable)")
    args = p.parse_args(argv)
    args.size = args.size or ((320, 180) if args.quick else (1920, 1080))
    args.budgets = args.budgets or ((10_000,) if args.quick else BUDGETS)
    try:
        speeds = (tuple(float(v) for v in args.speeds.split(",")) if args.speeds
                  else (100.0,) if args.quick else SPEEDS_KMH)
    except ValueError:
        p.error(f"--speeds must be comma-separated km/h, got {args.speeds!r}")
    if not all(0.0 <= v <= 250.0 for v in speeds):  # (also rejects NaN)
        p.error(f"--speeds must be in [0, 250] km/h, got {args.speeds!r}")
    args.speeds = speeds
    args.frames = args.frames if args.frames is not None else (1 if args.quick else 2)
    args.warmup = args.warmup if args.warmup is not None else (4 if args.quick else 30)
    if not 1 <= args.frames <= 100 or not 0 <= args.warmup <= 10_000:
        p.error(f"--frames must be in [1, 100] and --warmup in [0, 10000], got {args.frames} and {args.warmup}")
    check_overrides(p, args.overrides)
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    with headless_run(args.out) as (out, ctx):
        head = header(args, gl_description(ctx))
        print(head, flush=True)
        results = []
        for speed in args.speeds:
            for budget in args.budgets:
                results.append(count_case(ctx, args.size, budget, speed, args.frames, args.warmup,
                                          overrides=args.overrides))
                print(f"## {case_label(results[-1])}\n\n{case_table(results[-1])}\n", flush=True)
    md = (head + "\n## Summary\n\n" + summary_table(results) + "\n\n"
          + "\n\n".join(f"## {case_label(r)}\n\n{case_table(r)}" for r in results))
    print("## Summary\n\n" + summary_table(results))
    write_tables(out, "work", md, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
