"""A scene's pixels do not depend on what ran before it in the process: a sweep worker or ``sheets all`` renders
many scenes in one process, and each must give the image a fresh process gives. Module-level caches (a world's
drip sites, samplers, tables) are kept per everything their result depends on; a cache keyed on less shows here.

The scene drawn twice (``_render``) uses effects seeded apart from its world (as the contact sheets build them),
under the bridge where the drips fall, after a scene of the same world with the default seeds."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent('''
    import hashlib
    import numpy as np
    from rain_core.camera import look_at
    from rain_core.effects import default_effects
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    def _render(ctx, effects_seed):
        s = Settings()
        s.rain.rate_mm_h = 8.0
        s.time_of_day.hour = 15.0
        s.traffic.count = 0
        effects = None if effects_seed is None else default_effects(ctx, s, seed=effects_seed)
        scene = Scene(ctx, (96, 54), s, seed=1, effects=effects, gpu_timing=False)
        camera = look_at(np.array([-3.5, 1.6, 313.0]), np.array([0.0, 3.5, 300.0]), fov_y_deg=60.0)
        try:
            for _ in range(2):
                scene.step(1 / 30)
                scene.render(camera)
            return hashlib.sha1(scene.image().tobytes()).hexdigest()
        finally:
            scene.release()
            ctx.detect_framebuffer(0).use()
''')


def test_a_scene_renders_as_in_a_fresh_process(gl_ctx):
    namespace: dict = {}
    exec(SCRIPT, namespace)
    render = namespace["_render"]
    render(gl_ctx, None)  # the same world first, with the default seeds (the drips' sites: seed 1)
    here = render(gl_ctx, 7)
    fresh = subprocess.run(
        [sys.executable, "-c", SCRIPT + textwrap.dedent('''
            from rain_core.gl import create_headless_context
            print(_render(create_headless_context(), 7))
        ''')], capture_output=True, text=True, timeout=300, check=True).stdout.split()[-1]
    assert len(fresh) == 40 and here == fresh  # SHA-1 hex digests, not an error text
