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
        seen = 0
        for i in range(60):
            t = i / 30.0
            sim.advance(rain.input(t, pos=(1.75, 1.2, layout.BRIDGE_Z_M + 12.0), rate=rate, wetness=1.0, puddles=0.5))
            sp = sim.splashes()
            vis = sp["visible"]
            seen += int(np.count_nonzero(vis & (sp["age"] < 1.0 / 30.0)))  # the impacts of this frame
            if rate == 8.0:
                p = sp["pos"][vis]
                assert np.all(~np.isfinite(world.occluder_height(p[:, 0], p[:, 2]))), "a splash under a roof"
                life = sp["life"][vis]
                assert np.all(sp["age"][vis] < life)
                assert life.min() >= SPLASH_LIFE_S[0] - 1e-9 and life.max() <= SPLASH_LIFE_S[1] + 1e-9
                # The splash layer's box reaches under the bridge, whose open share is empty.
                under = sp["drawn"] & (np.abs(sp["pos"][:, 2] - layout.BRIDGE_Z_M) < layout.BRIDGE_DEPTH_M / 2 - 0.5)
                assert under.any() and not np.any(under & vis)
        counts[rate] = seen
    assert counts[8.0] > 20 * max(counts[0.5], 1)  # hardly any in light rain
    assert counts[8.0] > 200
    # A dry road gives prompt splashes, a wet one crowns; the drops that splash are the big ones.
    sim = RainfallSim(20000, seed=9)
    sim.advance(rain.input(0.0, rate=8.0, wetness=0.0, puddles=0.0))
    sp = sim.splashes()
    assert np.all(sp["kind"][sp["visible"]] == TYPE_PROMPT)
    assert np.all(sp["d_mm"] >= SPLASH_D_MIN_MM)
    # Their sizes follow N(D)·v(D) above SPLASH_D_MIN_MM (the impacts), not N(D).
    from rain_core import physics

    d = np.sort(sp["d_mm"])
    grid = np.linspace(SPLASH_D_MIN_MM, physics.D_MAX_MM, 2001)
    f = physics.marshall_palmer(grid, 8.0) * physics.terminal_velocity(grid)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(grid))])
    cdf /= cdf[-1]
    m = d.size
    j = np.arange(1, m + 1)
    fd = np.interp(d, grid, cdf)
    assert max((j / m - fd).max(), (fd - (j - 1) / m).max()) < 1.95 / np.sqrt(m) + 0.01  # v on a 16-point table
    wet = RainfallSim(20000, seed=9, world=world)
    wet.advance(rain.input(0.0, pos=(1.75, 1.2, 600.0), rate=8.0, wetness=1.0, puddles=1.0))
    sw = wet.splashes()
    road = sw["visible"] & (np.abs(sw["pos"][:, 0]) < layout.ROAD_HALF_WIDTH_M)
    assert road.any() and np.all(sw["kind"][road] == 0)  # every road splash is a puddle crown at puddles = 1
