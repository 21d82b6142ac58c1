"""rainfall: the physics of the drawn drops, the container's drawn density, the container's placement."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.rainfall import RainfallSim, drawn_share, full_region, layer_boxes, weighted_count
from rain_core.effects.rainfall.boxes import box_heights
from rain_core.effects.rainfall.constants import BOX_BOTTOM_Y_M, EYE_ALLOWANCE_M

# --- physics of the drawn drops ----------------------------------------------------------------------------


def test_drawn_diameters_and_speeds_follow_the_physics(rain):
    """At heavy rain every drawn drop stands for as many real ones, so the drawn sizes are N(D) itself; the fall
    speeds are the measured terminal velocities, quantised to a whole number of passes per period (< 1 %)."""
    rate = 8.0
    sim = RainfallSim(60000, seed=2)
    sim.advance(rain.input(0.0, rate=rate))
    d = sim.drops()
    drawn = d["drawn"]
    w = d["weight"][d["visible"]]
    # Thinned with one ratio: the weights differ only by the boxes' memberships, not by size.
    per_size = np.maximum(sim.last.thin_a * np.exp(-sim.last.thin_b * d["d_mm"][drawn]), sim.last.thin_c)
    assert np.ptp(per_size) < 1e-6 * per_size.max()
    assert w.size > 20000
    sizes = np.sort(d["d_mm"][drawn])
    n = sizes.size
    i = np.arange(1, n + 1)
    f = physics.drop_diameter_cdf(sizes, rate)
    assert max((i / n - f).max(), (f - (i - 1) / n).max()) < 1.95 / math.sqrt(n)
    # …while the instances' own size distribution (a heavier rain's) fails the same test: the thinning shapes it.
    all_d = np.sort(d["d_mm"])
    m = all_d.size
    f_all = physics.drop_diameter_cdf(all_d, rate)
    j = np.arange(1, m + 1)
    assert max((j / m - f_all).max(), (f_all - (j - 1) / m).max()) > 5.0 / math.sqrt(m)
    v = -d["vel"][:, 1]
    np.testing.assert_allclose(v, physics.terminal_velocity(d["d_mm"]), rtol=0.01)
    assert np.all(d["vel"][:, [0, 2]] == 0.0)  # no wind: purely vertical


@pytest.mark.parametrize("speed, wind", [(0.0, (0.0, 0.0, 0.0)), (27.8, (3.0, 0.0, 2.0))])
def test_expected_count_in_a_test_volume_within_5_percent(speed, wind, rain):
    """Weighted drops per m³ in a test box of each layer's full region equal the physical density."""
    rate = 8.0
    ratios = []
    for seed in range(2):
        sim = RainfallSim(30000, seed=seed)
        t = rain.drive(sim, 2.0, speed=speed, rate=rate, wind=wind)
        for _ in range(3):  # a few frames a second apart, averaged
            t = rain.drive(sim, 1.0, speed=speed, rate=rate, wind=wind, t0=t + 1.0 / 30.0)
            for k in range(3):
                lo, hi = full_region(sim.boxes, k)
                w, _ = weighted_count(sim, t, lo, hi)
                ratios.append((k, w / (physics.number_density_per_m3(rate) * np.prod(hi - lo))))
    for k in range(3):
        mean = np.mean([r for kk, r in ratios if kk == k])
        assert abs(mean - 1.0) < 0.05, (k, mean)
    # The drawn count follows the physical density until the budget is full (heavy rain).
    light = RainfallSim(8000, seed=1)
    light.advance(rain.input(0.0, rate=0.5))
    heavy = RainfallSim(8000, seed=1)
    heavy.advance(rain.input(0.0, rate=28.0))
    assert light.last.drawn_expected == pytest.approx(drawn_share(0.5) * heavy.last.drawn_expected, rel=0.02)
    assert drawn_share(0.5) < 0.5 and drawn_share(28.0) == 1.0
    assert np.count_nonzero(light.drops()["drawn"]) == pytest.approx(light.last.drawn_expected, rel=0.05)


@pytest.mark.parametrize("rate", [2.0, 8.0, 80.0])
def test_density_error_at_200k_within_2_percent(rate, rain):
    """The issue's accuracy target, on the twin: at a 200k budget the weighted density in the outer box's full
    region (every layer contributes there) is the physical one within 2 % — at light, heavy and extreme rain
    (where the sizes are thinned, and where large drops carry extra weight)."""
    sim = RainfallSim(200_000, seed=3)
    errors = []
    t = 0.0
    for i in range(2):
        t = rain.drive(sim, 0.5, speed=10.0, rate=rate, wind=(1.0, 0.0, 0.5), t0=t + 0.5 * i)
        lo, hi = full_region(sim.boxes, -1)
        w, count = weighted_count(sim, t, lo, hi)
        errors.append(w / (physics.number_density_per_m3(rate) * np.prod(hi - lo)) - 1.0)
        assert count > 10000
    assert abs(np.mean(errors)) < 0.02, errors


def test_container_follows_the_camera_and_looks_ahead():
    boxes = layer_boxes([0.0, 1.2, 100.0], [0.0, 0.0, -1.0], 40.0)
    lo, hi = boxes.lo, boxes.hi
    assert np.all(lo[:, 2] < 100.0) and np.all(hi[:, 2] > 100.0)  # the camera is inside every box
    assert np.all(100.0 - lo[:, 2] > 3.0 * (hi[:, 2] - 100.0))  # most of each box is in front
    assert np.all(np.diff(hi[:, 0] - lo[:, 0]) > 0)  # nested, growing
    down = layer_boxes([0.0, 5.0, 100.0], [0.0, -1.0, 0.0], 40.0)
    np.testing.assert_allclose(0.5 * (down.lo[:, 2] + down.hi[:, 2]), 100.0)  # looking down: centred
    # The height is the drops' vertical period: fixed while the eye moves up to EYE_ALLOWANCE_M …
    for y in (0.5, 1.2, 2.6, EYE_ALLOWANCE_M):
        b = layer_boxes([0.0, y, 100.0], [0.0, 0.0, -1.0], 40.0)
        np.testing.assert_allclose(b.hi[:, 1] - b.lo[:, 1], box_heights(40.0))
        np.testing.assert_allclose(b.lo[:, 1], BOX_BOTTOM_Y_M)
        assert np.all(b.fade_bottom == 0.0)
    # … and above it the boxes slide up with the same height, their bottoms fading in.
    high = layer_boxes([0.0, 20.0, 100.0], [0.0, 0.0, -1.0], 40.0)
    np.testing.assert_allclose(high.hi[:, 1] - high.lo[:, 1], box_heights(40.0))
    assert np.all(high.lo[:, 1] > BOX_BOTTOM_Y_M) and np.all(high.fade_bottom > 0.0)
