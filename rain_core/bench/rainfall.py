"""Rainfall cost and accuracy: frame cost against the particle budget (10k → 1M), the error of the drawn drop
density against the physical one in the view, for each budget and rate (run time vs error), the light the
compensation could not place, and the CPU time of spawning at heavy rain with a 1M budget.

``python -m rain_core.bench rainfall [--quick] [--out DIR]`` prints the tables and writes DIR/rainfall.md and a
plot DIR/rainfall.png (drawn with Pillow). GPU times on llvmpipe are the CPU emulating a GPU: compare ratios.
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from rain_core import layout, physics
from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.camera import Camera
from rain_core.effects.rainfall import (
    RainfallSim,
    RainInput,
    StreakCamera,
    drop_weights,
    full_region,
    streak_geometry,
)

RATES = (0.5, 2.0, 8.0, 28.0, 80.0)
DEPTH_BINS_M = (0.5, 3.0, 8.0, 16.0, 40.0)  # m, distance bins of the view volume
EYE = np.array([layout.LANE_CENTRES_X[0] - 0.37, 1.2, 600.0])
FORWARD = np.array([0.0, -0.07, -1.0]) / np.hypot(0.07, 1.0)
FOV_DEG, ASPECT = 60.0, 16.0 / 9.0


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
    parked camera in open air. Also the share of the streaks' light that the width/opacity caps drop."""
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
        for _ in range(15):
            t += 1.0 / 30.0
            sim.advance(RainInput(time_s=t, **inp))
        slots = np.flatnonzero(sim.pool.alive & (sim.t_hit > t))
        p = sim.positions(slots, t)
        inside = np.all((p >= lo) & (p <= hi), axis=1)
        slots, p = slots[inside], p[inside]
        k = _classify(p, *basis)
        w = drop_weights(sim, slots, p, sim.boxes)
        per_bin = np.array([w[k == b].sum() for b in range(len(vol))]) / vol
        ratios.append(per_bin / n_phys)
        drawn_count.append(int(np.count_nonzero(k >= 0)))
        g = streak_geometry(sim, slots[k >= 0], t, sc, sim.boxes)
        v = g["visible"]
        lost.append(1.0 - g["drawn_px2"][v].sum() / max(g["light_px2"][v].sum(), 1e-12))
    ratios = np.array(ratios)
    total = (ratios * vol).sum(axis=1) / vol.sum()
    return {
        "budget": budget, "rate": rate, "fill_s": fill_s, "in_view": int(np.mean(drawn_count)),
        "bin_rms": float(np.sqrt(np.mean((ratios - 1.0) ** 2))), "total_err": float(np.mean(np.abs(total - 1.0))),
        "bias": float(np.mean(total) - 1.0), "light_lost": float(np.mean(lost)), "per_bin": ratios.mean(axis=0),
    }


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
        rain_ms, scene_ms, update_ms = [], [], []
        for _ in range(frames):
            scene.step(1.0 / 60.0)
            frame = scene.frame()
            rc = scene.renderer.render_context(frame)
            ctx.finish()
            t0 = time.perf_counter()
            scene.renderer.render(frame)
            ctx.finish()
            scene_ms.append((time.perf_counter() - t0) * 1e3)
            stats = {st.name: st for st in scene.renderer.stats}
            update_ms.append(stats["rainfall.update"].cpu_ms if "rainfall.update" in stats else 0.0)
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
        rows.append({"budget": budget, "live": effect.sim.live if effect.sim else 0, "ran": ran,
                     "rain_ms": statistics.median(rain_ms), "frame_ms": statistics.median(scene_ms),
                     "update_ms": statistics.median(update_ms)})
        scene.release()
    ctx.release()
    return rows


