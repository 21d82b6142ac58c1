"""The water film the ripples ask about strip by strip (issue 13): ``sample_heightmap`` reads several maps on one
grid with one set of indices and ``water_depths_mm`` samples its four maps that way. Both must stay bit-identical
to sampling each map alone with the previous code, kept here as the reference."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core import layout
from rain_core.gutter import gutter_depth_mm
from rain_core.water_film import (
    PUDDLE_NOISE_WEIGHT,
    ROAD_HALF_WIDTH_M,
    WET_FILM_MM,
    _packed_grids,
    _standing_water_mm,
    default_world,
    film_depth_sampler,
    puddle_noise,
    shelter_map_for,
    smooth_heightmap_for,
    water_depths_mm,
)
from rain_core.world import sample_heightmap


def reference_sample(hmap, extent_m, x, z):
    """sample_heightmap as it was before the maps were sampled together (fancy indexing, astype, np.clip)."""
    nz, nx = hmap.shape
    fx = (np.asarray(x, dtype=np.float64) + extent_m[0] / 2) / extent_m[0] * nx - 0.5
    fz = np.asarray(z, dtype=np.float64) / extent_m[1] * nz - 0.5
    fx, fz = np.broadcast_arrays(fx, fz)
    i0 = np.floor(fx)
    j0 = np.floor(fz)
    tx = fx - i0
    tz = fz - j0
    i0 = i0.astype(np.int64)
    j0 = j0.astype(np.int64)
    ia = np.clip(i0, 0, nx - 1)
    ib = np.clip(i0 + 1, 0, nx - 1)
    ja = np.mod(j0, nz)
    jb = np.mod(j0 + 1, nz)
    top = hmap[ja, ia].astype(np.float64) * (1 - tx) + hmap[ja, ib].astype(np.float64) * tx
    bot = hmap[jb, ia].astype(np.float64) * (1 - tx) + hmap[jb, ib].astype(np.float64) * tx
    return top * (1 - tz) + bot * tz


def reference_depths(x_m, z_m, cracks, puddles, puddle_amount, seed, world, wetness):
    """water_depths_mm with each map sampled alone by the reference sampler."""
    x, z = np.broadcast_arrays(np.asarray(x_m, np.float64), np.asarray(z_m, np.float64))
    standing, film = np.zeros(x.shape), np.zeros(x.shape)
    on = np.abs(x) <= ROAD_HALF_WIDTH_M
    xr, zr = x[on], z[on]
    road = (2 * ROAD_HALF_WIDTH_M, layout.PERIOD_M)
    h = reference_sample(world.road_heightmap, world.heightmap_extent_m, xr, zr)
    hs = reference_sample(smooth_heightmap_for(world), world.heightmap_extent_m, xr, zr)
    n = reference_sample(puddle_noise(seed), road, xr, zr)
    shelter = reference_sample(shelter_map_for(world), road, xr, zr)
    standing[on] = _standing_water_mm(h, hs, n, shelter, cracks, puddles, puddle_amount)
    film[on] = WET_FILM_MM * wetness * (1.0 - shelter)
    return standing, film


def points(rng, count):
    # Across the road and beyond its edges, along several periods, negative z included; plus texel corners.
    x = rng.uniform(-9.0, 9.0, count)
    z = rng.uniform(-1.5 * layout.PERIOD_M, 2.5 * layout.PERIOD_M, count)
    x[:200] = np.round(x[:200] / 0.05) * 0.05
    z[:200] = np.round(z[:200] / 0.05) * 0.05
    return x, z


def test_several_maps_sample_exactly_as_each_alone():
    rng = np.random.default_rng(3)
    world = default_world()
    x, z = points(rng, 20_000)
    maps = (world.road_heightmap, smooth_heightmap_for(world), rng.random(world.road_heightmap.shape))
    together = sample_heightmap(maps, world.heightmap_extent_m, x, z)
    assert isinstance(together, tuple) and len(together) == 3
    for m, got in zip(maps, together, strict=True):
        np.testing.assert_array_equal(got, reference_sample(m, world.heightmap_extent_m, x, z))
        np.testing.assert_array_equal(sample_heightmap(m, world.heightmap_extent_m, x, z), got)
    # Scalars and broadcast shapes as before.
    assert sample_heightmap(maps[0], world.heightmap_extent_m, 1.0, 2.0) == \
        reference_sample(maps[0], world.heightmap_extent_m, 1.0, 2.0)
    grid = sample_heightmap(maps[0], world.heightmap_extent_m, x[:7, None], z[None, :5])
    np.testing.assert_array_equal(grid, reference_sample(maps[0], world.heightmap_extent_m, x[:7, None],
                                                         z[None, :5]))


@pytest.mark.parametrize("levels", [(1.0, 1.0, 0.5, 0, 0.0), (0.4, 0.7, 0.9, 3, 1.0), (0.0, 0.6, 0.3, 1, 0.5)])
def test_water_depths_are_bit_identical_to_sampling_each_map_alone(levels, kernel_path):
    cracks, puddles, amount, seed, wetness = levels
    world = default_world()
    x, z = points(np.random.default_rng(seed + 11), 20_000)
    got = water_depths_mm(x, z, cracks, puddles, amount, seed, world, wetness)
    want = reference_depths(x, z, cracks, puddles, amount, seed, world, wetness)
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    assert (got[0] > 0).any()


def test_water_depths_on_the_asphalt_only_and_in_any_shape(kernel_path):
    """Points all on the asphalt (the wheels) take the path without gather and scatter: still bit-identical, in
    the input's shape (a 2-D grid, a scalar)."""
    world = default_world()
    rng = np.random.default_rng(9)
    x, z = rng.uniform(-6.9, 6.9, (40, 25)), rng.uniform(0.0, 3 * layout.PERIOD_M, (40, 25))
    for args in ((x, z), (x[:, :1], z[:1, :]), (1.3, 71.2), (x[0], 55.0)):
        got = water_depths_mm(*args, 1.0, 1.0, 0.5, 0, world, 0.3)
        want = reference_depths(*args, 1.0, 1.0, 0.5, 0, world, 0.3)
        for g, w in zip(got, want, strict=True):
            assert np.shape(g) == np.shape(w)
            np.testing.assert_array_equal(g, w)


