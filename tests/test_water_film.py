"""rain_core.water_film's fast paths: the packed one-gather sampling inside ``water_depths_mm`` and the per-frame
``film_depth_sampler`` give the reference's numbers bit for bit (the reference: each map sampled alone by
``rain_core.world.sample_heightmap``, the model's formulas as written in DESIGN §3)."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core import layout, water_film
from rain_core.gutter import gutter_depth_mm
from rain_core.world import sample_heightmap


def _reference(x, z, cracks, puddles, amount, seed, world, wetness, gutter_k):
    """(standing, film) mm, every map sampled alone, float64, in the model's own order of operations."""
    x, z = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64))
    standing, film = np.zeros(x.shape), np.zeros(x.shape)
    on = np.abs(x) <= water_film.ROAD_HALF_WIDTH_M
    xr, zr = x[on], z[on]
    h = sample_heightmap(world.road_heightmap, world.heightmap_extent_m, xr, zr)
    hs = sample_heightmap(water_film.smooth_heightmap_for(world), world.heightmap_extent_m, xr, zr)
    n = water_film.sample_road_map(water_film.puddle_noise(seed), xr, zr)
    shelter = water_film.sample_road_map(water_film.shelter_map_for(world), xr, zr)
    road = water_film._standing_water_mm(h, hs, n, shelter, cracks, puddles, amount)
    if gutter_k > 0.0:
        road = np.maximum(road, gutter_depth_mm(xr, zr, gutter_k))
    standing[on] = road
    film[on] = water_film.WET_FILM_MM * wetness * (1.0 - shelter)
    return standing, film


def _points(rng, n):
    x = rng.uniform(-9.0, 9.0, n)
    # The clamped columns' edges, the centre line, and the periods' seams along z.
    x[:40] = np.repeat([-7.0, 7.0, np.nextafter(7.0, 0.0), -np.nextafter(7.0, 0.0), 0.0], 8)
    z = rng.uniform(-2.0 * layout.PERIOD_M, 2.0 * layout.PERIOD_M, n)
    z[:30] = np.repeat([0.0, 48.0, layout.PERIOD_M, -layout.PERIOD_M, np.nextafter(48.0, 0.0), -0.01], 5)
    return x, z


@pytest.mark.parametrize("levels", [(1.0, 1.0, 1.0, 0, 1.0, 0.2), (0.4, 0.7, 0.5, 3, 0.3, 0.0),
                                    (0.0, 0.0, 0.5, 1, 0.0, 0.05), (1.0, 0.2, 0.9, 0, 1.0, 0.0)])
def test_fast_paths_give_the_references_bits(levels, kernel_path):
    cracks, puddles, amount, seed, wetness, gutter_k = levels
    world = water_film.default_world()
    x, z = _points(np.random.default_rng(seed + 5), 6000)
    ref_standing, ref_film = _reference(x, z, cracks, puddles, amount, seed, world, wetness, gutter_k)
    standing, film = water_film.water_depths_mm(x, z, cracks, puddles, amount, seed, world, wetness, gutter_k)
    assert np.array_equal(standing, ref_standing) and np.array_equal(film, ref_film)
    depth = water_film.film_depth_mm(x, z, cracks, puddles, amount, seed, world, wetness, gutter_k)
    assert np.array_equal(depth, np.maximum(ref_standing, ref_film))
    sampler = water_film.film_depth_sampler(cracks, puddles, amount, seed, world, wetness, gutter_k)
    assert np.array_equal(sampler(x, z), depth)
    on = np.abs(x) <= water_film.ROAD_HALF_WIDTH_M  # all points on the road: the sampler's no-scatter branch
    assert np.array_equal(sampler(x[on], z[on]), depth[on])
    assert np.array_equal(sampler(x[:100].reshape(4, 25), z[:100].reshape(4, 25)), depth[:100].reshape(4, 25))
    off = np.array([8.0, -7.5])
    assert np.array_equal(sampler(off, np.array([1.0, 2.0])), np.zeros(2))


def test_shapes_and_scalars_are_kept(kernel_path):
    world = water_film.default_world()
    standing, film = water_film.water_depths_mm(1.75, np.array([[10.0, 20.0], [30.0, 40.0]]), 1.0, 1.0,
                                                world=world, wetness=1.0)
    assert standing.shape == film.shape == (2, 2)
    one = water_film.water_depths_mm(1.75, 10.0, 1.0, 1.0, world=world, wetness=1.0)
    assert one[0].shape == () and one[0] == standing[0, 0] and one[1] == film[0, 0]


def test_the_sampler_checks_its_arguments_once():
    with pytest.raises(ValueError, match="puddles"):
        water_film.film_depth_sampler(0.5, 1.5)
    with pytest.raises(ValueError, match="wetness"):
        water_film.film_depth_sampler(0.5, 0.5, wetness=-0.1)


def test_kernels_give_the_twins_bits_at_far_and_non_finite_z():
    """The compiled sampler's row arithmetic (a float modulo below 2^52 rows, int64's beyond, none for NaN and
    ±inf) gives the twin's depths, NaN included, and reads no row outside its table."""
    from rain_core import jit

    if not jit.AVAILABLE:
        pytest.skip("Numba not installed")
    world = water_film.default_world()
    x = np.array([1.0, 2.0, 3.0, 1.5, -4.0, 6.9, 0.3])
    z = np.array([np.nan, np.inf, -np.inf, 1e17, -3e14, 2.5e8, -1e300])
    got, want = [], []
    for on, out in ((True, got), (False, want)):
        with jit.forced(on), np.errstate(invalid="ignore"):
            out.extend(water_film.water_depths_mm(x, z, 1.0, 1.0, wetness=0.5, world=world, gutter_k=0.1))
            out.append(water_film.film_depth_sampler(1.0, 1.0, world=world, gutter_k=0.1)(x, z))
    for g, w in zip(got, want, strict=True):
        assert g.tobytes() == w.tobytes()


