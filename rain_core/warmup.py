"""``python -m rain_core.warmup``: compile the CPU simulations' kernels (rain_core.jit) into Numba's disk cache.

It renders a small headless scene through what calls them — heavy rain on a flooded road, the wipers running,
traffic spraying, first at speed and then parked — so each kernel compiles with the argument types the app
passes. The window starts this in a child process on a cold start (``jit.WarmUp``) and runs the NumPy twins
until it ends; run it by hand after an install to make the first start fast too.
"""

from __future__ import annotations

import sys
import time

from rain_core import jit

SIZE = (64, 36)  # the kernels do not depend on the frame size: the smallest frame the renderer takes
FRAMES_AT_SPEED = 45
FRAMES_PARKED = 20


def warm_up(frames_at_speed: int = FRAMES_AT_SPEED, frames_parked: int = FRAMES_PARKED) -> tuple[int, int]:
    """Render the warm-up scene with the kernels on; (kernels now loadable from disk, kernels defined)."""
    from rain_core.bench.frame import heavy_rain_settings
    from rain_core.gl import create_headless_context
    from rain_core.scene import Scene

    jit.set_active(True)
    ctx = create_headless_context()
    scene = Scene(ctx, SIZE, settings=heavy_rain_settings(10_000), seed=1, gpu_timing=False)
    try:
        for effect in scene.effects:
            if effect.name == "ripples":
                effect.backend = "numpy32"  # the CPU solver's kernels (the GPU one has none)
        scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 100.0 / 3.6
        for _ in range(frames_at_speed):
            scene.step(1.0 / 30.0, None)
            scene.render()
        scene.autopilot.target_speed_m_s = 0.0
        for _ in range(frames_parked):
            scene.step(1.0 / 30.0, None)
            scene.render()
        ctx.finish()
    finally:
        scene.release()
        ctx.release()
    loadable = sum(jit._loads_from_disk(d) for d in jit._KERNELS)
    return loadable, len(jit._KERNELS)


def main() -> int:
    if not jit.AVAILABLE:
        print("rain_core.warmup: Numba is not installed; nothing to compile (pip install 'rainroad[fast]')")
        return 0
    t0 = time.perf_counter()
    loadable, total = warm_up()
    jit.mark_warm()
    print(f"rain_core.warmup: {loadable} of {total} kernels cached on disk in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
