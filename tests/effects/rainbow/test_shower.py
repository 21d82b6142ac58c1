"""Where the bow's rain is: around the viewer while it rains, then a departing shower."""

from __future__ import annotations

import math

from rain_core.effects.rainbow.shower import MAX_DISTANCE_M, ShowerTracker


def test_never_rained_means_no_column():
    t = ShowerTracker()
    t.observe(0.0, 0.0)
    assert t.column(5.0, 0.0, 10.0, 3000.0) is None


def test_rain_fills_every_ray_from_the_eye():
    t = ShowerTracker()
    t.observe(1.0, 4.0)
    c = t.column(1.0, 4.0, 10.0, 3000.0)
    assert c.near_m == 0.0 and math.isinf(c.far_m) and c.rate_mm_h == 4.0


def test_the_shower_departs_at_its_speed_and_ends():
    t = ShowerTracker()
    t.observe(1.0, 4.0)
    t.observe(2.0, 0.0)
    c = t.column(61.0, 0.0, 10.0, 3000.0)
    assert c.rate_mm_h == 4.0 and c.near_m == 600.0 and c.far_m == 3600.0
    assert t.column(1.0 + MAX_DISTANCE_M / 10.0, 0.0, 10.0, 3000.0) is None


def test_time_running_backwards_forgets_the_rain():
    t = ShowerTracker()
    t.observe(10.0, 4.0)
    t.observe(0.0, 0.0)
    assert t.column(1.0, 0.0, 10.0, 3000.0) is None
