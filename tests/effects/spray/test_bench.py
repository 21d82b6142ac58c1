"""The spray benchmark's heavy-rain run (``python -m rain_core.bench spray``): its frames carry what the effect's
update reads (the driver's camera among them), and each frame's new parcels are counted as uploaded."""

from __future__ import annotations

import numpy as np


def test_heavy_rain_run_steps_the_effect_and_counts_its_uploads(gl_ctx):
    from rain_core.bench.spray import heavy_rain_run
    from rain_core.effects.spray.parcels import PARTICLE_DTYPE

    wall, cpu, nbytes, spawned, emitter, _ = heavy_rain_run(gl_ctx, frames=4, warmup=2)
    assert len(cpu) == 4 and np.isfinite(wall).all() and (cpu >= 0.0).all()
    assert spawned.sum() > 0 and (nbytes % PARTICLE_DTYPE.itemsize == 0).all() and nbytes.sum() > 0
    assert emitter.take_dirty() == [[], []]  # every written range went up in its frame's prepare
