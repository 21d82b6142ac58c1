"""rainfall over time: determinism, smooth rate changes, skipping when there is no rain."""

from __future__ import annotations

import numpy as np

from rain_core import physics
from rain_core.effects.rainfall import RainfallSim, full_region, weighted_count


def test_same_seed_same_frame(gl_ctx, shaders, rain):
    images = []
    for seed in (11, 11, 12):
        s = rain.settings(rate=8.0, mode="driver", budget=4000)
        scene, _ = rain.scene(gl_ctx, shaders, s, seed=seed)
        for _ in range(3):
            scene.step(1.0 / 30.0)
        scene.render()
        images.append(scene.image())
    assert np.array_equal(images[0], images[1])
    assert not np.array_equal(images[0], images[2])


def test_a_rate_change_takes_effect_smoothly(rain):
    """R steps from 2 to 28 mm/h and back to 0: the weighted density moves a little each frame, no pop."""
    sim = RainfallSim(20000, seed=6)
    dt = 1.0 / 30.0
    t = rain.drive(sim, 3.0, rate=2.0, dt=dt)
    lo, hi = full_region(sim.boxes, 2)
    volume = float(np.prod(hi - lo))
    series = []
    for rate, seconds in ((28.0, 12.0), (0.0, 30.0)):
        for _ in range(int(seconds / dt)):
            t += dt
            sim.advance(rain.input(t, rate=rate))
            series.append(weighted_count(sim, t, lo, hi)[0] / volume)
    series = np.array(series)
    n2, n28 = physics.number_density_per_m3(2.0), physics.number_density_per_m3(28.0)
    steps = np.abs(np.diff(series))
    # Never more than 8 % of the change in one frame: the ramp itself moves 2.2 % per frame at first, and the
    # thinning decides mid-air which instances show (the drops keep no spawn history), which adds noise of
    # about 3 % of the change per frame at this budget; a pop would be the whole change at once.
    assert steps.max() < 0.08 * (n28 - n2)
    assert series[0] < n2 + 0.1 * (n28 - n2)  # the first frame after the change still looks like before
    rise = series[: int(12.0 / dt)]
    assert rise[-1] > n2 + 0.6 * (n28 - n2)  # most of the way there within 12 s
    fall = series[int(12.0 / dt):]
    assert series[-1] < 0.01 * n28  # the air empties after the rain stops
    assert np.all(np.diff(fall[int(5.0 / dt):]) <= 0.01 * n28)  # … steadily
    assert sim.rate_eff == 0.0


def test_no_rain_no_pass(gl_ctx, shaders, rain):
    s = rain.settings(rate=0.0, mode="driver")
    scene, effect = rain.scene(gl_ctx, shaders, s)
    scene.step(1.0 / 60.0)
    scene.render()
    stats = {st.name: st.ran for st in scene.renderer.stats}
    assert stats["rainfall"] is False and "rainfall.transparent" not in stats
    assert effect.sim is None
    # Rain starts, then stops: the pass runs while drops are still in the air, then stops by itself.
    s.rain.rate_mm_h = 8.0
    scene.step(1.0 / 60.0)
    scene.render()
    assert "rainfall.transparent" in {st.name for st in scene.renderer.stats}
    s.rain.rate_mm_h = 0.0
    for _ in range(600):  # the rate ramps down (RATE_RAMP_S); no drop outlives it
        scene.step(0.25)
        frame = scene.frame()
        if not effect.active(frame):
            break
        effect.update(frame, scene.renderer.render_context(frame))
    assert not effect.active(scene.frame()) and effect.sim.rate_eff == 0.0
    # Switched off: skipped at once.
    s.rain.rate_mm_h = 8.0
    s.rainfall.enabled = False
    assert not effect.active(scene.frame())
