"""Drips without GL: where the sites are, how much water leaves a roof (a linear reservoir, exact for any step,
mass conserved) and how a drop falls (the closed form against its own inverse and limits)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.drips import edges, flow


def _roof_grid(height_m=5.0, size=(16, 32), cell=0.25):
    """An open grid with one flat roof of size cells (z, x) in its middle."""
    grid = np.full((80, 120), -np.inf, np.float32)
    grid[20:20 + size[0], 40:40 + size[1]] = height_m
    return grid, -15.0, cell


def test_a_flat_roof_drips_over_every_side():
    grid, x0, cell = _roof_grid()
    s = edges.find_drip_sites(grid, x0, cell, seed=1, street_half_x_m=100.0)
    assert len(s.area_m2) == 1 and s.area_m2[0] == pytest.approx(16 * 32 * cell * cell)
    assert len(s) > 10 and np.all(s.edge_y == 5.0) and np.all(s.land_y == 0.0)
    # Sites lie just outside the roof's outline, on all four sides.
    x_lo, x_hi = x0 + 40 * cell, x0 + 72 * cell
    z_lo, z_hi = 20 * cell, 36 * cell
    outside = (s.x < x_lo) | (s.x > x_hi) | (s.z < z_lo) | (s.z > z_hi)
    assert np.all(outside)
    assert {bool(v) for v in (s.x < x_lo).tolist()} == {True, False} and (s.z > z_hi).any() and (s.z < z_lo).any()
    # τ = (area / perimeter) / sheet-flow speed, the perimeter counted in edge cells.
    perimeter = 2 * (16 + 32) * cell
    assert s.drain_s[0] == pytest.approx(s.area_m2[0] / perimeter / edges.FILM_SPEED_M_S)
    assert np.all(np.diff(s.z) >= 0)


@pytest.mark.parametrize("height", [1.0, 12.0])
def test_no_drips_from_kerbs_or_guttered_roofs(height):
    grid, x0, cell = _roof_grid(height)
    assert len(edges.find_drip_sites(grid, x0, cell, street_half_x_m=100.0)) == 0


def test_only_the_street_side_is_kept_but_the_flow_is_shared_by_all():
    grid, x0, cell = _roof_grid()
    everywhere = edges.find_drip_sites(grid, x0, cell, seed=1, street_half_x_m=100.0)
    street = edges.find_drip_sites(grid, x0, cell, seed=1, street_half_x_m=0.0)
    assert len(street) < len(everywhere)
    np.testing.assert_array_equal(street.edges, everywhere.edges)


def test_reservoir_is_exact_for_any_step_and_conserves_water():
    r1 = flow.RoofReservoirs([100.0, 30.0], [60.0, 10.0])
    r2 = flow.RoofReservoirs([100.0, 30.0], [60.0, 10.0])
    r1.step(50.0, 8.0)
    for _ in range(5000):
        r2.step(0.01, 8.0)
    np.testing.assert_allclose(r1.storage_m3, r2.storage_m3, rtol=1e-9)
    # Steady state: what leaves is what falls on it.
    r1.step(1e5, 8.0)
    np.testing.assert_allclose(r1.outflow_m3_s, 8.0 / 3.6e6 * np.array([100.0, 30.0]), rtol=1e-9)
    # After the rain: e^(−t/τ), and everything held drips out eventually.
    held = r1.storage_m3.copy()
    r1.step(60.0, 0.0)
    np.testing.assert_allclose(r1.storage_m3, held * np.exp(-60.0 / np.array([60.0, 10.0])), rtol=1e-12)
    r3 = flow.RoofReservoirs([100.0], [60.0])
    r3.storage_m3 = held[:1].copy()
    dripped = 0.0
    for _ in range(20000):
        before = r3.storage_m3.copy()
        r3.step(0.1, 0.0)
        dripped += float((before - r3.storage_m3)[0])
    assert dripped == pytest.approx(held[0], rel=1e-6)


def test_fall_closed_form():
    vt = float(physics.terminal_velocity(4.5))
    for h in (0.5, 3.0, 6.0, 50.0):
        assert flow.fall_m(flow.fall_time_s(h, vt), vt) == pytest.approx(h, rel=1e-9)
    t = 1e-3
    assert flow.fall_m(t, vt) == pytest.approx(0.5 * physics.G_M_S2 * t * t, rel=1e-3)  # free fall at first
    assert flow.fall_speed_m_s(100.0, vt) == pytest.approx(vt)  # then terminal speed
    assert np.isfinite(flow.fall_m(1e6, vt))


def test_periods_and_landings_follow_the_outflow():
    diam = np.array([4.5])
    volume = math.pi / 6 * (4.5e-3) ** 3
    period = flow.site_periods_s(np.array([volume * 2.0 * 4]), np.array([4]), np.array([0]), diam)
    assert period[0] == pytest.approx(0.5)  # 2 drops/s per site
    n, momentum = flow.landings(0.0, 100.0, period, np.array([0.3]), np.array([5.0]), diam)
    assert abs(n[0] - 200) <= 1 and momentum[0] > 0.0
    dry = flow.site_periods_s(np.array([0.0]), np.array([4]), np.array([0]), diam)
    assert dry[0] == flow.MAX_PERIOD_S


def test_settled_roofs_keep_their_bits_and_the_outflow_follows_the_storage():
    """A step at the settled rate is skipped (S∞ + 0·e^(−dt/τ) is S∞): the same bits as the formula; another rate
    steps, and the kept outflow follows the new storage."""
    roofs = flow.RoofReservoirs([100.0, 30.0], [60.0, 10.0])
    roofs.settle(8.0)
    steady = 8.0 / 3.6e6 * roofs.area_m2 * roofs.drain_s
    want = steady + (roofs.storage_m3 - steady) * np.exp(-max(0.5, 0.0) / roofs.drain_s)
    roofs.step(0.5, 8.0)
    assert roofs.storage_m3.tobytes() == want.tobytes()
    assert roofs.total_outflow_m3_s() == float((roofs.storage_m3 / roofs.drain_s).sum())
    before = roofs.outflow_m3_s.copy()
    roofs.step(0.5, 2.0)
    assert not roofs._is_settled_at(2.0) and (roofs.storage_m3 < want).all()
    assert roofs.outflow_m3_s.tobytes() == (roofs.storage_m3 / roofs.drain_s).tobytes()
    assert (roofs.outflow_m3_s < before).all() and not roofs.outflow_m3_s.flags.writeable
