"""Rainfall cost and accuracy: the CPU time per frame of the rainfall (update + the Python side of its render)
against the particle budget (10k → 1M), parked and at 100 km/h; the streak pass against the budget; the error
of the drawn drop density against the physical one in the view, for each budget and rate (from the float64
twin of the shaders), and the light the compensation could not place.

``python -m rain_core.bench rainfall [--quick] [--cpu-only] [--out DIR]`` prints the tables and writes
DIR/rainfall.md and a plot DIR/rainfall.png (drawn with Pillow). GPU times on llvmpipe are the CPU emulating a
GPU: compare ratios. The CPU table uses only the effect's public API, so it also runs on older code:
``cd OLD_CHECKOUT && python -c "import runpy, sys; sys.argv = ['x', '--cpu-only']; runpy.run_path(
'/path/to/this/rainfall.py', run_name='__main__')"``.
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from rain_core import layout, physics
from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.camera import Camera
from rain_core.effects.rainfall import RainfallSim, RainInput, StreakCamera, full_region, streak_geometry

RATES = (0.5, 2.0, 8.0, 28.0, 80.0)
DEPTH_BINS_M = (0.5, 3.0, 8.0, 16.0, 40.0)  # m, distance bins of the view volume
EYE = np.array([layout.LANE_CENTRES_X[0] - 0.37, 1.2, 600.0])
FORWARD = np.array([0.0, -0.07, -1.0]) / np.hypot(0.07, 1.0)
FOV_DEG, ASPECT = 60.0, 16.0 / 9.0
WARMUP_FRAMES = 5  # frames before the CPU table measures (the first fills the container in older code)


def _camera() -> Camera:
    return Camera(position=EYE.copy(), forward=FORWARD.copy(), fov_y_deg=FOV_DEG)


def _view_bins(lo, hi, rng: np.random.Generator, n: int = 400_000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Monte Carlo volumes (m³) of the depth bins of the view frustum inside the box [lo, hi], each sampled in
    the bounding box of its own part of the frustum (so even the small near bin gets n points); also returns
    the (right, up, forward) basis used to classify points."""
    cam = _camera()
    r, u, f = cam.basis()
    tan_v = math.tan(math.radians(FOV_DEG) / 2.0)
    # Directions along the frustum's edges (its far cap bulges past the corners): their AABB holds the region.
    s = np.linspace(-1.0, 1.0, 33)
    edge = [(a, b) for a in s for b in (-1.0, 1.0)] + [(b, a) for a in s for b in (-1.0, 1.0)]
    corners = np.array([f + sx * tan_v * ASPECT * r + sy * tan_v * u for sx, sy in edge])
    corners /= np.linalg.norm(corners, axis=1)[:, None]
    vol = np.zeros(len(DEPTH_BINS_M) - 1)
    for k, far in enumerate(DEPTH_BINS_M[1:]):
        pts = np.vstack([EYE, EYE + far * corners, EYE + far * f])
        b_lo, b_hi = np.maximum(pts.min(axis=0), lo), np.minimum(pts.max(axis=0), hi)
        if np.any(b_hi <= b_lo):
            continue
        p = b_lo + rng.random((n, 3)) * (b_hi - b_lo)
        vol[k] = np.count_nonzero(_classify(p, r, u, f) == k) * float(np.prod(b_hi - b_lo)) / n
    return vol, np.stack([r, u, f]), None


def _classify(p, r, u, f) -> np.ndarray:
    """Depth bin of each point in the view frustum, −1 outside."""
    d = p - EYE
    z = d @ f
    tan_v = math.tan(math.radians(FOV_DEG) / 2.0)
    inside = (z > DEPTH_BINS_M[0]) & (np.abs(d @ u) < z * tan_v) & (np.abs(d @ r) < z * tan_v * ASPECT)
    dist = np.linalg.norm(d, axis=1)
    k = np.searchsorted(DEPTH_BINS_M, dist, side="right") - 1
    return np.where(inside & (k >= 0) & (k < len(DEPTH_BINS_M) - 1), k, -1)


