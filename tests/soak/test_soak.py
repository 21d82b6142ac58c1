"""The soak (issue 18): a long headless run at a tiny size with the weather, camera and speed changing every few
seconds, watching memory and every state for NaN/inf. Deselected by default; run it with

    RAINROAD_SOAK_FRAMES=14100 python -m pytest -m soak -s

(the default is 100,000 frames; the memory check needs at least 5,401, five cycles after the warm-up). It prints
frames, resident memory at the start (after a warm-up), at each cycle's start and at the end, growth per 1,000
frames and any non-finite state it met: NaN, inf or a
negative value in the HDR target after every frame; NaN or inf in the weather and the vehicles every frame; NaN
in any float array the effects hold every CHECK_EVERY frames (there inf is left alone: effects use it on purpose
as a sentinel, e.g. "no occluder above this cell", "empty slot"; the kernels' scratch arrays are made zeroed, so
one holds NaN only where a kernel wrote it). It fails on any of those, or on memory growing faster than
GROWTH_LIMIT_MB_PER_1000. On the 2-core VM with llvmpipe a frame takes ~115 ms (the city's vertices drawn for the
shadow, the reflection and the view): the default run is ~3 hours there.

The changes repeat with a period of CYCLE_CHANGES changes (the generator is reseeded at the start of every
cycle), so memory is compared at the same point of the same sequence: a pool that grows to the largest state the
sequence reaches levels off, a leak keeps growing by the same amount every cycle. The first cycle is the warm-up;
growth is the least-squares slope over the later half of the cycle boundaries after it (at least three). The later
half: the scene's state carries over from cycle to cycle (the weather's levels, the glass, the traffic), so the
first cycles still reach new extremes, and the allocators keep their high-water marks (resident memory rose in
steps of 3-25 MB at 1,350-1,620 and 2,970 frames and stayed flat between them, while Python's own heap stayed at
55 MB): such steps settle, a leak grows all the way.

Quality is turned down (QUALITY): at 64×36 the frame is the simulations' CPU work and llvmpipe's fixed costs,
and the soak is about leaks and stability over many frames, not about the picture.
"""

from __future__ import annotations

import gc
import math
import os
import time
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

FRAMES = int(os.environ.get("RAINROAD_SOAK_FRAMES", "100000"))
SIZE = (64, 36)
DT_S = 1.0 / 30.0
CHANGE_EVERY = 90  # frames (3 s) between changes of weather, camera and driving
CHECK_EVERY = 100  # frames between full walks over the effects' state
CYCLE_CHANGES = 12  # changes before the sequence repeats
CYCLE_FRAMES = CYCLE_CHANGES * CHANGE_EVERY  # 1,080 frames (36 s)
WARMUP_FRAMES = CYCLE_FRAMES  # the first cycle fills caches and pools; memory is measured from its end
GROWTH_LIMIT_MB_PER_1000 = 0.5
QUALITY = {"quality.particle_budget": 4000, "quality.ripple_grid": 64, "quality.windshield_resolution": 64,
           "spray.budget": 2000, "road.reflection_scale": 0.125}


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def nan_arrays(obj, path: str, seen: set, depth: int = 4) -> list[str]:
    """Paths of the float arrays (and floats) under ``obj``'s attributes that hold NaN."""
    if id(obj) in seen or depth < 0:
        return []
    seen.add(id(obj))
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc" and obj.size and np.isnan(obj).any():
            return [f"{path} ({int(np.isnan(obj).sum())} NaN of {obj.size})"]
        return []
    if isinstance(obj, float):
        return [f"{path} = nan"] if math.isnan(obj) else []
    if isinstance(obj, (list, tuple)):
        return [p for i, v in enumerate(obj[:64]) for p in nan_arrays(v, f"{path}[{i}]", seen, depth - 1)]
    if isinstance(obj, dict):
        return [p for k, v in list(obj.items())[:64] for p in nan_arrays(v, f"{path}[{k!r}]", seen, depth - 1)]
    module = type(obj).__module__ or ""
    if not module.startswith("rain_core") or not hasattr(obj, "__dict__"):
        return []  # GL wrappers, NumPy generators, settings' own types
    return [p for k, v in vars(obj).items() for p in nan_arrays(v, f"{path}.{k}", seen, depth - 1)]


def scene_state_problems(scene: Scene, with_effects: bool) -> list[str]:
    problems = []
    w = scene.weather_state
    values = [w.wetness, w.cracks, w.puddles, w.rate_mm_h, *w.wind.velocity_m_s, scene.time_s]
    if not all(math.isfinite(v) for v in values):
        problems.append(f"weather {w}")
    for i, v in enumerate(scene.vehicles):
        if not (np.isfinite(v.position).all() and math.isfinite(v.yaw) and math.isfinite(v.speed_m_s)):
            problems.append(f"vehicle {i}: position {v.position}, yaw {v.yaw}, speed {v.speed_m_s}")
    if with_effects:
        for effect in scene.effects:
            problems += nan_arrays(effect, type(effect).__name__, set())
    return problems


