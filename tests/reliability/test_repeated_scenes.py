"""Creating, rendering with and releasing a Scene many times in one process keeps memory flat (issue 18: a sweep
renders thousands of sequences in one worker; each Scene once kept ~34 MB of programs and vertex arrays alive).

Resident memory is read from /proc/self/statm (Linux); moderngl's ``context_gc`` mode queues every GL object
whose Python wrapper died unreleased, so after each release the queue must hold nothing but released shells.
"""

from __future__ import annotations

import ctypes
import gc
import os
import sys

import numpy as np
import pytest

from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

SCENES = 30
WARMUP = 5  # the first scenes fill the driver's and the allocator's caches (shader cache, arenas)
RSS_GROWTH_LIMIT_MB = 24.0  # over the last SCENES − WARMUP scenes (a leak of the old kind: ~34 MB per scene)


def rss_mb() -> float:
    """Resident set size of this process in MB (Linux /proc), after handing the allocator's free heap pages back
    to the system: in a long suite run, memory freed by one scene but kept in glibc's arenas showed as steps of
    ~14 MB over the first scenes, then none (not a leak; a leak of the old kind grows ~34 MB every scene)."""
    _trim_heap()
    with open("/proc/self/statm") as f:
        pages = int(f.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def _trim_heap() -> None:
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: RSS as it is
        pass


def live_gl_objects(ctx) -> list[str]:
    """Type names of the unreleased GL objects the context's gc queue holds (released ones are InvalidObject)."""
    return [type(o).__name__ for o in ctx.objects if type(o).__name__ != "InvalidObject"]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/statm")
def test_thirty_scenes_keep_memory_flat(gl_ctx):
    gc.collect()  # what earlier tests dropped is theirs, not this test's
    old_mode = gl_ctx.gc_mode
    gl_ctx.gc_mode = "context_gc"
    gl_ctx.objects.clear()
    rss = []
    try:
        for i in range(SCENES):
            s = Settings()
            set_value(s, "rain.rate_mm_h", 30.0)
            set_value(s, "camera.mode", ("driver", "chase")[i % 2])
            scene = Scene(gl_ctx, (64, 36), s, seed=i, gpu_timing=False)
            for _ in range(2):
                scene.step(1 / 30)
                scene.render()
            scene.release()
            del scene
            gc.collect()
            leaked = live_gl_objects(gl_ctx)
            assert not leaked, f"scene {i}: unreleased GL objects {sorted(set(leaked))} ({len(leaked)})"
            gl_ctx.objects.clear()  # released shells only
            rss.append(rss_mb())
    finally:
        gl_ctx.objects.clear()
        gl_ctx.gc_mode = old_mode
    # Medians of five scenes at each end: one allocator spike in a long suite run is not a trend (a leak of the
    # old kind still shows as ~34 MB per scene).
    growth = float(np.median(rss[-5:]) - np.median(rss[WARMUP - 1: WARMUP + 4]))
    per_scene = growth / (SCENES - WARMUP - 4)
    print(f"RSS after scene 1: {rss[0]:.0f} MB, after {WARMUP}: {rss[WARMUP - 1]:.0f} MB, after {SCENES}: "
          f"{rss[-1]:.0f} MB ({per_scene:+.2f} MB per scene)")
    assert growth < RSS_GROWTH_LIMIT_MB, f"RSS grew {growth:.1f} MB over {SCENES - WARMUP} scenes: {rss}"
