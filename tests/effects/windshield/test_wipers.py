"""rain_core.effects.windshield.wipers / wiping: a stroke clears its sweep, the modes and rates, auto, heavy rain."""

import numpy as np
import pytest

from rain_core.effects.windshield import GlassInputs, WindshieldSim, WiperController, tandem_blades
from rain_core.effects.windshield.constants import RESIDUE_M
from rain_core.physics import RHO_WATER


def test_wiper_stroke_clears_its_swept_area(scatter):
    sim = WindshieldSim(seed=2)
    scatter(sim, 600, (0.5, 2.0))
    sim.film[:] = RHO_WATER * 2e-6 * sim.cell_areas  # a 2 µm film everywhere
    sim.arrived += float(sim.film.sum())
    inputs = GlassInputs.for_speed(0.0, 0.0, wiper_mode="low", wiper_low_cpm=45.0)
    for _ in range(int(60 / 45 * 30) + 2):  # one cycle
        sim.step(1 / 30, inputs)
        if sim.wipers.cycles:
            break
    assert sim.wipers.cycles == 1
    residue = RESIDUE_M * (1 + 4 * inputs.blade_wear)
    centres = sim.cell_centres.reshape(-1, 2)
    thickness = sim.film_thickness_m().ravel()
    for blade in sim.blades:
        inner = _in_sector(blade, centres, margin=0.02)
        assert inner.sum() > 100
        assert np.all(thickness[inner] <= residue * 1.001)  # below a small water threshold: the residue
        in_drops = _in_sector(blade, sim.pos, margin=0.02)
        assert not in_drops.any()
    outside = ~(_in_sector(sim.blades[0], centres, -0.02) | _in_sector(sim.blades[1], centres, -0.02))
    # Untouched (but for drying) where no blade went, except the paths of drops shed at the ends of the
    # stroke.
    assert np.mean(np.isclose(thickness[outside], 2e-6, rtol=0.02)) > 0.95
    assert sim.wiped > 0 and abs(sim.balance_error_kg()) < 1e-12


def _in_sector(blade, pts, margin):
    rel = pts - np.asarray(blade.pivot)
    r = np.hypot(rel[:, 0], rel[:, 1])
    phi = np.arctan2(rel[:, 1], rel[:, 0])
    return (
        (r > blade.r_inner_m + margin)
        & (r < blade.r_outer_m - margin)
        & (phi > blade.park_rad + margin / np.maximum(r, 1e-3))
        & (phi < blade.top_rad - margin / np.maximum(r, 1e-3))
    )


def test_wiper_modes_and_their_rates():
    c = WiperController()
    assert c.advance(10.0, "off") == [] and not c.running
    segs = c.advance(60.001, "high", high_cpm=70.0)
    assert c.cycles == 70 and segs[0].p_start == 0.0
    assert [s.event for s in segs if s.event][:4] == ["top", "park", "top", "park"]
    c = WiperController()
    c.advance(60.001, "low", low_cpm=45.0)
    assert c.cycles == 45
    c = WiperController()
    for _ in range(601):
        c.advance(0.1, "intermittent", interval_s=5.0, low_cpm=60.0)
    # 60 s of 1 s cycles + 5 s pauses, the first at once: a cycle every 6 s.
    assert c.cycles == 10
    assert np.allclose(np.diff(c.cycle_starts), 6.0)
    # off in mid-stroke: the blade returns to park, then rests.
    c = WiperController()
    c.advance(0.3, "low", low_cpm=60.0)
    assert c.running
    c.advance(5.0, "off")
    assert not c.running and c.progress == 0.0 and c.cycles == 1
    blades = tandem_blades(1.54, 1.21, 1.1)
    assert blades[0].angle(0.0) == pytest.approx(blades[0].park_rad)
    assert blades[0].angle(1.0) == pytest.approx(blades[0].top_rad)
    with pytest.raises(ValueError):
        c.advance(1.0, "fast")


def _auto_cycles(rate_mm_h: float) -> int:
    sim = WindshieldSim(seed=6)
    inputs = GlassInputs.for_speed(50.0, rate_mm_h, wiper_mode="auto", drop_budget=800)
    for _ in range(20 * 30):
        sim.step(1 / 30, inputs)
    return sim.wipers.cycles


def test_auto_wipes_more_often_in_heavier_rain():
    light, heavy = _auto_cycles(0.5), _auto_cycles(8.0)
    assert heavy > light >= 1


def test_heavy_rain_overwhelms_a_slow_wiper_more_than_a_fast_one():
    def water_in_view(mode: str) -> float:
        """Mean water (kg/m²) in the driver's blade's sweep, over 6 s after the first 2."""
        sim = WindshieldSim(seed=9)
        blade = sim.blades[0]
        cells = _in_sector(blade, sim.cell_centres.reshape(-1, 2), 0.0)
        area = sim.cell_areas.ravel()[cells].sum()
        inputs = GlassInputs.for_speed(60.0, 8.0, wiper_mode=mode, drop_budget=1500)
        samples = []
        for k in range(8 * 30):
            sim.step(1 / 30, inputs)
            if k > 60:
                drops = sim.mass[_in_sector(blade, sim.pos, 0.0)].sum()
                samples.append((drops + sim.film.ravel()[cells].sum() + sim.beads[0].sum()) / area)
        return float(np.mean(samples))

    assert water_in_view("low") > 1.5 * water_in_view("high")
