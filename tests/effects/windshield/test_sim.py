"""rain_core.effects.windshield.sim: arrivals, the water balance, determinism, and the simulation without GL."""

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.windshield import GlassInputs, WindshieldSim


def test_arrivals_follow_the_physics_flux_and_stop_under_a_roof():
    sim = WindshieldSim(seed=3)
    inputs = GlassInputs.for_speed(50.0, 4.0, drop_budget=0)
    rate, _, _ = sim.arrival_rate_per_s(inputs)
    n = sim.glass.normal
    flux = physics.flux_on_surface_per_s(4.0, sim.glass.area_m2, n, (0, 0, -50 / 3.6))
    assert rate == pytest.approx(flux, rel=1e-3)
    parked = GlassInputs.for_speed(0.0, 4.0, wind_m_s=np.array([3.0, 0.0, 5.0]))
    flux = physics.flux_on_surface_per_s(4.0, sim.glass.area_m2, n, (0, 0, 0), (3.0, 0.0, 5.0))
    assert sim.arrival_rate_per_s(parked)[0] == pytest.approx(flux, rel=1e-3)
    for _ in range(60):
        sim.step(1 / 60, inputs)
    expected = rate * 1.0
    assert abs(sim.arrival_count - expected) < 5 * math.sqrt(expected)
    covered = GlassInputs.for_speed(50.0, 4.0, sheltered=True)
    assert sim.arrival_rate_per_s(covered)[0] == 0.0
    assert sim.arrival_rate_per_s(GlassInputs.for_speed(50.0, 0.0))[0] == 0.0


def test_arrival_sizes_are_flux_weighted_marshall_palmer():
    sim = WindshieldSim(seed=4)
    inputs = GlassInputs.for_speed(0.0, 8.0)
    _, closing, cdf = sim.arrival_rate_per_s(inputs)
    d, _ = sim._sample_arrivals(40000, closing, cdf)
    # Parked, a drop's chance to land grows with its fall speed: the mean is ∫D·N·v / ∫N·v.
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 4001)
    w = physics.marshall_palmer(grid, 8.0) * physics.terminal_velocity(grid)
    assert d.mean() == pytest.approx(np.sum(grid * w) / np.sum(w), rel=0.02)
    assert d.mean() > physics.sample_drop_diameters(8.0, 40000, 5).mean() * 1.2


def test_mass_bookkeeping_closes_over_ten_thousand_frames():
    """arrived − wiped − shed − evaporated = on the glass, through speeds 0→120→0 km/h, a roof, wiper
    modes."""
    sim = WindshieldSim(seed=7)
    frames = 10_000
    for k in range(frames):
        x = k / frames
        speed = 120.0 * math.sin(math.pi * x)
        mode = ("auto", "low", "intermittent", "high", "off")[int(x * 5) % 5]
        inputs = GlassInputs.for_speed(
            speed,
            6.0 if x < 0.8 else 0.0,
            sheltered=0.3 < x < 0.35,
            drop_budget=300,
            wiper_mode=mode,
            wiper_interval_s=2.0,
        )
        sim.step(1 / 60, inputs)
        if k % 500 == 0:
            assert sim.glass.contains(sim.pos).all()
    assert sim.arrived > 0 and sim.wiped > 0 and sim.shed > 0 and sim.evaporated > 0
    assert abs(sim.balance_error_kg()) <= 0.01 * sim.arrived
    assert abs(sim.balance_error_kg()) <= 1e-9 * sim.arrived  # in fact exact up to rounding
    assert sim.glass.contains(sim.pos).all()
    assert np.all(sim.mass > 0) and np.all(sim.film >= 0) and np.all(sim.beads >= 0)


def test_drops_leave_the_glass_only_by_shedding(scatter):
    sim = WindshieldSim(seed=8)
    scatter(sim, 300, (3.5, 6.0))  # large drops: they run
    inputs = GlassInputs.for_speed(0.0, 0.0)
    before = sim.mass_on_glass()
    for _ in range(240):
        sim.step(1 / 30, inputs)
        assert sim.glass.contains(sim.pos).all()
    assert sim.shed > 0  # some ran off the lower edge …
    assert sim.mass_on_glass() + sim.shed + sim.evaporated == pytest.approx(
        before, rel=1e-12
    )  # … and nothing else


def test_determinism():
    def run():
        sim = WindshieldSim(seed=21)
        for k in range(200):
            sim.step(1 / 30, GlassInputs.for_speed(k * 0.5, 8.0, wiper_mode="auto", drop_budget=1500))
        return sim

    a, b = run(), run()
    assert np.array_equal(a.pos, b.pos) and np.array_equal(a.mass, b.mass) and np.array_equal(a.film, b.film)
    assert a.wiped == b.wiped and a.wipers.cycle_starts == b.wipers.cycle_starts
