"""Windshield benchmark (issues 8, 13): ``python -m rain_core.bench windshield [--quick] [--cpu-only] [--frame-case]
[--jit on|off] [--out DIR]``.

1. CPU: milliseconds per frame (1/30 s, one sub-step) of ``WindshieldSim.step`` (the fast path) and of
   ``WindshieldSimReference.step`` (the float64 reference, the algorithm of the code before issue 13) against the
   number of drops on the glass, parked, at 60 and at 120 km/h, in heavy rain (8 mm/h) with the wipers on low.
   Both start from the same filled glass, their frames interleaved; each time is the minimum (and the median) of
   many frames, of the main thread's CPU time (``--clock thread``, the default: robust on a shared machine) or of
   wall time (``--clock wall``). Also a light-rain row (2 mm/h, parked): the cost of a glass at rest, and a
   "120~" row at 120 km/h whose speed drifts a little every frame, as the scene's autopilot holds it.
   ``--jit``: the fast path with its compiled kernels (``kernels``, where Numba is installed) or its NumPy
   twins (``off``), for before/after on one tree.
   Accuracy: after 30 more frames from that state, the largest distance between a drop of the fast path and the
   same drop of the reference (µm; "diverged" if a rounding flipped one merge and the drop lists differ) and the
   relative difference of the water on the glass.
   The frame case (``--frame-case`` alone, or after the table): the frame benchmark's glass (~5,800 drops,
   100 km/h, heavy rain, wipers auto and sweeping) stepped alone, and a digest of the glass after it; then,
   with the compiled kernels, where its step goes: each kernel timed around its calls, and the rest.
2. GPU: the windshield passes (water textures + the glass) against the water-texture resolution, and the error
   of each resolution against the finest, from one identical simulated state: RMS difference of the displayed
   frame (sRGB 0–1, over the whole frame) and of the water thickness texture averaged to 64² cells
   (relative L1). Run time against error. Bytes uploaded per frame (splat instances and the coarse film).
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

from rain_core.bench._common import add_jit_argument, apply_jit_argument, markdown_table, parser, write_output

FPS = 30.0
RATE_MM_H = 8.0  # heavy rain
LIGHT_MM_H = 2.0  # light rain: the glass mostly at rest


def _fill(sim, inputs, target: int, limit_s: float = 30.0) -> None:
    """Run until ``target`` drops are on the glass (or ``limit_s`` of simulated time passed)."""
    for _ in range(int(limit_s * FPS)):
        sim.step(1.0 / FPS, inputs)
        if sim.count >= target:
            return


CLOCKS = {"thread": time.thread_time, "wall": time.perf_counter}


def _frame_inputs(inputs, k: int):
    """The inputs of frame ``k``: ``inputs`` itself, or of a list of them the k-th (cycled)."""
    return inputs[k % len(inputs)] if isinstance(inputs, list) else inputs


def _time_steps(sims, inputs, repeat: int, clock: str = "thread") -> list[tuple[float, float]]:
    """(min, median) ms of ``repeat`` frames of each simulation (``clock``: the main thread's CPU time or wall
    time), their frames interleaved so that both see the same machine (on a shared one the load comes and goes:
    the minimum is the step's own cost). ``inputs``: one GlassInputs, or a list, one a frame (cycled)."""
    now = CLOCKS[clock]
    samples = [[] for _ in sims]
    for k in range(repeat):
        frame_inputs = _frame_inputs(inputs, k)
        for sim, out in zip(sims, samples, strict=True):
            t0 = now()
            sim.step(1.0 / FPS, frame_inputs)
            out.append(now() - t0)
    return [(1e3 * min(x), 1e3 * float(np.median(x))) for x in samples]


def _accuracy(fast, ref, inputs, frames: int = 30) -> tuple[str, float]:
    """(largest drop distance µm or "diverged", relative difference of the water on the glass) after
    ``frames`` frames of both from the same state."""
    for k in range(frames):
        fast.step(1.0 / FPS, _frame_inputs(inputs, k))
        ref.step(1.0 / FPS, _frame_inputs(inputs, k))
    water = abs(fast.mass_on_glass() - ref.mass_on_glass()) / max(ref.mass_on_glass(), 1e-30)
    if fast.count != ref.count:
        return "diverged", water
    return f"{1e6 * float(np.abs(fast.pos - ref.pos).max(initial=0.0)):.2g}", water


ROWS_PER_COUNT = 5  # parked, 60, 120, 120 drifting (heavy rain), parked in light rain


def cpu_cost(counts, repeat: int, clock: str = "thread") -> list[tuple]:
    """Rows (drops, speed km/h, rain mm/h, fast min ms, fast median ms, reference min ms, reference median ms,
    speed-up of the minima, max drop distance µm, water difference). The "120~" row drives at 120 km/h ± 2 %,
    the speed changing every frame (as the scene's autopilot holds it: ~0.1–0.3 % a frame)."""
    from rain_core.effects.windshield import GlassInputs, WindshieldSim
    from rain_core.effects.windshield.reference import WindshieldSimReference

    rows = []
    for n in counts:
        for speed, rate in ((0.0, RATE_MM_H), (60.0, RATE_MM_H), (120.0, RATE_MM_H), ("120~", RATE_MM_H),
                            (0.0, LIGHT_MM_H)):
            ref = WindshieldSimReference(seed=1)
            _fill(ref, GlassInputs.for_speed(60.0, 16.0, drop_budget=n), int(0.97 * n))
            if speed == "120~":
                inputs = [GlassInputs.for_speed(120.0 * (1.0 + 0.02 * math.sin(k / 8.0)), rate, drop_budget=n,
                                                wiper_mode="low") for k in range(100)]
            else:
                inputs = GlassInputs.for_speed(speed, rate, drop_budget=n, wiper_mode="low")
            for k in range(5):
                ref.step(1.0 / FPS, _frame_inputs(inputs, k))
            fast = WindshieldSim(seed=1)
            fast.load_state(ref)
            f, r = _time_steps([copy.deepcopy(fast), copy.deepcopy(ref)], inputs, repeat, clock)
            dist, water = _accuracy(fast, ref, inputs)
            label = speed if isinstance(speed, str) else int(speed)
            rows.append((ref.count, label, rate, f[0], f[1], r[0], r[1], r[0] / max(f[0], 1e-9), dist, water))
    return rows


# The frame benchmark's glass (``bench frame``, 100 km/h, heavy rain): full (the default budget of 6,000 drops,
# ~5,800 on the glass), the wipers on auto and sweeping, a light crosswind, the autopilot's speed drifting.
FRAME_KMH = 100.0
FRAME_BUDGET = 6000
FRAME_WIND_M_S = (1.7, 0.0, 0.04)


def frame_case_inputs(frames: int = 100) -> list:
    """One GlassInputs a frame of the frame benchmark's glass (auto wipers), the speed drifting ±1 %."""
    from rain_core.effects.windshield import GlassInputs

    return [GlassInputs(rate_mm_h=RATE_MM_H, car_velocity_m_s=np.array(
        [0.0, 0.0, -FRAME_KMH / 3.6 * (1.0 + 0.01 * math.sin(k / 8.0))]), wind_m_s=np.array(FRAME_WIND_M_S),
        drop_budget=FRAME_BUDGET, wiper_mode="auto") for k in range(frames)]


def frame_case_glass(seed: int = 1):
    """A WindshieldSim filled to ~97 % of the budget at 100 km/h (wipers off), then 10 frames of the case."""
    from rain_core.effects.windshield import GlassInputs, WindshieldSim

    sim = WindshieldSim(seed=seed)
    fill = GlassInputs(rate_mm_h=2.0 * RATE_MM_H, car_velocity_m_s=np.array([0.0, 0.0, -FRAME_KMH / 3.6]),
                       wind_m_s=np.array(FRAME_WIND_M_S), drop_budget=FRAME_BUDGET)
    _fill(sim, fill, int(0.97 * FRAME_BUDGET))
    for inputs in frame_case_inputs(10):
        sim.step(1.0 / FPS, inputs)
    return sim


def state_digest(sim) -> str:
    """A short hash of a simulation's drops, film and beads (the same bits give the same hash: before/after
    checks that a change left the results alone)."""
    import hashlib

    h = hashlib.sha1(np.ascontiguousarray(sim.pos).tobytes())
    for arr in (sim.vel, sim.mass, sim.trail, sim.fresh, sim.film, sim.beads):
        h.update(np.ascontiguousarray(arr).tobytes())
    h.update(repr((sim.count, sim.arrived, sim.wiped, sim.shed, sim.evaporated, sim.wipers.phase)).encode())
    return h.hexdigest()[:10]


def frame_case(repeat: int, clock: str = "thread") -> tuple:
    """(drops at the start, mean drops, min ms, median ms of ``repeat`` frames, state digest after them) of the
    frame benchmark's glass (``frame_case_glass``)."""
    sim = frame_case_glass()
    inputs = frame_case_inputs()
    n0 = sim.count
    now = CLOCKS[clock]
    times, counts = [], []
    for k in range(repeat):
        frame_inputs = _frame_inputs(inputs, k)
        t0 = now()
        sim.step(1.0 / FPS, frame_inputs)
        times.append(now() - t0)
        counts.append(sim.count)
    return n0, round(float(np.mean(counts))), 1e3 * min(times), 1e3 * float(np.median(times)), state_digest(sim)


def frame_case_kernels(repeat: int, clock: str = "thread") -> tuple[list[tuple], float, float, float, float]:
    """Where a step of the frame case goes: each compiled kernel of the windshield (``effects.windshield.kernels``,
    called through that package by the fast path) timed around its calls. Returns (rows of (kernel, calls a step,
    mean µs a step, share of the mean step %), largest first, then the rest of the step (Python and NumPy
    between the kernels); the mean step in µs; drops that slid a step (median); drops merged into others a step
    (mean); the share of the merge tests that searched by boxes, some drop's motion reaching past NEAR_CELL_M / 2,
    rather than by the near grid). Run apart from ``frame_case``: the wrappers cost ~1 µs a call. No rows with
    the kernels off."""
    from rain_core import jit
    from rain_core.effects.windshield import kernels
    from rain_core.effects.windshield.grid import NEAR_CELL_M

    names = [name for name in dir(kernels) if hasattr(getattr(kernels, name), "py_func")]  # Numba dispatchers
    now = CLOCKS[clock]
    spent = dict.fromkeys(names, 0.0)
    calls = dict.fromkeys(names, 0)
    slid, boxed = [], []
    originals = {name: getattr(kernels, name) for name in names}

    def timed(name, fn):
        def call(*args):
            t0 = now()
            result = fn(*args)
            spent[name] += now() - t0
            calls[name] += 1
            if name == "move_drops":  # returns how many drops slid
                slid.append(result)
            elif name == "merge_drops":  # its pair search: the near grid only if every reach is ≤ NEAR_CELL_M / 2
                n, mid = args[1], args[-1]  # (mid: the kernel's midpoints and reaches, its own test's operands)
                boxed.append(n >= 2 and not (mid[2, :n] <= 0.5 * NEAR_CELL_M).all())
            return result
        return call

    sim = frame_case_glass()
    inputs = frame_case_inputs()
    merges0 = sim.merges
    for name in names:
        setattr(kernels, name, timed(name, originals[name]))
    try:
        t0 = now()
        for k in range(repeat):
            sim.step(1.0 / FPS, _frame_inputs(inputs, k))
        step_us = (now() - t0) / repeat * 1e6
    finally:
        for name, fn in originals.items():
            setattr(kernels, name, fn)
    rows = [(name, round(calls[name] / repeat, 2), spent[name] / repeat * 1e6) for name in names if calls[name]]
    rows.sort(key=lambda row: -row[2])
    rest = step_us - sum(row[2] for row in rows)
    table = [(name, per_step, round(us, 1), round(100.0 * us / step_us, 1)) for name, per_step, us in rows]
    if jit.active():
        table.append(("(Python and NumPy between them)", "-", round(rest, 1), round(100.0 * rest / step_us, 1)))
    boxed_share = sum(boxed) / len(boxed) if boxed else 0.0
    return table, step_us, float(np.median(slid)) if slid else 0.0, (sim.merges - merges0) / repeat, boxed_share


def _frame_case_md(repeat: int, clock: str) -> list[str]:
    from rain_core import jit

    md = [
        f"Frame-benchmark glass ({FRAME_KMH:g} km/h ±1 %, {RATE_MM_H:g} mm/h, budget {FRAME_BUDGET}, wipers auto, "
        f"crosswind; {jit.describe()}): one step (1/30 s), ms ({clock} clock) over {repeat} frames.",
        "",
        markdown_table(("drops at start", "mean drops", "min ms", "median ms", "state digest"),
                       [frame_case(repeat, clock)]),
    ]
    if not jit.active():
        return md
    table, step_us, slid, merged, boxed = frame_case_kernels(repeat, clock)
    return md + [
        "",
        f"Where a step goes ({repeat} more frames, each compiled kernel timed around its calls; mean step "
        f"{step_us:.0f} µs with the timers): {slid:.0f} drops slid a step (median), {merged:.1f} merged into "
        f"others; the merge test searched by boxes (a drop reached past half a near cell) in {100 * boxed:.0f} % "
        "of the steps, by the near grid in the rest. Most kernels pass over every drop on the glass, resting or "
        "not.",
        "",
        markdown_table(("kernel", "calls a step", "µs a step (mean)", "share of the step %"), table),
    ]


def _frame_passes(scene) -> float:
    """GPU (or wall) ms of the windshield's draw passes in the last frame."""
    total = 0.0
    for name, ran, cpu_ms, gpu_ms, *_ in scene.renderer.pass_table():
        if ran and name in ("windshield.prepare", "windshield.overlay"):
            total += gpu_ms if gpu_ms is not None else cpu_ms
    return total


def _render_state(ctx, base_sim, settings, resolution: int, size, frames: int, traffic: bool = False):
    """Render ``frames`` frames from a copy of ``base_sim`` at a water-texture resolution; returns (median ms
    of the windshield passes, last image as float sRGB, the water thickness texture averaged to 64² cells), and
    with ``traffic`` also (bytes uploaded, splat draws) of the last frame."""
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
    upload = (effect.upload_bytes, effect.splat_draws)
    scene.release()
    ms = float(np.median(times[1:] if len(times) > 1 else times))
    return (ms, image, cells, upload) if traffic else (ms, image, cells)


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
    """(drops, ms of the windshield passes, bytes uploaded and splat draws in the last frame) at the default 512²
    water texture."""
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
        ms, _, _, (uploaded, draws) = _render_state(ctx, base, settings, 512, size, frames, traffic=True)
        rows.append((base.count, ms, uploaded, draws))
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
        (20, "CPU ms/frame vs drops, fast path (log-log)"),
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
    p.add_argument("--cpu-only", action="store_true", help="the CPU table alone (no GL context)")
    p.add_argument("--clock", choices=tuple(CLOCKS), default="thread",
                   help="thread: the main thread's CPU time (default; robust on a shared machine); wall: wall time")
    p.add_argument("--frame-case", action="store_true",
                   help="the frame benchmark's glass alone (~5,800 drops, 100 km/h, wipers auto): the sim timed alone")
    add_jit_argument(p)
    args = p.parse_args(argv)
    apply_jit_argument(p, args)
    from rain_core import jit
    quick = args.quick
    if args.frame_case:
        text = "\n".join(["# Windshield benchmark", "", *_frame_case_md(30 if quick else 150, args.clock)])
        print(text)
        write_output(args.out, "windshield", text)
        return 0
    counts = (2000,) if quick else (500, 2000, 5000)
    cpu_rows = cpu_cost(counts, repeat=20 if quick else 60, clock=args.clock)
    md = [
        "# Windshield benchmark",
        "",
        f"CPU: one step (1/30 s) of the fast path ({jit.describe()}) and of the float64 reference from the same "
        f"glass, wipers low; ms ({args.clock} clock), min and median of the frames; accuracy after 30 more frames.",
        "",
        markdown_table(
            ("drops", "km/h", "mm/h", "fast min ms", "fast median ms", "reference min ms", "reference median ms",
             "speed-up (min)", "max drop distance µm", "water on glass, rel. diff."),
            cpu_rows,
        ),
        "",
        *_frame_case_md(30 if quick else 150, args.clock),
    ]
    if args.cpu_only:
        text = "\n".join(md)
        print(text)
        write_output(args.out, "windshield", text)
        return 0
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    size = (320, 180) if quick else (640, 360)
    resolutions = (128, 256, 512, 1024) if quick else (128, 256, 512, 1024, 2048)
    res_rows = gpu_resolution(ctx, resolutions, size, frames=3 if quick else 6)
    drop_rows = gpu_drops(ctx, (500, 5000) if quick else (500, 2000, 5000, 10000), size, frames=3)
    ran, skip_ms = skip_check(ctx, size)
    md += [
        "",
        f"GPU: the windshield passes against the water-texture resolution ({size[0]}×{size[1]} frame, "
        f"error against {max(resolutions)}²).",
        "",
        markdown_table(("resolution", "passes ms", "frame RMS (sRGB)", "thickness L1 (rel.)"), res_rows),
        "",
        "GPU: the windshield passes against the drop count (512²), and the bytes uploaded per frame (splat "
        "instances for the film and the drops, and the coarse film texture).",
        "",
        markdown_table(("drops", "passes ms", "uploaded bytes/frame", "draw calls/frame"), drop_rows),
        "",
        f"Dry glass, no rain, wipers auto: windshield passes run: {ran} ({skip_ms:.3f} ms).",
        "",
        "On llvmpipe the GPU column is the CPU emulating a GPU: compare ratios.",
    ]
    text = "\n".join(md)
    print(text)
    write_output(args.out, "windshield", text)
    from pathlib import Path

    # Fast-path minima per drop count at heavy rain: (drops, parked, 60 km/h, 120 km/h).
    plot_cpu = [(cpu_rows[k][0], *(r[3] for r in cpu_rows[k : k + 3]))
                for k in range(0, len(cpu_rows), ROWS_PER_COUNT)]
    _plot(Path(args.out) / "windshield.png", plot_cpu, res_rows, drop_rows)
    ctx.release()
    return 0 if not ran and math.isfinite(skip_ms) else 1
