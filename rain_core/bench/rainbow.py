"""Rainbow benchmark: the P(θ) table's run time against its error (wavelength step and drop-size nodes against a
dense reference), and the pass's cost when a bow is drawn against every case that skips it.

``python -m rain_core.bench rainbow [--quick] [--out DIR]`` prints the tables and writes DIR/rainbow.md. On
llvmpipe (CPU-emulated GL) compare ratios, not absolute milliseconds.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.effects.rainbow.effect import LUT_SAMPLES
from rain_core.effects.rainbow.optics import WAVELENGTHS_NM, bow_lut
from rain_core.gfx.context import create_headless_context
from rain_core.settings import Settings


def table_rows(quick: bool) -> list[tuple]:
    """(λ step nm, size nodes, ms per table, max error / peak) against 2 nm and 192 nodes."""
    reference = bow_lut(4.0, LUT_SAMPLES, wavelengths_nm=np.arange(380.0, 781.0, 2.0), size_nodes=192)
    peak = reference.max()
    configs = [(20.0, 16), (20.0, 32), (10.0, 48), (5.0, 96)]
    rows = []
    for step, nodes in configs:
        lam = np.arange(380.0, 781.0, step)
        t0 = time.perf_counter()
        lut = bow_lut(4.0, LUT_SAMPLES, wavelengths_nm=lam, size_nodes=nodes)
        ms = (time.perf_counter() - t0) * 1e3
        used = "← used" if nodes == 32 and np.array_equal(lam, WAVELENGTHS_NM) else ""
        rows.append((f"{step:g}", nodes, ms, float(np.abs(lut - reference).max() / peak), used))
        if quick:
            break
    return rows


def _pass_ms(ctx, case: str, frames: int, size) -> tuple[bool, float, float]:
    from rain_core.scene import Scene
    from rain_core.sheets.rainbow import antisolar_camera

    s = Settings()
    s.rain.rate_mm_h = 0.0 if case == "dry" else 4.0
    s.time_of_day.hour = {"noon (sun 62°)": 12.0, "night": 22.0}.get(case, 17.0)
    s.rainbow.enabled = case != "disabled"
    camera = antisolar_camera(s.time_of_day.hour, (-1.75, 40.0, 700.0))
    if case == "facing the sun":
        camera = antisolar_camera(s.time_of_day.hour, (-1.75, 40.0, 700.0), raise_deg=-10.0)
        camera.forward = -camera.forward * np.array([1.0, 0.0, 1.0])
    scene = Scene(ctx, size, s, seed=1, gpu_timing=True)
    post, total, ran = [], [], False
    try:
        for i in range(frames + 2):
            scene.step(1.0 / 30.0)
            scene.render(camera)
            ctx.finish()
            if i < 2:
                continue  # compile, allocate, and let the timer queries (read a frame late) fill
            stats = {p.name: p for p in scene.renderer.stats}
            p = stats.get("rainbow.post")
            ran = bool(p and p.ran)
            post.append((p.gpu_ms if p and p.gpu_ms is not None else (p.cpu_ms if p else 0.0)) if ran else 0.0)
            total.append(sum((q.gpu_ms if q.gpu_ms is not None else q.cpu_ms) for q in stats.values() if q.ran))
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()
    return ran, statistics.median(post), statistics.median(total)


def main(argv=None) -> int:
    args = parser("rainbow", __doc__).parse_args(argv)
    frames, size = (3, (320, 180)) if args.quick else (10, (640, 360))
    t_rows = table_rows(args.quick)
    table = markdown_table(["λ step (nm)", "size nodes", "ms per table", "max error / peak", ""], t_rows)
    ctx = create_headless_context()
    cases = ["bow drawn (17 h, 4 mm/h)", "disabled", "dry", "noon (sun 62°)", "night", "facing the sun"]
    c_rows = []
    for case in cases:
        ran, post, total = _pass_ms(ctx, case, frames, size)
        c_rows.append((case, "yes" if ran else "skipped", post, total))
    cost = markdown_table(["case", "rainbow pass", "rainbow.post ms", "frame ms (all passes)"], c_rows)
    md = (f"# Rainbow\n\nP(θ) table ({LUT_SAMPLES} angles, 4 mm/h) against 2 nm × 192 sizes:\n\n{table}\n\n"
          f"Pass cost at {size[0]}×{size[1]} (llvmpipe: compare ratios):\n\n{cost}\n")
    print(md)
    write_output(args.out, "rainbow", md)
    return 0