def test_small_queries_take_the_dry_test_and_give_the_references_bits(kernel_path):
    """With the kernels on, queries of any size take the dry-cell test (below DRY_TEST_MIN_POINTS too): a few
    wheels or a frame's landings on standing water and kerb streams give the reference's depths."""
    world = water_film.default_world()
    x, z = _points(np.random.default_rng(21), 2000)
    for n in (1, 5, 64, 65, 300, water_film.DRY_TEST_MIN_POINTS - 1):
        xs, zs = x[-n:], z[-n:]
        for levels in ((1.0, 1.0, 0.5, 0, 0.0, 0.1), (0.6, 0.3, 1.0, 2, 0.0, 0.0)):
            standing, film = _reference(xs, zs, *levels[:3], levels[3], world, levels[4], levels[5])
            sampler = water_film.film_depth_sampler(*levels[:4], world, levels[4], levels[5])
            assert np.array_equal(sampler(xs, zs), np.maximum(standing, film))


def test_wet_queries_of_any_size_give_the_references_bits(kernel_path):
    """With the wet film (the compiled path samples, makes the film and finds the kerb band in one loop): queries
    either side of KERB_BAND_MIN_POINTS, all on the asphalt or not, 2-D and scalar, give the reference's depths."""
    world = water_film.default_world()
    x, z = _points(np.random.default_rng(33), 2000)
    x[-700:] = np.clip(x[-700:], -6.99, 6.99)  # the last points all on the asphalt, many in the kerb band
    band = water_film.KERB_BAND_MIN_POINTS
    for n in (1, 7, band - 1, band, band + 1, 640):
        xs, zs = x[-n:], z[-n:]
        for levels in ((1.0, 1.0, 0.5, 0, 1.0, 0.1), (0.6, 0.3, 1.0, 2, 0.4, 0.0), (0.0, 0.9, 0.5, 1, 0.7, 0.03)):
            standing, film = _reference(xs, zs, *levels[:3], levels[3], world, levels[4], levels[5])
            got = water_film.water_depths_mm(xs, zs, *levels[:4], world, levels[4], levels[5])
            assert np.array_equal(got[0], standing) and np.array_equal(got[1], film)
            sampler = water_film.film_depth_sampler(*levels[:4], world, levels[4], levels[5])
            assert np.array_equal(sampler(xs, zs), np.maximum(standing, film))
        mixed = slice(0, n)  # the first points: some off the asphalt
        standing, film = _reference(x[mixed], z[mixed], 1.0, 1.0, 0.5, 0, world, 1.0, 0.1)
        assert np.array_equal(water_film.film_depth_sampler(1.0, 1.0, 0.5, 0, world, 1.0, 0.1)(x[mixed], z[mixed]),
                              np.maximum(standing, film))
    grid = water_film.water_depths_mm(x[-60:].reshape(6, 10), z[-60:].reshape(6, 10), 1.0, 1.0, 0.5, 0, world, 1.0,
                                      0.1)
    flat = _reference(x[-60:], z[-60:], 1.0, 1.0, 0.5, 0, world, 1.0, 0.1)
    for g, f in zip(grid, flat, strict=True):
        assert g.shape == (6, 10) and np.array_equal(g.reshape(-1), f)


def test_grid_queries_give_the_points_bits(kernel_path):
    """A grid given as views (a row of x down every column, a column of z along every row: the ripples' strips)
    takes the compiled grid sampler: the depths of the same points asked one by one, kerb streams included, over
    the asphalt's edges, the kerb bands, the periods' seams and far z (whose rows go to the fallback)."""
    world = water_film.default_world()
    rng = np.random.default_rng(8)
    x = np.concatenate([np.linspace(-9.0, 9.0, 301), [-7.0, 7.0, np.nextafter(7.0, 0.0), -np.nextafter(7.0, 0.0),
                                                      0.0, -0.0, 6.5, -6.5]])
    seams = [0.0, 48.0, 25.0, 50.0, layout.PERIOD_M, -layout.PERIOD_M, np.nextafter(48.0, 0.0), -0.01]
    z = np.concatenate([rng.uniform(-2.0 * layout.PERIOD_M, 2.0 * layout.PERIOD_M, 400), seams])
    for levels in ((1.0, 1.0, 0.5, 0, 0.0, 0.1), (0.6, 0.3, 1.0, 2, 0.0, 0.0), (1.0, 0.0, 0.5, 1, 0.0, 0.3)):
        sampler = water_film.film_depth_sampler(*levels[:4], world, levels[4], levels[5])
        for zs in (z, z[:1], np.array([3e9, 1.0]), np.array([np.nan, 2.0])):
            for xs in (x, x[:1], np.array([8.0, -9.0])):
                shape = (zs.size, xs.size)
                with np.errstate(invalid="ignore"):  # the NaN row
                    want = sampler(np.ascontiguousarray(np.broadcast_to(xs, shape)),
                                   np.ascontiguousarray(np.broadcast_to(zs[:, None], shape)))
                    got = sampler(np.broadcast_to(xs, shape), np.broadcast_to(zs[:, None], shape))
                assert got.shape == shape and got.tobytes() == want.tobytes()
        if levels[4] == 0.0:
            flat = _reference(np.broadcast_to(x, (z.size, x.size)), np.broadcast_to(z[:, None], (z.size, x.size)),
                              *levels[:3], levels[3], world, levels[4], levels[5])[0]
            assert np.array_equal(sampler(np.broadcast_to(x, flat.shape), np.broadcast_to(z[:, None], flat.shape)),
                                  flat)
