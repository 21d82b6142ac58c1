"""Stateless raindrops (issue 13): the impulse vertex shader makes a frame's drops from a hash, the NumPy twin
(``raindrops.py``) makes the same ones, and their count and spread follow the rain rate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.ripples.constants import MIN_FOOTPRINT_CELLS
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.raindrops import (
    RainBatch,
    drop_law,
    pcg,
    pcg_int,
    rain_key,
    raindrop_quantiles,
    raindrop_sites,
    raindrops,
)


def test_pcg_twin_matches_python_integers():
    v = np.array([0, 1, 2, 12345, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF], np.uint32)
    assert [int(h) for h in pcg(v)] == [pcg_int(int(x)) for x in v]
    assert rain_key(3, 1) != rain_key(3, 2) != rain_key(4, 2)


@pytest.mark.parametrize("n", [16, 513, 4096])
def test_sites_are_interior_cells_with_exact_offsets(n):
    ix, iz, x, z = raindrop_sites(rain_key(1, 7), 50_000, n)
    for cell, pos in ((ix, x), (iz, z)):
        assert cell.min() >= 1 and cell.max() <= n - 2
        assert np.all(np.abs(pos - cell) <= 0.5)
        np.testing.assert_array_equal(pos.astype(np.float32), pos)  # what the shader holds exactly


def test_drops_on_water_follow_the_rate_and_spread_uniformly():
    """Uncapped frames: the drops on water per frame average flux × water area × dt, with a Poisson spread, and
    they fall uniformly over the water cells (χ² over 4×4 blocks) and nowhere else."""
    n = 66  # 64 interior cells per side
    field = RippleField(n=n, extent_m=6.5, backend="numpy32", seed=5)
    field.recenter(0.0, 0.0)
    water = np.zeros((n, n), bool)
    water[:, :33] = True  # interior columns 1 … 32: half the interior
    field.set_water_mask(water)
    rate, dt, frames = 8.0, 1 / 60, 60
    counts, hits = [], np.zeros((n, n))
    for _ in range(frames):
        batch = field.rain_batch(rate, dt)
        _, xs, zs, _, dents = raindrops(batch, n, field.cell_m, field.solver.water_mask)
        assert batch.peak_per_momentum == pytest.approx(-field.rain_gain * 37.0)  # uncapped: weight 1
        counts.append(xs.size)
        np.add.at(hits, (np.rint(zs / field.cell_m).astype(int), np.rint(xs / field.cell_m).astype(int)), 1)
        assert np.all(dents < 0.0)
    expected = physics.flux_horizontal_per_m2_s(rate) * 64 * 32 * field.cell_m ** 2 * dt
    mean = np.mean(counts)
    assert mean == pytest.approx(expected, abs=5 * math.sqrt(expected / frames))
    assert np.var(counts) == pytest.approx(expected, rel=0.5)  # Poisson: variance = mean
    assert hits[~water].sum() == 0 and hits[0].sum() == hits[-1].sum() == 0
    blocks = hits[1:-1, 1:33].reshape(16, 4, 8, 4).sum(axis=(1, 3)).ravel()  # 128 blocks of 16 cells
    e = blocks.mean()
    chi2 = float(((blocks - e) ** 2 / e).sum())
    assert chi2 < 127 + 5 * math.sqrt(2 * 127)  # 127 degrees of freedom


def test_capped_frames_put_about_the_budget_on_water():
    field = RippleField(n=130, extent_m=12.9, backend="numpy32", seed=2, max_drops_per_frame=500)
    field.recenter(0.0, 0.0)
    water = np.zeros((130, 130), bool)
    water[:, :33] = True  # a quarter of the interior
    field.set_water_mask(water)
    laid = [field.add_raindrops(50.0, 1 / 30) for _ in range(20)]
    assert np.mean(laid) == pytest.approx(500, rel=0.1)


@pytest.fixture
def gpu_field(gl_ctx, shaders):
    from rain_core.effects.ripples.backend import make_field

    made = []

    def make(**kwargs):
        field = make_field(gl_ctx, backend="gpu", shaders=shaders, **kwargs)
        made.append(field)
        return field

    yield make
    for field in made:
        field.release()


@pytest.mark.parametrize("n, extent, rate", [(64, 6.3, 20.0), (512, 25.0, 8.0)])
def test_gpu_raindrops_equal_the_numpy_twin(gpu_field, n, extent, rate):
    """The shader's bumps (read back by transform feedback) against the twin's: the same drops on water, the
    same centres exactly, the same widened radius and peak within float32 roundoff (1e-4 relative), over
    several frames of a field with dry cells."""
    field = gpu_field(n=n, extent_m=extent, seed=9)
    field.recenter(0.0, 0.0)
    water = np.ones((n, n), bool)
    water[: n // 3, n // 2:] = False
    field.set_water_mask(water)
    solver, h = field.solver, field.cell_m
    for _ in range(3):
        batch = field.rain_batch(rate, 1 / 30)
        got = solver.raindrop_bumps(batch).astype(np.float64)
        index, xs, zs, radii, dents = raindrops(batch, n, h, solver.water_mask)
        assert batch.count > 1000 and index.size > 0.5 * batch.count
        np.testing.assert_array_equal(np.flatnonzero(got[:, 3] != 0.0), index)
        r_eff = np.maximum(radii, MIN_FOOTPRINT_CELLS * h)
        want = np.column_stack([xs / h, zs / h, r_eff / h, dents * (radii / r_eff) ** 2])
        g = got[index]
        _, _, x, z = raindrop_sites(batch.key, batch.count, n)
        np.testing.assert_array_equal(g[:, 0], x[index])  # exact: integer cell + 12-bit offset
        np.testing.assert_array_equal(g[:, 1], z[index])
        np.testing.assert_allclose(g[:, :2], want[:, :2], rtol=1e-12)
        np.testing.assert_allclose(g[:, 2:], want[:, 2:], rtol=1e-4)


def test_gpu_field_rain_equals_the_numpy_field(gpu_field):
    """Whole frames of rain and wakes on the GPU field and on the float32 NumPy field with the same seed: the same
    heights (the GPU makes its drops, the NumPy field lays the twin's)."""
    n, extent = 96, 9.5

    def film(x, z):
        return np.where(np.sin(1.1 * np.asarray(x)) + np.cos(0.8 * np.asarray(z)) > 0.2, 3.0, 0.0)

    fields = [gpu_field(n=n, extent_m=extent, seed=4), RippleField(n=n, extent_m=extent, backend="numpy32", seed=4)]
    for field in fields:
        field.solver.sleep_energy = 0.0
        for frame in range(12):
            wheels = [((-3.0 + 0.3 * frame, 0.4), (-2.7 + 0.3 * frame, 0.4), 8.0, None, 0.2)]
            field.update(1 / 30, center_xz=(0.1 * frame, 0.0), rate_mm_h=30.0, wheels=wheels, film_depth_fn=film)
    gpu, cpu = (f.height.astype(np.float64) for f in fields)
    scale = np.max(np.abs(cpu))
    assert scale > 0.0
    assert np.max(np.abs(gpu - cpu)) < 1e-4 * scale


def test_twin_quantiles_are_the_law():
    law = drop_law(8.0)
    key = rain_key(0, 1)
    u = raindrop_quantiles(key, np.arange(200_000))
    assert 0.0 <= u.min() and u.max() < 1.0
    assert abs(u.mean() - 0.5) < 0.005
    batch = RainBatch(key, 200_000, -1.0, 2.5e-3, law)
    _, _, _, radii, _ = raindrops(batch, 64, 0.1)
    d = radii / 2.5e-3
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 20001)
    density = np.gradient(np.asarray(physics.drop_diameter_cdf(grid, 8.0)), grid)
    flux = density * np.asarray(physics.terminal_velocity(grid))
    assert d.mean() == pytest.approx(np.trapezoid(grid * flux, grid) / np.trapezoid(flux, grid), rel=0.005)