def density_errors(budget: int, rate: float, frames: int, seed: int = 1) -> dict:
    """Drawn (weighted) drops per m³ in the view's depth bins against N(R), over a few frames 0.5 s apart, a
    parked camera in open air, from the float64 twin of the shaders. Also the share of the streaks' light that
    the width/opacity caps drop."""
    sim = RainfallSim(budget, seed=seed)
    inp = dict(camera_position=EYE, camera_forward=FORWARD, camera_velocity=np.zeros(3), rate_mm_h=rate,
               splashes=False)
    t0 = time.perf_counter()
    sim.advance(RainInput(time_s=0.0, **inp))
    fill_s = time.perf_counter() - t0
    lo, hi = full_region(sim.boxes, -1)
    vol, basis, _ = _view_bins(lo, hi, np.random.default_rng(0))
    n_phys = physics.number_density_per_m3(rate)
    cam = _camera()
    view_proj = cam.projection_matrix(ASPECT) @ cam.view_matrix()
    sc = StreakCamera(view_proj, EYE, 0.0, np.zeros(3), 1.0 / 60.0, (1280, 720))
    ratios, lost, drawn_count = [], [], []
    t = 0.0
    for _ in range(frames):
        t += 0.5
        sim.advance(RainInput(time_s=t, **inp))
        d = sim.drops()
        p, w = d["pos"], np.where(d["visible"], d["weight"], 0.0)
        inside = (w > 0) & np.all((p >= lo) & (p <= hi), axis=1)
        k = _classify(p[inside], *basis)
        w = w[inside]
        per_bin = np.array([w[k == b].sum() for b in range(len(vol))]) / vol
        ratios.append(per_bin / n_phys)
        drawn_count.append(int(np.count_nonzero(k >= 0)))
        g = streak_geometry(sim, d["index"][inside][k >= 0], t, sc)
        v = g["visible"]
        lost.append(1.0 - g["drawn_px2"][v].sum() / max(g["light_px2"][v].sum(), 1e-12))
    ratios = np.array(ratios)
    total = (ratios * vol).sum(axis=1) / vol.sum()
    return {
        "budget": budget, "rate": rate, "fill_s": fill_s, "in_view": int(np.mean(drawn_count)),
        "bin_rms": float(np.sqrt(np.mean((ratios - 1.0) ** 2))), "total_err": float(np.mean(np.abs(total - 1.0))),
        "bias": float(np.mean(total) - 1.0), "light_lost": float(np.mean(lost)), "per_bin": ratios.mean(axis=0),
    }


def _drawn(effect) -> int:
    upd = getattr(effect, "last_update", None)
    if hasattr(upd, "drawn_expected"):
        return int(upd.drawn_expected)
    return int(getattr(effect.sim, "live", 0)) if effect.sim is not None else 0


def gpu_costs(budgets, size, frames: int) -> list[dict]:
    """Frame time of the streak pass (wall time to ctx.finish) against the budget, heavy rain, driver view."""
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.gl import create_headless_context
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    ctx = create_headless_context()
    rows = []
    for budget in (0, *budgets):
        s = Settings()
        s.rain.rate_mm_h = 8.0 if budget else 0.0
        s.quality.particle_budget = max(budget, 1)
        effect = RainfallEffect(ctx, settings=s, seed=1)
        scene = Scene(ctx, size, s, seed=1, effects=[effect], gpu_timing=False)
        scene.step(1.0 / 60.0)
        scene.render()
        rain_ms, scene_ms = [], []
        for _ in range(frames):
            scene.step(1.0 / 60.0)
            frame = scene.frame()
            rc = scene.renderer.render_context(frame)
            ctx.finish()
            t0 = time.perf_counter()
            scene.renderer.render(frame)
            ctx.finish()
            scene_ms.append((time.perf_counter() - t0) * 1e3)
            if effect.active(frame):
                rc.hdr.fbo.use()
                ctx.finish()
                t0 = time.perf_counter()
                effect.render("transparent", rc)
                ctx.finish()
                rain_ms.append((time.perf_counter() - t0) * 1e3)
            else:
                rain_ms.append(0.0)
        ran = "rainfall.transparent" in {st.name for st in scene.renderer.stats}
        rows.append({"budget": budget, "drawn": _drawn(effect) if budget else 0, "ran": ran,
                     "rain_ms": statistics.median(rain_ms), "frame_ms": statistics.median(scene_ms)})
        scene.release()
    ctx.release()
    return rows


class _no_draws:
    """Within it, ``VertexArray.render`` and ``transform`` (the streak records' pass) do nothing: llvmpipe shades
    vertices inside the draw call, on the calling thread, so timing a pass with its draws would time the emulated
    GPU."""

    def __enter__(self):
        import moderngl

        self._orig = (moderngl.VertexArray.render, moderngl.VertexArray.transform)
        moderngl.VertexArray.render = moderngl.VertexArray.transform = lambda *args, **kwargs: None

    def __exit__(self, *exc):
        import moderngl

        moderngl.VertexArray.render, moderngl.VertexArray.transform = self._orig


