"""Offline quality: sub-frames per recorded frame against the error to 64 sub-frames (run time vs error).

``python -m rain_core.bench offline [--size 160x90] [--frames 3] [--warmup 10] [--out DIR]``. For each N in
1, 2, 4, …, 64 a fresh Session (same seed, heavy rain, driver's seat, wipers on high) drives ``--warmup``
plain frames at 30 frames/s, then ``--frames``
frames of N sub-frames each (``Session.step(dt, subframes=N)``). The error is that of those frames against the
N = 64 run's, in sRGB levels (0–255, mean absolute) and as PSNR. Time per frame: wall (the GPU's share
included) and the process's CPU (thread clock), minimum over the frames.

The simulations step at the sub-frame rate, so spray, drops and ripples of different N are different draws of the
same weather: part of the error at large N is that, not the shutter's sampling (it levels off instead of
falling to 0).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

SUBFRAMES = (1, 2, 4, 8, 16, 32, 64)


def _settings():
    from rain_core.settings import Settings, set_value

    s = Settings()
    for key, value in {"rain.rate_mm_h": 16.0, "rain.wetness": 1.0, "rain.puddles": 0.6, "wipers.mode": "high",
                       "camera.exposure_s": 1.0 / 60.0, "traffic.count": 4}.items():
        set_value(s, key, value)
    return s


def run(ctx, size, n: int, frames: int, warmup: int, fps: float = 30.0):
    """(pictures, wall s per frame, CPU s per frame) of ``frames`` frames at ``n`` sub-frames."""
    from rain_core.session import Session

    pictures, walls, cpus = [], [], []
    with Session(size=size, seed=1, camera="driver", settings=_settings(), ctx=ctx) as sim:
        for _ in range(warmup):
            sim.step(1.0 / fps)
        for _ in range(frames):
            t0, c0 = time.perf_counter(), time.thread_time()
            sim.step(1.0 / fps, subframes=n)
            pictures.append(sim.capture().rgb)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.thread_time() - c0)
    return pictures, min(walls), min(cpus)


def errors(pictures, reference) -> tuple[float, float]:
    """(mean |Δ| in sRGB levels, PSNR dB) over all frames."""
    a = np.stack(pictures).astype(np.float64)
    b = np.stack(reference).astype(np.float64)
    mae = float(np.abs(a - b).mean())
    mse = float(((a - b) ** 2).mean())
    return mae, (math.inf if mse == 0.0 else 10.0 * math.log10(255.0**2 / mse))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m rain_core.bench offline", description=__doc__.splitlines()[0])
    p.add_argument("--size", default="160x90", help="frame size WxH")
    p.add_argument("--frames", type=int, default=3, help="measured frames per N")
    p.add_argument("--warmup", type=int, default=10, help="plain frames before them")
    p.add_argument("--out", default="bench_out", help="folder for offline.md")
    args = p.parse_args(argv)
    size = tuple(int(v) for v in args.size.lower().split("x"))
    from rain_core.gl import create_headless_context

    ctx = create_headless_context()
    results = {n: run(ctx, size, n, args.frames, args.warmup) for n in reversed(SUBFRAMES)}
    reference = results[SUBFRAMES[-1]][0]
    lines = [f"# Offline quality, {size[0]}x{size[1]}, {args.frames} frames after {args.warmup}: sub-frames vs "
             f"error to {SUBFRAMES[-1]}", "", "| sub-frames | wall ms/frame | CPU ms/frame | mean abs error "
             "(sRGB levels) | PSNR dB |", "|---|---|---|---|---|"]
    for n in SUBFRAMES:
        pictures, wall, cpu = results[n]
        mae, psnr = errors(pictures, reference)
        lines.append(f"| {n} | {wall * 1e3:.0f} | {cpu * 1e3:.0f} | {mae:.3f} | {psnr:.1f} |")
    md = "\n".join(lines)
    print(md)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "offline.md").write_text(md + "\n")
    ctx.release()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