def change(scene: Scene, rng: np.random.Generator, step: int) -> SimpleNamespace | None:
    """New weather, time of day, camera and driving; returns the drive input (None: the autopilot)."""
    s = scene.settings
    rate = float(rng.choice([0.0, 0.3, 4.0, 30.0, 120.0, 500.0, rng.uniform(0.0, 500.0)]))
    set_value(s, "rain.rate_mm_h", rate)
    set_value(s, "time_of_day.hour", float(rng.uniform(0.0, 24.0)))
    set_value(s, "wind.speed_m_s", float(rng.uniform(0.0, 40.0)))
    set_value(s, "wind.direction_deg", float(rng.uniform(0.0, 360.0)))
    set_value(s, "wind.gustiness", float(rng.uniform(0.0, 1.0)))
    set_value(s, "camera.mode", str(rng.choice(["driver", "chase"])))
    set_value(s, "traffic.count", int(rng.integers(0, 8)))
    mode = step % 4
    if mode == 0:
        return None  # autopilot
    if mode == 1:
        return SimpleNamespace(throttle=1.0, brake=0.0, steer=float(rng.uniform(-0.05, 0.05)), reverse=False)
    if mode == 2:
        return SimpleNamespace(throttle=0.0, brake=float(rng.uniform(0.2, 1.0)), steer=0.0, reverse=False)
    return SimpleNamespace(throttle=float(rng.uniform(0.0, 1.0)), brake=0.0, steer=0.0, reverse=False)


@pytest.mark.soak
def test_soak(gl_ctx, capsys):
    settings = Settings()
    for path, value in QUALITY.items():
        set_value(settings, path, value)
    scene = Scene(gl_ctx, SIZE, settings, seed=18, gpu_timing=False)
    samples: list[tuple[int, float]] = []
    problems: list[str] = []
    drive = None
    start = time.perf_counter()
    rss_start = rss_end = math.nan
    ran = 0
    try:
        for i in range(FRAMES):
            ran = i + 1
            if i % CYCLE_FRAMES == 0:
                rng = np.random.default_rng(18)  # the same sequence every cycle
            if i % CHANGE_EVERY == 0:
                drive = change(scene, rng, (i % CYCLE_FRAMES) // CHANGE_EVERY)
            scene.step(DT_S, drive)
            scene.render()
            hdr = scene.renderer.hdr_image()
            found = [] if np.isfinite(hdr).all() and hdr.min() >= 0.0 else [
                f"HDR: {int((~np.isfinite(hdr)).any(-1).sum())} non-finite, {int((hdr < 0).any(-1).sum())} negative"]
            found += scene_state_problems(scene, with_effects=i % CHECK_EVERY == 0)
            problems += [f"frame {i}: {p}" for p in found]
            if i == WARMUP_FRAMES:
                gc.collect()
                rss_start = rss_mb()
            if i >= WARMUP_FRAMES and i % CYCLE_FRAMES == 0:
                gc.collect()
                samples.append((i, rss_mb()))
            if len(problems) > 50:
                break
        gc.collect()
        rss_end = rss_mb()
    finally:
        scene.release()
    wall = time.perf_counter() - start
    later = np.array(samples[len(samples) // 2:], dtype=float).reshape(-1, 2)  # (frame, MB) at the cycles' starts
    growth = float(np.polyfit(later[:, 0], later[:, 1], 1)[0] * 1000.0) if len(later) >= 3 else math.nan
    report = (f"soak: {ran} of {FRAMES} frames at {SIZE[0]}x{SIZE[1]} in {wall:.0f} s "
              f"({1000 * wall / max(ran, 1):.1f} ms a frame); "
              f"RSS {rss_start:.1f} MB after the first cycle ({WARMUP_FRAMES} frames), {rss_end:.1f} MB at the end "
              f"({rss_end - rss_start:+.1f} MB), growth {growth:+.3f} MB per 1,000 frames over the later half; "
              f"non-finite or negative states: {len(problems)}; RSS (MB) at each cycle's start: "
              + ", ".join(f"{int(f)}: {m:.0f}" for f, m in samples[::max(1, len(samples) // 12)]))
    with capsys.disabled():
        print("\n" + report)
        for p in problems[:20]:
            print("  " + p)
    assert not problems, report
    if len(later) >= 3:
        assert growth < GROWTH_LIMIT_MB_PER_1000, report