def reference_film_depth(x, z, cracks, puddles, amount, seed, world, gutter_k):
    """film_depth_mm without the wet film, each map sampled alone: max(standing, +0 film), the sign of zero kept."""
    standing, film = reference_depths(x, z, cracks, puddles, amount, seed, world, 0.0)
    if gutter_k > 0.0:
        on = np.abs(x) <= ROAD_HALF_WIDTH_M
        standing[on] = np.maximum(standing[on], gutter_depth_mm(x[on], z[on], gutter_k))
    return np.maximum(standing, film)


def edge_points(rng, count):
    """Points on and a few ulps either side of the heightmap's texel edges (which include the puddle map's), across
    the road, its kerbs and beyond."""
    x, z = points(rng, count)
    x[:count // 2] = np.round(x[:count // 2] / 0.05) * 0.05
    z[:count // 2] = np.round(z[:count // 2] / 0.05) * 0.05
    x[: count // 4] = x[: count // 4] + rng.integers(-3, 4, count // 4) * 2e-15
    z[: count // 4] = z[: count // 4] * (1.0 + rng.integers(-3, 4, count // 4) * 2.3e-16)
    x[-40:] = np.repeat([-7.0, 7.0, np.nextafter(7.0, 0.0), -np.nextafter(7.0, 0.0)], 10)
    return x, z


@pytest.mark.parametrize("levels", [(1.0, 1.0, 0.5, 0, 0.17), (0.4, 0.7, 0.9, 3, 0.0), (0.0, 0.3, 0.3, 1, 0.4),
                                    (1.0, 0.0, 0.5, 0, 0.0), (0.0, 0.0, 0.5, 2, 0.05)])
def test_the_sampler_without_film_skips_only_dry_cells(levels, kernel_path):
    """Without the wet film (the road's film function) the sampler samples only where the dry-cell table allows
    standing water or a kerb stream: the same bits as sampling every map at every point (zeros' signs too), for
    flat points, the ripples' strips (rows × columns, with the wheels' few points), texel edges and far z."""
    cracks, puddles, amount, seed, gutter_k = levels
    world = default_world()
    sampler = film_depth_sampler(cracks, puddles, amount, seed, world, 0.0, gutter_k)
    x, z = edge_points(np.random.default_rng(seed + 21), 20_000)
    want = reference_film_depth(x, z, cracks, puddles, amount, seed, world, gutter_k)
    got = sampler(x, z)
    assert got.tobytes() == want.tobytes()
    assert sampler(x.reshape(100, 200), z.reshape(100, 200)).tobytes() == want.tobytes()
    if cracks or puddles:
        assert (want > 0).mean() > 0.01  # a real test: water among the points
    cols, rows = np.arange(-256, 256) * 0.049, 1234.5 + np.arange(19) * 0.049
    xs, zs = np.meshgrid(cols, rows)
    xs = np.concatenate([xs.reshape(-1), [1.2, -1.2, 6.9]])
    zs = np.concatenate([zs.reshape(-1), [1235.0, 1236.0, 1237.0]])
    assert sampler(xs, zs).tobytes() == reference_film_depth(xs, zs, cracks, puddles, amount, seed, world,
                                                             gutter_k).tobytes()
    far = z + 3e8  # beyond the dry-cell test's rows: every point sampled
    assert sampler(x, far).tobytes() == reference_film_depth(x, far, cracks, puddles, amount, seed, world,
                                                             gutter_k).tobytes()


def test_the_dry_cell_floors_lie_below_every_sample_in_their_cell():
    """The dry-cell table's floors bound the sampled height and puddle ground from below at any point of the
    cell, texel edges and the clamped columns included (what makes skipping a cell exact)."""
    world = default_world()
    floors = _packed_grids(0, world).dry_floors()
    x, z = edge_points(np.random.default_rng(5), 200_000)
    on = np.abs(x) <= ROAD_HALF_WIDTH_M
    x, z = x[on], z[on]
    h = sample_heightmap(world.road_heightmap, world.heightmap_extent_m, x, z)
    hs = sample_heightmap(smooth_heightmap_for(world), world.heightmap_extent_m, x, z)
    n = reference_sample(puddle_noise(0), (2 * ROAD_HALF_WIDTH_M, layout.PERIOD_M), x, z)
    ground = (1.0 - PUDDLE_NOISE_WEIGHT) * hs + PUDDLE_NOISE_WEIGHT * n
    nz, nx = puddle_noise(0).shape
    cell = (np.mod(np.floor(z / layout.PERIOD_M * nz), nz) * nx
            + np.minimum(np.floor((x + ROAD_HALF_WIDTH_M) / (2 * ROAD_HALF_WIDTH_M) * nx), nx - 1)).astype(int)
    assert (h >= floors[0][cell]).all() and (ground >= floors[1][cell]).all()
    # Tight enough to matter: most of the road is ruled out at full flood.
    assert (floors[1] > 0.5).mean() > 0.3