def cpu_costs(budgets, frames: int, repeats: int) -> list[dict]:
    """CPU ms per frame of the rainfall alone in the street (heavy rain 8 mm/h, 2 m/s wind, 5 traffic cars,
    driver camera, 160×90): ``update`` (the simulation and its uploads, GL calls included) and ``render`` (the
    Python side of the pass: its draw calls made no-ops, since llvmpipe shades vertices inside them; the GPU is
    idle before). Each row is the minimum over ``repeats`` runs of the median over ``frames`` frames after a
    warm-up."""
    from rain_core.effects.rainfall import RainfallEffect
    from rain_core.gl import create_headless_context
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    ctx = create_headless_context()
    rows = []
    for budget in budgets:
        for label, speed in (("parked", 0.0), ("100 km/h", 100.0 / 3.6)):
            best = None
            for _ in range(repeats):
                s = Settings()
                s.rain.rate_mm_h = 8.0
                s.wind.speed_m_s = 2.0
                s.traffic.count = 5
                s.camera.mode = "driver"
                s.quality.particle_budget = budget
                effect = RainfallEffect(ctx, settings=s, seed=1)
                scene = Scene(ctx, (160, 90), s, seed=1, effects=[effect], gpu_timing=False)
                upd_ms, ren_ms = [], []
                for i in range(frames + WARMUP_FRAMES):
                    scene.ego.speed_m_s = speed
                    scene.step(1.0 / 60.0)
                    frame = scene.frame()
                    rc = scene.renderer.render_context(frame)
                    rc.hdr.fbo.use()
                    ctx.finish()
                    t0 = time.perf_counter()
                    effect.update(frame, rc)
                    t1 = time.perf_counter()
                    with _no_draws():
                        effect.render("transparent", rc)
                    t2 = time.perf_counter()
                    ctx.finish()
                    if i >= WARMUP_FRAMES:
                        upd_ms.append((t1 - t0) * 1e3)
                        ren_ms.append((t2 - t1) * 1e3)
                row = {"budget": budget, "case": label, "update_ms": statistics.median(upd_ms),
                       "render_ms": statistics.median(ren_ms), "drawn": _drawn(effect)}
                row["total_ms"] = row["update_ms"] + row["render_ms"]
                if best is None or row["total_ms"] < best["total_ms"]:
                    best = row
                scene.release()
            rows.append(best)
    ctx.release()
    return rows


def _cpu_table(cpu) -> str:
    rows = [(c["budget"], c["case"], c["drawn"], f"{c['update_ms']:.2f}", f"{c['render_ms']:.2f}",
             f"{c['total_ms']:.2f}") for c in cpu]
    return markdown_table(["budget", "camera", "streaks drawn", "update ms", "render (Python) ms", "total ms"], rows)


def _plot(path, gpu: list[dict], dens: list[dict]) -> None:
    from PIL import Image, ImageDraw

    w, h, pad = 1000, 460, 60
    img = Image.new("RGB", (w, h), "white")
    draw = ImageDraw.Draw(img)

    def axes(x0, x1, title, xr, yr):
        left, right, top, bottom = x0 + pad, x1 - 20, 40, h - pad

        def to_px(x, y):
            fx = (math.log10(x) - math.log10(xr[0])) / (math.log10(xr[1]) - math.log10(xr[0]))
            fy = (math.log10(y) - math.log10(yr[0])) / (math.log10(yr[1]) - math.log10(yr[0]))
            return left + fx * (right - left), bottom - min(max(fy, -0.02), 1.02) * (bottom - top)

        draw.rectangle([left, top, right, bottom], outline="black")
        draw.text((left, 12), title, fill="black")
        for frac in (0.0, 0.5, 1.0):
            xv = xr[0] * (xr[1] / xr[0]) ** frac
            yv = yr[0] * (yr[1] / yr[0]) ** frac
            px, _ = to_px(xv, yr[0])
            _, py = to_px(xr[0], yv)
            draw.text((px - 10, bottom + 6), f"{xv:.3g}", fill="black")
            draw.text((x0 + 4, py - 6), f"{yv:.3g}", fill="black")
        return to_px

    budgets = [g["budget"] for g in gpu if g["budget"]]
    xr = (min(budgets) / 1.5, max(budgets) * 1.5)
    costs = [g["rain_ms"] for g in gpu if g["budget"]] + [g["frame_ms"] for g in gpu]
    to_px = axes(0, 500, "ms per frame vs budget: streak pass (blue), whole frame (gray)", xr,
                 (max(min(costs) / 2, 1e-2), max(costs) * 2))
    for key, colour in (("rain_ms", "blue"), ("frame_ms", "gray")):
        pts = [to_px(g["budget"], max(g[key], 1e-3)) for g in gpu if g["budget"]]
        draw.line(pts, fill=colour, width=2)
        for px, py in pts:
            draw.ellipse([px - 3, py - 3, px + 3, py + 3], fill=colour)
    colours = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e"]
    budgets_d = sorted({d["budget"] for d in dens})
    errs = [max(d["bin_rms"], 1e-4) for d in dens]
    to_px = axes(500, 1000, "RMS density error in the view's depth bins vs budget, per rate",
                 (min(budgets_d) / 1.5, max(budgets_d) * 1.5), (min(errs) / 2, max(errs) * 2))
    for i, rate in enumerate(RATES):
        pts = [to_px(d["budget"], max(d["bin_rms"], 1e-4)) for d in dens if d["rate"] == rate]
        if len(pts) > 1:
            draw.line(pts, fill=colours[i % len(colours)], width=2)
        for px, py in pts:
            draw.ellipse([px - 3, py - 3, px + 3, py + 3], fill=colours[i % len(colours)])
        draw.text((840, 50 + 14 * i), f"{rate:g} mm/h", fill=colours[i % len(colours)])
    img.save(path)


