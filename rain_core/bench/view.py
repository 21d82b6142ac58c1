"""Driver's view benchmark: the automatic exposure (its passes' cost and the GPU meter's error against the float64
reference) and the door mirrors (their view's cost, and skipped where not in view).

``python -m rain_core.bench view [--quick] [--out DIR]`` prints the table and writes DIR/view.md. On llvmpipe
(CPU-emulated GL) compare ratios, not absolute milliseconds.
"""

from __future__ import annotations

import statistics

from rain_core import exposure as X
from rain_core.bench._common import markdown_table, parser, write_output
from rain_core.gfx.context import create_headless_context
from rain_core.settings import Settings, set_value

CASES = (  # label, settings
    ("driver 40°, auto exposure", {}),
    ("driver 40°, hour's meter", {"camera.auto_exposure": False}),
    ("driver 70°, mirror in view", {"camera.driver_fov_deg": 70.0}),
    ("driver 70°, mirrors off", {"camera.driver_fov_deg": 70.0, "camera.mirrors": False}),
    ("chase", {"camera.mode": "chase"}),
    ("night 22.5 h, auto exposure", {"time_of_day.hour": 22.5}),
)


def _case(ctx, values: dict, frames: int, size) -> tuple[dict[str, float], float | None]:
    from rain_core.scene import Scene

    settings = Settings()
    for path, value in {"rain.rate_mm_h": 8.0, "time_of_day.hour": 17.5, **values}.items():
        set_value(settings, path, value)
    scene = Scene(ctx, size, settings, seed=1, gpu_timing=True)
    times: dict[str, list[float]] = {}
    errors = []
    try:
        for i in range(frames + 2):
            scene.step(1.0 / 30.0)
            scene.render()
            ctx.finish()
            if i < 2:
                continue
            for p in scene.renderer.stats:
                if p.ran:
                    times.setdefault(p.name, []).append(p.gpu_ms if p.gpu_ms is not None else p.cpu_ms)
            if settings.camera.auto_exposure:
                ref = X.metered_log2_luminance(scene.renderer.hdr_image())
                errors.append(abs(scene.renderer.exposure.read_meter() - ref))
    finally:
        scene.release()
        ctx.detect_framebuffer(0).use()
    return {k: statistics.median(v) for k, v in times.items()}, (max(errors) if errors else None)


def main(argv=None) -> int:
    args = parser("view", __doc__).parse_args(argv)
    frames, size = (2, (320, 180)) if args.quick else (6, (640, 360))
    ctx = create_headless_context()
    rows = []
    for label, values in CASES:
        t, err = _case(ctx, values, frames, size)
        total = sum(t.values())
        rows.append((label, t.get("exposure", "skipped"), t.get("mirrors", "skipped"), total,
                     "—" if err is None else f"{err:.1e}"))
    table = markdown_table(["case", "exposure ms", "mirrors ms", "all passes ms",
                            "meter |Δ log2 L| vs float64"], rows)
    md = (f"# Driver's view\n\nFrames at {size[0]}×{size[1]}, 8 mm/h, 17.5 h unless stated (llvmpipe: ratios; GPU ms "
          f"from timer queries). The exposure passes meter the finished frame, so on llvmpipe their row also waits "
          f"for the frame's queued work; compare the totals.\n\n{table}\n")
    print(md)
    write_output(args.out, "view", md)
    return 0
