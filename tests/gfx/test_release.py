"""A scene releases every GL object it made: a sweep builds thousands of scenes in one worker (issue 18)."""

import gc

import numpy as np

from rain_core.scene import Scene
from rain_core.settings import Settings, set_value


def _rainy_settings() -> Settings:
    s = Settings()
    set_value(s, "rain.rate_mm_h", 8.0)
    return s


def test_scene_release_leaves_no_gl_object_behind(gl_ctx):
    # context_gc: moderngl queues objects whose Python wrapper died unreleased instead of freeing them, so the
    # queue is exactly what a release() forgot.
    gc.collect()  # what earlier tests dropped is theirs, not this test's: collect it before counting
    old_mode = gl_ctx.gc_mode
    gl_ctx.gc_mode = "context_gc"
    try:
        for camera in ("driver", "chase"):
            s = _rainy_settings()
            set_value(s, "camera.mode", camera)
            scene = Scene(gl_ctx, (96, 54), s, seed=3, gpu_timing=False)
            for _ in range(3):
                scene.step(1 / 30)
                scene.render()
            assert np.isfinite(scene.renderer.hdr_image()).all()
            scene.release()
            del scene
            gc.collect()
        # Released objects reach the queue too, as InvalidObject shells; anything else was never released.
        leaked = [type(o).__name__ for o in gl_ctx.objects if type(o).__name__ != "InvalidObject"]
        assert not leaked, f"unreleased GL objects after Scene.release(): {sorted(set(leaked))} ({len(leaked)})"
    finally:
        gl_ctx.objects.clear()  # only released shells are left (a real leak has failed the test above)
        gl_ctx.gc_mode = old_mode