def main(argv: list[str] | None = None) -> int:
    p = parser("rainfall", __doc__.splitlines()[0])
    p.add_argument("--cpu-only", action="store_true", help="only the CPU table (runs on older code too)")
    args = p.parse_args(argv)
    quick = args.quick
    cpu_budgets = (10_000, 50_000, 200_000, 1_000_000)
    cpu = cpu_costs(cpu_budgets, frames=8 if quick else 20, repeats=1 if quick else 2)
    cpu_md = ("## CPU ms per frame of the rainfall (heavy rain, street, 5 cars, 2 m/s wind)\n\n"
              + cpu_costs.__doc__.split("\n\n")[0].replace("\n    ", " ") + "\n\n" + _cpu_table(cpu))
    if args.cpu_only:
        print(cpu_md)
        return 0
    gpu_budgets = (10_000, 50_000, 200_000) if quick else (10_000, 50_000, 200_000, 1_000_000)
    size = (320, 180) if quick else (640, 360)
    dens_budgets = (10_000, 50_000) if quick else (10_000, 50_000, 200_000, 1_000_000)

    gpu = gpu_costs(gpu_budgets, size, frames=3 if quick else 8)
    base = next(g for g in gpu if g["budget"] == 0)
    gpu_rows = [(g["budget"] or "R = 0", g["drawn"], "yes" if g["ran"] else "skipped", f"{g['rain_ms']:.1f}",
                 f"{g['frame_ms']:.0f}", f"{g['rain_ms'] / max(base['frame_ms'], 1e-9):.3f}") for g in gpu]
    dens = [density_errors(b, r, frames=2 if quick else 4) for b in dens_budgets for r in RATES]
    dens_rows = [(d["budget"], d["rate"], d["in_view"], f"{d['fill_s'] * 1e3:.1f}", f"{100 * d['bin_rms']:.1f}",
                  f"{100 * d['total_err']:.2f}", f"{100 * d['bias']:+.2f}", f"{100 * d['light_lost']:.2f}",
                  " ".join(f"{x:.3f}" for x in d["per_bin"])) for d in dens]
    bins = ", ".join(f"{a:g}–{b:g}" for a, b in zip(DEPTH_BINS_M[:-1], DEPTH_BINS_M[1:], strict=True))
    md = "\n\n".join([
        "# Rainfall",
        cpu_md,
        f"## Streak pass against the particle budget (heavy rain 8 mm/h, driver view, {size[0]}×{size[1]})",
        "Wall time to `ctx.finish()` of the streak pass (a transform-feedback pass computes each instance's "
        "streak once, then one instanced draw of their quads) and of the whole frame. `R = 0`: the effect is "
        "inactive — no update, no pass (the car's headlights also stay off then, so the dry frame's scene pass "
        "is cheaper). On llvmpipe only the ratios mean something.",
        markdown_table(["budget", "streaks drawn", "pass", "streak pass ms", "frame ms", "pass / dry frame"],
                       gpu_rows),
        "## Drawn density against the physical density, in the view",
        f"Parked camera in open air; the view frustum inside the outer box's full region, split by distance (m): "
        f"{bins}. Each drawn drop counts with its weight (the real drops it stands for); the ratio to "
        "N(R) (drops/m³, `physics.number_density_per_m3`) should be 1. *bin RMS*: the spatial error (Poisson "
        "noise of the thinned sample, what a viewer sees as a coarser texture); *total*: the error of the whole "
        "view's count; *light lost*: the share of the streaks' light the opacity/width caps could not place "
        "(1280×720 view). *advance ms*: the CPU time of the first frame (the drop table is built there).",
        markdown_table(["budget", "R (mm/h)", "drops in view", "advance ms", "bin RMS %", "total error %",
                        "bias %", "light lost %", "ratio per depth bin"], dens_rows),
    ])
    print(md)
    target = write_output(args.out, "rainfall", md)
    try:
        _plot(target.with_suffix(".png"), gpu, dens)
        print(f"\nwrote {target} and {target.with_suffix('.png')}")
    except ImportError:
        print(f"\nwrote {target} (no plot: Pillow is not installed)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