def spawn_cpu(budget: int, frames: int) -> list[dict]:
    """CPU time of RainfallSim.advance per frame in the street (roofs, ego car, traffic), heavy rain, 2 m/s wind:
    the first fill, then the steady state parked and at 100 km/h."""
    from rain_core.car_mesh import DRIVER_EYE_LOCAL
    from rain_core.vehicles import EgoCar, Traffic
    from rain_core.world import build_world

    world = build_world(seed=1)
    rows = []
    for label, speed in (("parked", 0.0), ("100 km/h", 100.0 / 3.6)):
        sim = RainfallSim(budget, seed=1, world=world)
        ego = EgoCar(position=np.array([layout.LANE_CENTRES_X[0], 0.0, 600.0]), speed_m_s=speed)
        traffic = Traffic(count=5, seed=1, ego=ego)
        vehicles = (ego, *traffic.vehicles)
        ms, spawned = [], []
        first = 0.0
        for i in range(frames):
            ego.step(1.0 / 60.0, 0.0, 0.0 if speed else 1.0, 0.0)
            ego.speed_m_s = speed
            traffic.step(1.0 / 60.0)
            eye = ego.to_world(DRIVER_EYE_LOCAL[None])[0]
            upd = sim.advance(RainInput(time_s=i / 60.0, camera_position=eye, camera_forward=ego.forward(),
                                        camera_velocity=ego.velocity(), rate_mm_h=8.0,
                                        wind_m_s=np.array([2.0, 0.0, 0.0]), vehicles=vehicles, wetness=1.0,
                                        puddles=0.5))
            if i == 0:
                first = upd.cpu_ms
            else:
                ms.append(upd.cpu_ms)
                spawned.append(upd.spawn_slots.size)
        steady = ms[len(ms) // 3:]
        rows.append({"case": label, "first_ms": first, "median_ms": statistics.median(steady),
                     "p95_ms": float(np.percentile(steady, 95)), "spawns": statistics.median(spawned[len(ms) // 3:]),
                     "live": sim.live})
    return rows


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
    args = parser("rainfall", __doc__.splitlines()[0]).parse_args(argv)
    quick = args.quick
    gpu_budgets = (10_000, 50_000, 200_000) if quick else (10_000, 50_000, 200_000, 1_000_000)
    size = (320, 180) if quick else (640, 360)
    dens_budgets = (10_000, 50_000) if quick else (10_000, 50_000, 200_000, 1_000_000)
    spawn_budget, spawn_frames = (1_000_000, 12) if quick else (1_000_000, 90)

    gpu = gpu_costs(gpu_budgets, size, frames=3 if quick else 8)
    base = next(g for g in gpu if g["budget"] == 0)
    gpu_rows = [(g["budget"] or "R = 0", g["live"], "yes" if g["ran"] else "skipped", f"{g['update_ms']:.2f}",
                 f"{g['rain_ms']:.1f}", f"{g['frame_ms']:.0f}", f"{g['rain_ms'] / max(base['frame_ms'], 1e-9):.3f}")
                for g in gpu]
    dens = [density_errors(b, r, frames=2 if quick else 4) for b in dens_budgets for r in RATES]
    dens_rows = [(d["budget"], d["rate"], d["in_view"], f"{d['fill_s'] * 1e3:.0f}", f"{100 * d['bin_rms']:.1f}",
                  f"{100 * d['total_err']:.2f}", f"{100 * d['bias']:+.2f}", f"{100 * d['light_lost']:.2f}",
                  " ".join(f"{x:.3f}" for x in d["per_bin"])) for d in dens]
    spawn = spawn_cpu(spawn_budget, spawn_frames)
    spawn_rows = [(s["case"], f"{s['first_ms']:.0f}", f"{s['median_ms']:.1f}", f"{s['p95_ms']:.1f}",
                   int(s["spawns"]), s["live"]) for s in spawn]
    bins = ", ".join(f"{a:g}–{b:g}" for a, b in zip(DEPTH_BINS_M[:-1], DEPTH_BINS_M[1:], strict=True))
    md = "\n\n".join([
        "# Rainfall",
        f"## Frame cost against the particle budget (heavy rain 8 mm/h, driver view, {size[0]}×{size[1]})",
        "Wall time to `ctx.finish()` of the streak pass (instanced quads, positions from the drop state texture), "
        "the CPU update (spawning, retiring, uploads) and the whole frame. `R = 0`: the effect is inactive — no "
        "update, no pass (the car's headlights also stay off then, so the dry frame's scene pass is cheaper). "
        "On llvmpipe only the ratios mean something.",
        markdown_table(["budget", "live drops", "pass", "update CPU ms", "streak pass ms", "frame ms",
                        "pass / dry frame"], gpu_rows),
        "## Drawn density against the physical density, in the view",
        f"Parked camera in open air; the view frustum inside the outer box's full region, split by distance (m): "
        f"{bins}. Each drawn drop counts with its weight (the real drops it stands for); the ratio to "
        "N(R) (drops/m³, `physics.number_density_per_m3`) should be 1. *bin RMS*: the spatial error (Poisson "
        "noise of the thinned sample, what a viewer sees as a coarser texture); *total*: the error of the whole "
        "view's count; *light lost*: the share of the streaks' light the opacity/width caps could not place "
        "(1280×720 view). Run time of the first fill in ms.",
        markdown_table(["budget", "R (mm/h)", "drops in view", "fill ms", "bin RMS %", "total error %",
                        "bias %", "light lost %", "ratio per depth bin"], dens_rows),
        f"## CPU time of spawning (heavy rain, {spawn_budget:,} budget, street with roofs, 6 vehicles, 2 m/s wind)",
        markdown_table(["case", "first fill ms", "median ms / frame", "p95 ms", "spawns / frame", "live drops"],
                       spawn_rows),
    ])
    print(md)
    target = write_output(args.out, "rainfall", md)
    try:
        _plot(target.with_suffix(".png"), gpu, dens)
        print(f"\nwrote {target} and {target.with_suffix('.png')}")
    except ImportError:
        print(f"\nwrote {target} (no plot: Pillow is not installed)")
    return 0
