"""Ripple solver: cost per step of each backend, accuracy and convergence, GPU vs reference, sleep, retiming.

``python -m rain_core.bench ripples [--quick] [--out DIR]`` prints the tables, writes DIR/ripples.md and a
log-log plot of run time against error, DIR/ripples.png (drawn with Pillow).

Accuracy runs use the product's field (L = 25 m, s = 0.35 m/s) with a single standing mode (p, q) = (6, 4)
started at rest and C² = 1/4, to a fixed time T (ωT = 2.5π): the error against (a) the exact discrete solution
cos(ω_d t)·sin·sin (cos ω_dΔt = 1 − 2C²[sin²(pπh/2L) + sin²(qπh/2L)]), which only roundoff separates from
the scheme, and (b) the continuous mode cos(ωt)·sin·sin, ω = sπ√(p² + q²)/L, which falls as h² at fixed C.
On Mesa's llvmpipe the "GPU" is the CPU emulating one: compare ratios there, quote GPU times from a real GPU.
"""

from __future__ import annotations

import math
import time

import numpy as np

from rain_core import jit
from rain_core.bench._common import add_jit_argument, apply_jit_argument, markdown_table, parser, write_output
from rain_core.effects.ripples.backend import choose_backend, make_field
from rain_core.effects.ripples.constants import CAPILLARY_SPEED_M_S, DEFAULT_DAMPING_PER_S
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.gpu import WaveSolverGPU
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.textures import RippleTextures

EXTENT_M = 25.0
MODE = (6, 4)
COURANT2 = 0.25
# End time at a zero of the continuous mode (ωT = 2.5π), where a phase error shows at first order in the
# phase (at an extremum, cos would hide it to second order).
T_END_S = 2.5 * math.pi / (CAPILLARY_SPEED_M_S * math.pi * math.hypot(*MODE) / EXTENT_M)
BACKEND_LABELS = {"reference": "NumPy float64 (reference)", "numpy32": "NumPy float32", "gpu": "GPU shader"}


def _mode(n: int, h: float) -> np.ndarray:
    length = (n - 1) * h
    x = np.arange(n) * h
    p, q = MODE
    return np.outer(np.sin(q * np.pi * x / length), np.sin(p * np.pi * x / length))


def _omegas(n: int, h: float, dt: float, speed: float) -> tuple[float, float]:
    """(ω_d discrete, ω continuous) of MODE in rad/s."""
    length = (n - 1) * h
    p, q = MODE
    c2 = (speed * dt / h) ** 2
    cos_w = 1.0 - 2.0 * c2 * (math.sin(p * math.pi * h / (2 * length)) ** 2
                              + math.sin(q * math.pi * h / (2 * length)) ** 2)
    return math.acos(cos_w) / dt, speed * math.pi * math.hypot(p, q) / length


def _make(backend: str, ctx, n: int, h: float, **kwargs):
    speed = CAPILLARY_SPEED_M_S
    if backend == "reference":
        return WaveSolver(n, h, speed, **kwargs)
    if backend == "numpy32":
        return WaveSolverF32(n, h, speed, **kwargs)
    return WaveSolverGPU(ctx, n, h, speed, **kwargs)


def _release(solver):
    if isinstance(solver, WaveSolverGPU):
        solver.release()


def _sync(solver):
    if isinstance(solver, WaveSolverGPU):
        solver.ctx.finish()


