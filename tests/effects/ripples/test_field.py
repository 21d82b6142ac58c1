"""The ripple field around the car without OpenGL (issue 5): world anchoring, wakes, raindrops, the film mask."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.wheels import WheelSweep


def test_field_is_world_anchored():
    field = RippleField(n=64, extent_m=6.3, backend="reference", recenter_margin_cells=1)
    field.recenter(0.0, 0.0)
    field.solver.add_impulse(*(np.array([1.0, 2.0]) - field.origin_xz), 0.2, 1e-3)  # world (1, 2)
    field.solver.sleep_energy = 0.0

    def peak_world():
        z = field.height
        iz, ix = np.unravel_index(np.argmax(z), z.shape)
        return field.origin_xz[0] + ix * field.cell_m, field.origin_xz[1] + iz * field.cell_m

    assert peak_world() == pytest.approx((1.0, 2.0), abs=field.cell_m)
    shift = field.recenter(0.77, -0.52)
    assert shift != (0, 0)
    assert peak_world() == pytest.approx((1.0, 2.0), abs=field.cell_m)
    fx, fz = field.world_to_cell(1.0, 2.0)
    assert field.height[round(float(fz)), round(float(fx))] == pytest.approx(field.height.max())
    field.recenter(100.0, 0.0)  # far away: everything left the window, at rest
    assert np.all(field.height == 0.0)


def test_wheel_sweep_leaves_a_continuous_wake():
    field = RippleField(n=128, extent_m=12.7, backend="reference")
    field.recenter(0.0, 0.0)
    laid = field.add_wheel_sweep((-3.0, 0.5), (3.0, 0.5), speed_m_s=20.0, film_depth_mm=5.0, tire_width_m=0.2)
    assert laid >= math.floor(6.0 / field.cell_m + 1e-9)
    z = field.height
    fx0, fz = field.world_to_cell(-2.5, 0.5)
    fx1, _ = field.world_to_cell(2.5, 0.5)
    row = z[round(float(fz)), round(float(fx0)):round(float(fx1))]
    expected = 5e-3 * 20.0 / 10.0  # film depth × speed / 10 m/s
    assert np.all(row < -0.5 * expected)
    assert row.min() > -1.5 * expected
    assert field.add_wheel_sweep((-3.0, 0.5), (3.0, 0.5), 0.0, 5.0, 0.2) == 0  # standing still
    assert field.add_wheel_sweep((50.0, 50.0), (60.0, 50.0), 20.0, 5.0, 0.2) == 0  # outside the window


def test_raindrops_poisson_seeded_and_only_on_water():
    from rain_core import physics

    def run(seed):
        field = RippleField(n=64, extent_m=6.3, backend="numpy32", seed=seed)
        field.recenter(0.0, 0.0)
        depth = np.zeros((64, 64))
        depth[:, :32] = 3.0
        field.set_water_mask(depth)
        counts = [field.add_raindrops(5.0, 1 / 60) for _ in range(30)]
        return field, counts

    a, counts = run(3)
    b, _ = run(3)
    np.testing.assert_array_equal(a.height, b.height)
    assert np.all(a.height[:, 32:] == 0.0)
    assert np.any(a.height[:, :32] < 0.0)
    water_area = 62 * 31 * a.cell_m ** 2
    expected = physics.flux_horizontal_per_m2_s(5.0) * water_area / 60
    assert np.mean(counts) == pytest.approx(expected, rel=5 * math.sqrt(expected * 30) / (expected * 30) + 0.01)
    assert a.add_raindrops(0.0, 1 / 60) == 0


def test_raindrop_budget_keeps_momentum_flux():
    """A capped frame's drops carry the momentum of all of them: the total dent agrees with the uncapped one.
    The capped sum is a mean of budget × frames momenta of a heavy-tailed law (the big drops dominate: ~20 %
    spread with 64 × 20), so the test takes 256 × 60 (~6 %) and allows 20 %."""
    def total_dent(budget):
        field = RippleField(n=64, extent_m=6.3, backend="reference", seed=11,
                            max_drops_per_frame=budget)
        field.recenter(0.0, 0.0)
        for _ in range(60):
            field.add_raindrops(20.0, 1 / 30)
        return field.height.sum()

    full, capped = total_dent(10**6), total_dent(256)
    assert capped == pytest.approx(full, rel=0.2)


def test_field_update_with_film_depth_fn():
    field = RippleField(n=64, extent_m=6.3, backend="numpy32", seed=2)

    def film(x, z):
        return np.where(x > 0.5, 4.0, 0.0)  # mm: water east of x = 0.5 m

    wheels = [WheelSweep((-2.0, 0.0), (2.0, 0.0), 15.0, 0.2, None), ((1.0, -1.0), (1.5, -1.0), 5.0, 3.0, 0.2)]
    stats = field.update(1 / 60, center_xz=(0.0, 0.0), rate_mm_h=2.0, wheels=wheels, film_depth_fn=film)
    assert stats["substeps"] >= 1 and stats["wake_bumps"] > 0
    xs, _ = field.cell_centres_xz()
    assert np.all(field.height[xs <= 0.5] == 0.0)
    assert np.any(field.height[xs > 0.5] != 0.0)
    with pytest.raises(ValueError):
        field.update(1 / 60, wheels=[WheelSweep((0, 0), (1, 0), 5.0, 0.2, None)])


def test_film_depth_followed_with_strips_and_bands():
    """After a scroll only the entering cells are asked; each frame re-asks a band of rows; the mask always
    equals the function's verdict on the current window."""
    asked = []
    puddle_x = [0.5]

    def film(x, z):
        asked.append(np.size(x))
        return np.where(np.asarray(x) > puddle_x[0], 4.0, 0.0)

    n = 64
    field = RippleField(n=n, extent_m=6.3, backend="numpy32", recenter_margin_cells=1, mask_refresh_s=0.5)
    field.update(1 / 60, center_xz=(0.0, 0.0), film_depth_fn=film)
    assert asked == [n * n]
    asked.clear()
    field.update(1 / 60, center_xz=(0.31, 0.0), film_depth_fn=film)  # 3 cells east
    assert sum(asked) < 8 * n  # the 3 new columns and a band of rows, not the window
    xs, _ = field.cell_centres_xz()
    np.testing.assert_array_equal(field.solver.water_mask > 0.5, xs > 0.5)
    puddle_x[0] = 1.0  # the puddle shrinks: within mask_refresh_s every row has been re-asked
    for _ in range(31):
        field.update(1 / 60, film_depth_fn=lambda x, z: film(x, z))  # a new function object every frame
    assert max(asked[-31:]) < n * n
    np.testing.assert_array_equal(field.solver.water_mask > 0.5, xs > 1.0)
    with pytest.raises(ValueError):
        field.refresh_water_mask(lambda x, z: np.full(np.shape(x), np.nan))


def test_arriving_drops_are_flux_weighted():
    """Drops reaching the water follow N(D)·v(D) (the fast, large drops arrive more often than their share
    of the air), not the airborne N(D)."""
    from rain_core import physics

    field = RippleField(n=16, extent_m=1.0, backend="numpy32", seed=0)
    rate = 10.0
    d = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 20001)
    density = np.gradient(np.asarray(physics.drop_diameter_cdf(d, rate)), d)
    flux = density * np.asarray(physics.terminal_velocity(d))
    expected = np.trapezoid(d * flux, d) / np.trapezoid(flux, d)
    airborne = np.trapezoid(d * density, d) / np.trapezoid(density, d)
    samples = field._flux_weighted_diameters(rate, 200_000)
    assert samples.mean() == pytest.approx(expected, rel=0.005)
    assert expected > 1.1 * airborne
