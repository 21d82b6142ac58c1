"""rainfall splashes: they follow the rate, never fall under a roof, and their kind follows the road."""

from __future__ import annotations

import numpy as np

from rain_core import layout
from rain_core.effects.rainfall import RainfallSim
from rain_core.effects.rainfall.constants import SPLASH_D_MIN_MM, SPLASH_LIFE_S, TYPE_PROMPT

# --- splashes -------------------------------------------------------------------------------------------------


def test_splashes_follow_the_rate_and_never_fall_under_a_roof(world, rain):
    counts = {}
    for rate in (0.5, 8.0):
        sim = RainfallSim(20000, seed=8, world=world)
        spawned = []
        t = 0.0
        for i in range(60):
            t = i / 30.0
            upd = sim.advance(rain.input(t, pos=(1.75, 1.2, layout.BRIDGE_Z_M + 12.0), rate=rate, wetness=1.0,
                                     puddles=0.5))
            spawned.append(upd.splash_slots)
        slots = np.concatenate(spawned)
        counts[rate] = slots.size
        if rate == 8.0:
            p = sim.splash_pos[np.unique(slots)]
            assert np.all(~np.isfinite(world.occluder_height(p[:, 0], p[:, 2]))), "a splash under a roof"
            life = sim.splash_life[slots]
            assert life.min() >= SPLASH_LIFE_S[0] - 1e-9 and life.max() <= SPLASH_LIFE_S[1] + 1e-9
    assert counts[8.0] > 20 * max(counts[0.5], 1)  # hardly any in light rain
    assert counts[8.0] > 200
    # A dry road gives prompt splashes, a wet one crowns; the drops that splash are the big ones.
    sim = RainfallSim(20000, seed=9)
    upd = sim.advance(rain.input(0.0, rate=8.0, wetness=0.0, puddles=0.0))
    kinds = np.floor(upd.splash_data[:, 6]).astype(int)
    assert np.all(kinds == TYPE_PROMPT)
    assert np.all(upd.splash_data[:, 4] >= SPLASH_D_MIN_MM)