def time_per_step(backend: str, ctx, n: int, reps: int) -> tuple[float, float | None]:
    """(wall ms per step including a finish on the GPU, GPU timer-query ms or None)."""
    h = EXTENT_M / (n - 1)
    solver = _make(backend, ctx, n, h, sleep_energy=0.0)
    solver.reset(_mode(n, h))
    dt = solver.dt_max
    solver.step(dt)
    _sync(solver)
    samples = []
    for _ in range(reps):  # the median of single steps: other processes share the CPU
        t0 = time.perf_counter()
        solver.step(dt)
        _sync(solver)
        samples.append((time.perf_counter() - t0) * 1e3)
    wall = float(np.median(samples))
    gpu_ms = None
    if isinstance(solver, WaveSolverGPU):
        from rain_core.gl import PassTimer

        timer = PassTimer(ctx)
        if timer.gpu_source == "timer query":
            samples = sorted(timer.measure(lambda s=solver, d=dt: s.step(d))[1] for _ in range(max(3, reps // 2)))
            gpu_ms = samples[len(samples) // 2]
    _release(solver)
    return wall, gpu_ms


def accuracy(backend: str, ctx, n: int) -> dict:
    """Errors of MODE at T_END_S (max abs, amplitude 1) and the wall time of the run."""
    h = EXTENT_M / (n - 1)
    solver = _make(backend, ctx, n, h, sleep_energy=0.0)
    dt = math.sqrt(COURANT2) * h / CAPILLARY_SPEED_M_S
    steps = round(T_END_S / dt)
    z0 = _mode(n, h)
    solver.reset(z0)
    _sync(solver)
    t0 = time.perf_counter()
    for _ in range(steps):
        solver.step(dt)
    _sync(solver)
    wall = time.perf_counter() - t0
    t = steps * dt
    w_d, w = _omegas(n, h, dt, CAPILLARY_SPEED_M_S)
    z = np.asarray(solver.height, dtype=np.float64)
    _release(solver)
    return {"steps": steps, "run_s": wall, "err_discrete": float(np.max(np.abs(z - z0 * math.cos(w_d * t)))),
            "err_continuous": float(np.max(np.abs(z - z0 * math.cos(w * t))))}


def gpu_vs_reference(ctx, n: int, steps: int) -> tuple[float, float]:
    """(max |GPU − reference| / max |reference|, same for float32 NumPy) after ``steps`` steps of a
    two-mode field with damping, at C² = 0.45."""
    h = EXTENT_M / (n - 1)
    x = np.arange(n) * h
    length = (n - 1) * h
    z0 = _mode(n, h) + 0.3 * np.outer(np.sin(5 * np.pi * x / length), np.sin(7 * np.pi * x / length))
    out = {}
    for backend in ("reference", "numpy32", "gpu"):
        if backend == "gpu" and ctx is None:
            continue
        solver = _make(backend, ctx, n, h, damping_per_s=DEFAULT_DAMPING_PER_S * 0.1, sleep_energy=0.0)
        solver.reset(z0)
        dt = math.sqrt(0.45) * h / CAPILLARY_SPEED_M_S
        for _ in range(steps):
            solver.step(dt)
        out[backend] = np.asarray(solver.height, dtype=np.float64)
        _release(solver)
    scale = np.max(np.abs(out["reference"]))
    gpu = float(np.max(np.abs(out["gpu"] - out["reference"])) / scale) if "gpu" in out else float("nan")
    return gpu, float(np.max(np.abs(out["numpy32"] - out["reference"])) / scale)


def sleep_and_retime_table(ctx, n: int, frames: int) -> str:
    """Per-frame cost of a RippleField: active, asleep; and of a jittery frame time with and without the
    reuse tolerance (exact retiming every frame vs keeping the sub-step)."""
    rows = []
    backends = ["numpy32"] + (["gpu"] if ctx is not None else [])
    for backend in backends:
        for label, tolerance, jitter, asleep in (("steady 60 Hz, active", 0.25, 0.0, False),
                                                 ("steady 60 Hz, asleep (no sources, settled)", 0.25, 0.0, True),
                                                 ("±5 % jitter, exact retime every frame", 0.0, 0.05, False),
                                                 ("±5 % jitter, reuse tolerance 0.25", 0.25, 0.05, False)):
            field = make_field(ctx, n=n, extent_m=EXTENT_M, backend=backend, reuse_tolerance=tolerance)
            textures = RippleTextures(ctx, field) if ctx is not None else None
            field.recenter(0.0, 0.0)
            field.solver.sleep_energy = 1e300 if asleep else 0.0
            field.solver.add_impulse(12.0, 12.0, 1.0, 1e-3)
            rng = np.random.default_rng(0)
            for _ in range(30):  # warm up (and, for the asleep row, let it fall asleep: checks every 8 frames)
                field.update(1 / 60)
                _ = textures.normal_texture if textures is not None else None
            retimes0 = field.solver.retimes
            samples = []
            for _ in range(frames):
                t0 = time.perf_counter()
                field.update((1 / 60) * (1 + jitter * rng.uniform(-1, 1)))
                if textures is not None:
                    _ = textures.normal_texture
                    ctx.finish()
                samples.append((time.perf_counter() - t0) * 1e3)
            ms = float(np.median(samples))
            rows.append((BACKEND_LABELS[backend], label, f"{ms:.3f}", field.solver.retimes - retimes0,
                         "yes" if field.asleep else "no"))
            if textures is not None:
                textures.release()
            field.release()
    return markdown_table(["backend", f"frame ({n}², update + normals)", "median ms / frame", "retimes",
                           "asleep"], rows)


def mask_upkeep_table(n: int, frames: int) -> str:
    """ms per frame that ``RippleField.update`` spends following the road's film depth (no rain, no wheels:
    the solver sleeps), with the default road at full flood, parked and at 100 km/h, for a film function
    with and without a ``cache_key``: with one, unchanged levels ask only the strips that scroll in; without,
    a band of rows is re-asked every frame. Min over frames of the thread's CPU time, after one warm-up frame."""
    from rain_core.water_film import film_depth_mm

    def film(keyed: bool):
        def fn(x_m, z_m):
            return film_depth_mm(x_m, z_m, 1.0, 1.0)
        if keyed:
            fn.cache_key = ("bench film", 1.0, 1.0)
        return fn

    rows = []
    dt = 1 / 30
    for speed_kmh in (0.0, 100.0):
        for keyed in (False, True):
            field = RippleField(n=n, extent_m=EXTENT_M, backend="numpy32")
            z = 0.0
            field.update(dt, center_xz=(0.0, z), film_depth_fn=film(keyed))
            best = math.inf
            for _ in range(frames):
                z += speed_kmh / 3.6 * dt
                fn = film(keyed)  # a new function object every frame, as the road publishes it
                t0 = time.thread_time()  # this thread's CPU time: the machine may be shared
                field.update(dt, center_xz=(0.0, z), film_depth_fn=fn)
                best = min(best, time.thread_time() - t0)
            rows.append((n, f"{speed_kmh:g}", "yes" if keyed else "no", f"{best * 1e3:.2f}"))
            field.release()
    return markdown_table(["N", "km/h", "film function has cache_key", "ms per frame (min)"], rows)


def sources_table(n: int, frames: int, ctx=None) -> str:
    """CPU ms per frame of gathering the sources: the raindrops at 8 and 50 mm/h over the road's standing water
    at full flood (the candidates are capped so that about ``max_drops_per_frame`` land on water), and 16
    wheels' wakes with their film depths asked. The NumPy backends make the drops with the twin of the shader's
    hash (``raindrops.py``) and gather them; the GPU backend (with a context) sends a few uniforms (the CPU
    column) and draws them: the draw call's own thread time is a column apart (on llvmpipe it includes the
    emulated vertex shading, which runs on the calling thread; ``ctx.finish`` excluded). Min over frames of the
    thread's CPU time."""
    from rain_core.effects.ripples.wheels import WheelBatch
    from rain_core.water_film import film_depth_mm

    def film(x_m, z_m):
        return film_depth_mm(x_m, z_m, 1.0, 1.0)

    film.cache_key = ("bench film", 1.0, 1.0)
    fields = {"numpy32": RippleField(n=n, extent_m=EXTENT_M, backend="numpy32")}
    if ctx is not None:
        fields["gpu"] = make_field(ctx, n=n, extent_m=EXTENT_M, backend="gpu")
    for field in fields.values():
        field.update(1 / 30, center_xz=(1.75, 0.0), film_depth_fn=film)
    rng = np.random.default_rng(0)
    p0 = np.column_stack([rng.uniform(-6.0, 9.0, 16), rng.uniform(-10.0, 10.0, 16)])
    wheels = WheelBatch(p0, p0 + [0.0, 0.9], np.full(16, 27.0), np.full(16, 0.2))

    def timed(field, fn) -> tuple[float, float]:
        best, best_draw = math.inf, math.inf
        for _ in range(frames + 1):
            field._batch = []  # gathered as in update, not deposited: the solver's share is measured above
            t0 = time.thread_time()
            fn()
            t1 = time.thread_time()
            if isinstance(field.solver, WaveSolverGPU):
                field.solver._flush()  # the GPU's raindrops: uniforms and one draw
            best, best_draw = min(best, t1 - t0), min(best_draw, time.thread_time() - t1)
            field._batch = None
            if ctx is not None:
                ctx.finish()
        return best * 1e3, best_draw * 1e3

    rows = []
    for backend, field in fields.items():
        upload = "0 (uniforms only)" if backend == "gpu" else "-"
        for rate in (8.0, 50.0):
            drawn = []
            ms, draw_ms = timed(field, lambda f=field, r=rate, out=drawn: out.append(f._raindrops(r, 1 / 30)))
            rows.append((n, backend, f"raindrops at {rate:g} mm/h ({min(drawn)}–{max(drawn)} on water)",
                         f"{ms:.3f}", f"{draw_ms:.3f}" if backend == "gpu" else "-", upload))
    field = fields["numpy32"]
    rows.append((n, "any", "16 wheels' wakes (film depths asked)",
                 f"{timed(field, lambda: field._wakes(wheels.rows(film)))[0]:.3f}", "-", "-"))
    for field in fields.values():
        field.release()
    return markdown_table(["N", "backend", "source", "CPU ms per frame (min)", "draw call ms (thread)",
                           "raindrop bytes uploaded"], rows)


def _plot(path, series: dict[str, list[tuple[int, float, float]]], ref_slope_points) -> bool:
    """Log-log plot: run time to T (ms) against error vs the continuous mode, one line per backend."""
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        print("Pillow is missing: no plot")
        return False
    width, height = 900, 600
    left, right, top, bottom = 90, 230, 40, 70
    img = Image.new("RGB", (width, height), "white")
    draw = ImageDraw.Draw(img)
    points = [(t, e) for pts in series.values() for _, t, e in pts if t > 0 and e > 0]
    xs = [math.log10(t) for t, _ in points]
    ys = [math.log10(e) for _, e in points]
    x_lo, x_hi = math.floor(min(xs)), math.ceil(max(xs))
    y_lo, y_hi = math.floor(min(ys)), math.ceil(max(ys))

    def px(t, e):
        u = (math.log10(t) - x_lo) / (x_hi - x_lo)
        v = (math.log10(e) - y_lo) / (y_hi - y_lo)
        return left + u * (width - left - right), height - bottom - v * (height - top - bottom)

    draw.rectangle([left, top, width - right, height - bottom], outline="black")
    for d in range(x_lo, x_hi + 1):
        x, _ = px(10.0 ** d, 10.0 ** y_lo)
        draw.line([x, top, x, height - bottom], fill=(225, 225, 225))
        draw.text((x - 12, height - bottom + 6), f"1e{d}", fill="black")
    for d in range(y_lo, y_hi + 1):
        _, y = px(10.0 ** x_lo, 10.0 ** d)
        draw.line([left, y, width - right, y], fill=(225, 225, 225))
        draw.text((left - 40, y - 6), f"1e{d}", fill="black")
    draw.text((left + 150, height - 35), f"run time to T = {T_END_S:.3g} s of simulated time (ms)", fill="black")
    draw.text((8, top - 28), "max error vs continuous mode (amplitude 1)", fill="black")
    colors = {"reference": (30, 90, 200), "numpy32": (220, 120, 20), "gpu": (30, 160, 60)}
    for i, (name, pts) in enumerate(series.items()):
        pts = [(n, t, e) for n, t, e in pts if t > 0 and e > 0]
        col = colors.get(name, (0, 0, 0))
        coords = [px(t, e) for _, t, e in pts]
        if len(coords) > 1:
            draw.line(coords, fill=col, width=2)
        for (n, _, _), (x, y) in zip(pts, coords, strict=True):
            draw.ellipse([x - 4, y - 4, x + 4, y + 4], fill=col)
            if name == "reference":
                draw.text((x + 6, y - 14), f"N={n}", fill=col)
        ly = top + 10 + 20 * i
        draw.line([width - right + 15, ly + 6, width - right + 40, ly + 6], fill=col, width=3)
        draw.text((width - right + 45, ly), BACKEND_LABELS.get(name, name), fill="black")
    if ref_slope_points:  # a slope guide: error ∝ h², run time ∝ N³ → error ∝ time^(−2/3)
        (t0, e0) = ref_slope_points
        t1 = 10.0 ** x_hi
        e1 = e0 * (t1 / t0) ** (-2 / 3)
        if e1 < 10.0 ** y_lo:  # stop at the frame
            t1 = t0 * (10.0 ** y_lo / e0) ** (-1.5)
            e1 = 10.0 ** y_lo
        draw.line([px(t0, e0), px(t1, e1)], fill=(150, 150, 150), width=1)
        draw.text((width - right + 15, top + 90), "grey: error ~ time^(-2/3)", fill=(110, 110, 110))
        draw.text((width - right + 15, top + 106), "(2nd order, N^3 work)", fill=(110, 110, 110))
    img.save(path)
    return True


def main(argv: list[str] | None = None) -> int:
    p = parser("ripples", __doc__.splitlines()[0])
    add_jit_argument(p)
    args = p.parse_args(argv)
    apply_jit_argument(p, args)
    sizes = [64, 128, 256] if args.quick else [64, 128, 256, 512, 1024]
    try:
        from rain_core.gl import create_headless_context

        ctx = create_headless_context()
        renderer = ctx.info.get("GL_RENDERER", "?")
    except Exception as exc:  # no GL: the CPU paths still run
        ctx, renderer = None, f"none ({exc})"
    backends = ["reference", "numpy32"] + (["gpu"] if ctx is not None else [])
    print(f"GL renderer: {renderer}; CPU paths: {jit.describe()}")

    cost_rows = []
    for n in sizes:
        reps = max(3, min(50, int(2e6 / n ** 2))) if not args.quick else 3
        row = [n]
        for backend in backends:
            wall, gpu_ms = time_per_step(backend, ctx, n, reps)
            row.append(f"{wall:.3f}")
            if backend == "gpu":
                row.append("-" if gpu_ms is None else f"{gpu_ms:.3f}")
        cost_rows.append(row)
    headers = ["N"] + [f"{BACKEND_LABELS[b]} ms/step" for b in backends]
    if ctx is not None:
        headers.append("GPU timer query ms/step")
    cost = markdown_table(headers, cost_rows)
    print(cost)

    series: dict[str, list[tuple[int, float, float]]] = {b: [] for b in backends}
    acc_rows = []
    prev = {}
    for n in sizes:
        for backend in backends:
            res = accuracy(backend, ctx, n)
            order = ""
            if backend in prev:
                order = f"{math.log2(prev[backend] / res['err_continuous']) / math.log2((n - 1) / (n // 2 - 1)):.2f}"
            prev[backend] = res["err_continuous"]
            series[backend].append((n, res["run_s"] * 1e3, res["err_continuous"]))
            acc_rows.append((n, BACKEND_LABELS[backend], res["steps"], f"{res['run_s'] * 1e3:.1f}",
                             f"{res['err_discrete']:.2e}", f"{res['err_continuous']:.3e}", order))
    acc = markdown_table(["N", "backend", "steps to T", "run time (ms)", "error vs exact discrete",
                          "error vs continuous", "order vs continuous"], acc_rows)
    print(acc)

    gpu_rows = []
    steps = 200 if args.quick else 1000
    for n in sizes:
        g, f32 = gpu_vs_reference(ctx, n, steps)
        gpu_rows.append((n, steps, f"{g:.2e}", f"{f32:.2e}"))
    gpu_tab = markdown_table(["N", "steps", "GPU vs reference (max rel.)", "float32 NumPy vs reference"], gpu_rows)
    print(gpu_tab)

    choice_n = 128 if args.quick else 512
    choice, timings = choose_backend(ctx, choice_n, cell_m=EXTENT_M / (choice_n - 1))
    choice_tab = markdown_table(["N", "numpy32 ms/step (incl. upload)", "gpu ms/step (incl. finish)", "chosen"],
                                [(choice_n, f"{timings.get('numpy32_ms', float('nan')):.3f}",
                                  f"{timings.get('gpu_ms', float('nan')):.3f}", choice)])
    print(choice_tab)
    sleep_tab = sleep_and_retime_table(ctx, 128 if args.quick else 512, 20 if args.quick else 60)
    print(sleep_tab)
    upkeep_tab = mask_upkeep_table(512, 10 if args.quick else 30)
    print(upkeep_tab)
    sources_tab = sources_table(512, 10 if args.quick else 30, ctx)
    print(sources_tab)

    plot_path = None
    ref = series["reference"]
    guide = (ref[0][1], ref[0][2] * 2) if ref else None
    import pathlib

    out_dir = pathlib.Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    if _plot(out_dir / "ripples.png", series, guide):
        plot_path = out_dir / "ripples.png"
    md = "\n\n".join([
        "# Ripples: wave solver cost and accuracy",
        f"GL renderer: {renderer}. CPU paths: {jit.describe()}. "
        f"Field L = {EXTENT_M:g} m, s = {CAPILLARY_SPEED_M_S} m/s. "
        "On llvmpipe the GPU column is the CPU emulating a GPU.",
        "## Cost per step (one sub-step, N×N cells)", cost,
        f"## Accuracy: mode {MODE} from rest, C² = {COURANT2}, to T = {T_END_S:.4g} s", acc,
        f"## GPU and float32 vs the float64 reference after {steps} steps (C² = 0.45, light damping)", gpu_tab,
        "## Backend choice at start-up (choose_backend)", choice_tab,
        "## Sleep and retiming, per frame of RippleField.update (+ normals when there is a context)", sleep_tab,
        "## Water-mask upkeep: following the road's film depth, per frame of RippleField.update", upkeep_tab,
        "## Sources: a frame's raindrops (twin on NumPy, uniforms on the GPU) and wakes (CPU ms)", sources_tab,
        f"Plot: {plot_path.name if plot_path else 'none'}",
    ])
    path = write_output(args.out, "ripples", md)
    print(f"wrote {path}" + (f" and {plot_path}" if plot_path else ""))
    return 0
