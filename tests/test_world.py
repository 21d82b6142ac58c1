"""The procedural street tile: determinism, geometry sanity, the road heightmap and the roof (occluder) map."""

import time

import numpy as np
import pytest

from rain_core import layout
from rain_core.mesh import (
    MAT_ASPHALT,
    MAT_CAR_PAINT,
    MAT_CONCRETE,
    MAT_EMISSIVE,
    MAT_GENERIC,
    MAT_GLASS,
    MAT_METAL,
    MAT_PAINT,
    MAT_RUBBER,
    VERTEX_DTYPE,
)
from rain_core.world import (
    HEIGHTMAP_TEXEL_M,
    OCCLUDER_HALF_X_M,
    World,
    build_world,
    make_road_heightmap,
    sample_heightmap,
)
from rain_core.world.kerbside import PARKED_INNER_X_M, SIGN_POST_X_M


@pytest.fixture(scope="module")
def world() -> World:
    t0 = time.perf_counter()
    w = build_world(seed=1)
    print(f"\nbuild_world(1): {time.perf_counter() - t0:.3f} s, {len(w.vertices) // 3} triangles, "
          f"{len(w.lamps)} lamps, {len(w.occluders.faces)} occluder triangles")
    return w


def test_same_seed_same_world_and_other_seed_differs(world):
    again = build_world(seed=1)
    assert again.vertices.tobytes() == world.vertices.tobytes()
    assert np.array_equal(again.road_heightmap, world.road_heightmap)
    assert np.array_equal(again.occluders.vertices, world.occluders.vertices)
    assert np.array_equal(again.occluder_map.grid, world.occluder_map.grid)
    assert [lamp.position.tolist() for lamp in again.lamps] == [lamp.position.tolist() for lamp in world.lamps]
    other = build_world(seed=2)
    assert other.vertices.tobytes() != world.vertices.tobytes()
    assert not np.array_equal(other.road_heightmap, world.road_heightmap)


def test_vertices_are_finite_triangles_with_unit_normals(world):
    v = world.vertices
    assert v.dtype == VERTEX_DTYPE
    assert len(v) % 3 == 0
    assert len(v) // 3 < 300_000
    for name in ("position", "normal", "albedo", "params"):
        assert np.isfinite(v[name]).all(), name
    np.testing.assert_allclose(np.linalg.norm(v["normal"], axis=1), 1.0, atol=1e-4)
    rough_metal = v["params"][:, :2]
    assert (rough_metal >= 0).all() and (rough_metal <= 1).all()
    lit = v["params"][:, 2] != MAT_EMISSIVE
    assert (v["albedo"][lit] >= 0).all() and (v["albedo"][lit] <= 1).all()


def test_flat_faces_wind_counter_clockwise_around_their_normal(world):
    tri = world.vertices["position"].reshape(-1, 3, 3).astype(np.float64)
    nrm = world.vertices["normal"].reshape(-1, 3, 3).astype(np.float64)
    flat = (np.abs(nrm - nrm[:, :1]).max(axis=(1, 2)) < 1e-6)
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(cross, axis=1)
    ok = flat & (area > 1e-8)
    assert ok.sum() > 0.5 * len(tri)
    cos = np.einsum("ij,ij->i", cross[ok] / area[ok, None], nrm[ok, 0])
    assert (cos > 0.999).all()


def test_road_surface_is_flat_at_zero_and_the_carriageway_is_clear(world):
    p = world.vertices["position"]
    mat = np.rint(world.vertices["params"][:, 2])
    road = p[mat == MAT_ASPHALT]
    assert len(road) > 0
    np.testing.assert_allclose(road[:, 1], 0.0, atol=1e-6)
    assert np.abs(road[:, 0]).max() <= layout.ROAD_HALF_WIDTH_M + 1e-5
    assert road[:, 2].min() <= 1e-3 and road[:, 2].max() >= layout.PERIOD_M - 1e-3
    paint = p[(mat == MAT_PAINT) & (np.abs(p[:, 0]) < layout.ROAD_HALF_WIDTH_M)]  # markings (signs are paint too)
    assert (paint[:, 1] > 0).all() and (paint[:, 1] < 0.01).all()
    # Over the traffic lanes nothing hangs below 4.5 m (trucks pass; bridge and canopy are higher); parked cars
    # stand up to 0.4 m into the gutter, no nearer the centre line than PARKED_INNER_X_M.
    over_road = (np.abs(p[:, 0]) < PARKED_INNER_X_M - 0.01) & (p[:, 1] > 0.01)
    assert p[over_road, 1].min() > 4.5
    gutter = (np.abs(p[:, 0]) < layout.ROAD_HALF_WIDTH_M - 0.05) & (p[:, 1] > 0.01) & (p[:, 1] < 4.5)
    assert np.all(np.isin(mat[gutter], [MAT_CAR_PAINT, MAT_GLASS, MAT_GENERIC, MAT_RUBBER, MAT_METAL]))
    # Kerb tops and sidewalks at kerb height.
    walk = (np.abs(p[:, 0]) > layout.ROAD_HALF_WIDTH_M + 0.05) & (np.abs(p[:, 0]) < 10.2)
    walk &= np.abs(world.vertices["normal"][:, 1] - 1.0) < 1e-6  # up-facing
    walk &= mat == MAT_CONCRETE  # not the parked cars' roofs
    assert np.median(p[walk, 1]) == pytest.approx(layout.KERB_HEIGHT_M, abs=1e-6)


def test_geometry_stays_in_its_tile_along_z(world):
    z = world.vertices["position"][:, 2]
    assert z.min() > -3.0 and z.max() < layout.PERIOD_M + 3.0


def test_heightmap_range_resolution_and_seamless_wrap(world):
    h = world.road_heightmap
    assert h.dtype == np.float32 and h.ndim == 2
    assert max(h.shape) <= 1024
    assert h.min() == 0.0 and h.max() == 1.0
    size_x, size_z = world.heightmap_extent_m
    assert size_x == pytest.approx(2 * layout.ROAD_HALF_WIDTH_M)
    assert (layout.PERIOD_M / size_z) == pytest.approx(round(layout.PERIOD_M / size_z))
    assert size_z / h.shape[0] == pytest.approx(HEIGHTMAP_TEXEL_M)
    assert size_x / h.shape[1] == pytest.approx(HEIGHTMAP_TEXEL_M)
    # Across the wrap (last row → first row) the map changes no more than between any two neighbouring rows.
    step = np.abs(np.diff(h.astype(np.float64), axis=0)).mean()
    seam = np.abs(h[0].astype(np.float64) - h[-1]).mean()
    assert seam < 1.5 * step


def test_ruts_and_gutters_are_lower_than_lane_centres(world):
    h = world.road_heightmap.astype(np.float64)
    col = lambda x: int((x + layout.ROAD_HALF_WIDTH_M) / HEIGHTMAP_TEXEL_M)  # noqa: E731
    for c in layout.LANE_CENTRES_X:
        centre = h[:, col(c)].mean()
        for off in (-0.9, 0.9):
            assert h[:, col(c + off)].mean() < centre - 0.05
    assert h[:, col(0.0)].mean() > h[:, col(6.9)].mean() + 0.1  # crown above the gutter


def test_cracks_are_lower_than_their_surroundings():
    h, cracks = make_road_heightmap(np.random.default_rng(7))
    core = cracks == 1.0
    assert 0.001 < core.mean() < 0.05
    near = np.zeros_like(core)
    for dz in range(-3, 4):
        for dx in range(-3, 4):
            near |= np.roll(np.roll(core, dz, axis=0), dx, axis=1)
    ring = near & (cracks == 0)
    assert h[core].mean() < h[ring].mean() - 0.3
    assert np.median(h[core]) < np.percentile(h, 5)


def test_road_height01_is_a_gl_style_bilinear_repeat_along_z(world):
    h = world.road_heightmap
    size_x, size_z = world.heightmap_extent_m
    nz, nx = h.shape
    dx = size_x / nx
    dz = size_z / nz
    i = np.array([0, 5, 140, nx - 1])
    j = np.array([0, 17, 500, nz - 1])
    xc = -size_x / 2 + (i + 0.5) * dx
    zc = (j + 0.5) * dz
    np.testing.assert_allclose(world.road_height01(xc[:, None], zc[None, :]), h[np.ix_(j, i)].T, atol=1e-6)
    # Halfway between two texel centres: the mean; across the wrap: between the last and the first row.
    assert world.road_height01(xc[2] + dx / 2, zc[2]) == pytest.approx((h[500, 140] + h[500, 141]) / 2, abs=1e-6)
    assert world.road_height01(xc[2], 0.0) == pytest.approx((h[0, 140] + h[-1, 140]) / 2, abs=1e-6)
    # Repeats along z (also over the world period), clamps across x.
    x = np.linspace(-7.5, 7.5, 37)
    z = np.linspace(0, size_z, 41)
    base = world.road_height01(x[:, None], z[None, :])
    np.testing.assert_allclose(world.road_height01(x[:, None], z[None, :] + size_z), base, atol=1e-6)
    np.testing.assert_allclose(world.road_height01(x[:, None], z[None, :] + layout.PERIOD_M), base, atol=1e-5)
    np.testing.assert_allclose(world.road_height01(x[:, None], z[None, :] - 3 * size_z), base, atol=1e-5)
    assert world.road_height01(-50.0, 3.0) == pytest.approx(world.road_height01(-size_x / 2, 3.0), abs=1e-6)
    assert sample_heightmap(h, (size_x, size_z), 1.0, 2.0) == world.road_height01(1.0, 2.0)


def test_occluder_height_under_roofs_and_open_road(world):
    zb, zc = layout.BRIDGE_Z_M, layout.CANOPY_Z_M
    deck_top = layout.BRIDGE_CLEARANCE_M + 1.0
    under_bridge = world.occluder_height(np.array([-6.0, 0.0, 3.0, 6.5]), zb)
    np.testing.assert_allclose(under_bridge, deck_top, atol=1e-4)
    assert (under_bridge > layout.BRIDGE_CLEARANCE_M).all()
    under_canopy = world.occluder_height(np.array([4.0, 6.0, 9.0, 14.0]), zc)
    assert np.isfinite(under_canopy).all()
    assert (under_canopy > layout.CANOPY_HEIGHT_M).all() and (under_canopy < layout.CANOPY_HEIGHT_M + 2).all()
    # Open road: nothing overhead (lamp heads are not occluders; parked cars stand beyond the traffic lanes).
    x = np.linspace(-PARKED_INNER_X_M + 0.15, PARKED_INNER_X_M - 0.15, 50)
    for z in (10.0, 150.0, 500.0, 1000.0):
        assert np.isneginf(world.occluder_height(x, z)).all()
    # Outside the canopy's x range, the other lanes are open.
    assert np.isneginf(world.occluder_height(np.array([-3.0, 1.0, 3.0]), zc)).all()
    # Periodic in z; the embankment far out is covered by the coarse map.
    np.testing.assert_allclose(world.occluder_height(0.0, zb + 5 * layout.PERIOD_M), deck_top, atol=1e-4)
    np.testing.assert_allclose(world.occluder_height(0.0, zb - layout.PERIOD_M), deck_top, atol=1e-4)
    assert world.occluder_height(150.0, zb) == pytest.approx(deck_top, abs=1e-4)
    assert np.isneginf(world.occluder_height(1000.0, zb))
    # Buildings line the street: most of a strip behind the façades is roofed.
    xs = np.concatenate([np.linspace(-25, -15, 11), np.linspace(15, 25, 11)])
    zs = np.linspace(0, layout.PERIOD_M, 400)
    zs = zs[np.abs(zs - zb) > 20]  # the railway embankment slopes down to the ground there
    roofs = world.occluder_height(xs[:, None], zs[None, :])
    assert 0.6 < np.isfinite(roofs).mean() < 1.0
    assert roofs[np.isfinite(roofs)].min() >= 3.0 and roofs[np.isfinite(roofs)].max() <= 30.0


def test_occluder_map_agrees_with_a_direct_drop_test_on_the_mesh(world):
    rng = np.random.default_rng(0)
    n = 400
    # Half the points near the underpass and the station, where the roofs are; half anywhere.
    x = rng.uniform(-OCCLUDER_HALF_X_M + 1, OCCLUDER_HALF_X_M - 1, n)
    z = np.concatenate([rng.uniform(270, 330, n // 4), rng.uniform(670, 750, n // 4),
                        rng.uniform(0, layout.PERIOD_M, n - n // 2)])
    tri = np.asarray(world.occluders.triangles, dtype=np.float64)
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = (tri[:, k].T for k in range(3))
    det = (z2 - z3) * (x1 - x3) + (x3 - x2) * (z1 - z3)
    keep = np.abs(det) > 1e-9
    x1, y1, z1, x2, y2, z2, x3, y3, z3, det = (a[keep] for a in (x1, y1, z1, x2, y2, z2, x3, y3, z3, det))
    px, pz = x[:, None], z[:, None]
    l1 = ((z2 - z3) * (px - x3) + (x3 - x2) * (pz - z3)) / det
    l2 = ((z3 - z1) * (px - x3) + (x1 - x3) * (pz - z3)) / det
    l3 = 1 - l1 - l2
    inside = (l1 >= 0) & (l2 >= 0) & (l3 >= 0)
    truth = np.where(inside, l1 * y1 + l2 * y2 + l3 * y3, -np.inf).max(axis=1)
    got = world.occluder_height(x, z)
    same_cover = np.isfinite(truth) == np.isfinite(got)
    assert np.isfinite(truth).sum() > 50
    assert same_cover.mean() > 0.97  # disagreements only within half a cell of a roof edge
    both = np.isfinite(truth) & np.isfinite(got)
    assert np.median(np.abs(truth[both] - got[both])) < 1e-3


def test_lamps_line_both_sides_at_street_light_height(world):
    street = [lamp for lamp in world.lamps if lamp.position[1] > 6.0]
    assert len(street) >= 50
    for side in (-1, 1):
        zs = np.sort([lamp.position[2] for lamp in street if np.sign(lamp.position[0]) == side])
        assert len(zs) >= 25
        gaps = np.diff(np.concatenate([zs, zs[:1] + layout.PERIOD_M]))
        assert gaps.min() > 25.0 and np.median(gaps) < 40.0
    for lamp in world.lamps:
        assert lamp.position.shape == (3,) and lamp.direction.shape == (3,) and lamp.color.shape == (3,)
        assert np.linalg.norm(lamp.direction) == pytest.approx(1.0)
        assert lamp.direction[1] < -0.9
        assert 500.0 <= lamp.intensity_cd <= 20000.0
        assert 0.2126 * lamp.color[0] + 0.7152 * lamp.color[1] + 0.0722 * lamp.color[2] == pytest.approx(1.0)
    for lamp in street:
        # Heads reach from the sidewalk poles over the road edge, 6–10 m up.
        assert 5.0 < abs(lamp.position[0]) < layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M
        assert 6.0 < lamp.position[1] < 10.0
    # Each light source sits just under an emissive lens.
    emissive = world.vertices["position"][np.rint(world.vertices["params"][:, 2]) == MAT_EMISSIVE]
    for lamp in world.lamps:
        d = np.linalg.norm(emissive - lamp.position, axis=1)
        assert d.min() < 0.5
    # The underpass and the canopy are lit too.
    assert any(abs(lamp.position[2] - layout.BRIDGE_Z_M) < 7 and lamp.position[1] < layout.BRIDGE_CLEARANCE_M
               for lamp in world.lamps)
    assert sum(abs(lamp.position[2] - layout.CANOPY_Z_M) < 12 and lamp.position[1] < layout.CANOPY_HEIGHT_M
               for lamp in world.lamps) >= 4


def test_detail_scales_tessellation_and_is_validated():
    low = build_world(seed=1, detail=0.5)
    high = build_world(seed=1, detail=2.0)
    assert len(low.vertices) < len(high.vertices)
    assert np.array_equal(low.road_heightmap, high.road_heightmap)
    with pytest.raises(ValueError, match="detail"):
        build_world(seed=1, detail=0.0)


def test_kerbside_parked_cars_signs_and_crossings(world):
    from rain_core.labels import CLASS_IDS, world_classes

    p = world.vertices["position"]
    cls = world_classes(world)
    # Parked cars: half on the sidewalk beside both kerbs, clear of the traffic lanes, inside the walls.
    cars = cls == CLASS_IDS["vehicle"]
    assert cars.sum() > 20_000
    assert np.abs(p[cars, 0]).min() >= PARKED_INNER_X_M - 1e-4
    assert np.abs(p[cars, 0]).max() < layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M
    assert p[cars, 1].min() > -0.05
    boxes = world.solid_boxes
    for side in (-1, 1):
        b = boxes[np.sign(boxes[:, 0]) == side]
        assert len(b) >= 10
        zs = np.sort(b[:, 2])
        assert np.all(np.diff(zs) > 3.0)  # no two cars overlap along the kerb
    # Every car box holds car vertices; none stands under the bridge or on the station's forecourt.
    zc = (boxes[:, 2] + boxes[:, 3]) / 2
    assert not np.any(np.abs(zc - layout.BRIDGE_Z_M) < 20.0)
    assert not np.any((boxes[:, 0] > 0) & (zc > layout.CANOPY_Z_M - 30.0) & (zc < layout.CANOPY_Z_M + 50.0))
    # Clear of the lamp posts, sign posts and trunks (solid circles) by their radius.
    c = world.solid_circles
    for x0, x1, z0, z1 in boxes:
        inside = ((c[:, 0] + c[:, 2] > x0) & (c[:, 0] - c[:, 2] < x1)
                  & (c[:, 1] + c[:, 2] > z0) & (c[:, 1] - c[:, 2] < z1))
        assert not inside.any()
    # Lights off: no emissive vertex among the parked cars.
    assert not np.any(np.rint(world.vertices["params"][cars, 2]) == MAT_EMISSIVE)
    # Signs: plates above head height at the sidewalk's edge, their posts solid.
    plates = cls == CLASS_IDS["traffic_sign"]
    assert plates.sum() > 500
    assert p[plates, 1].min() > 1.4 and p[plates, 1].max() < 4.0
    ax = np.abs(p[plates, 0])
    assert ax.min() > layout.ROAD_HALF_WIDTH_M and ax.max() < layout.ROAD_HALF_WIDTH_M + 3.3
    posts = c[np.isclose(np.abs(c[:, 0]), SIGN_POST_X_M)]
    assert len(posts) >= 8
    # Zebra crossings: white bars across the carriageway, just above the lane lines.
    marks = (cls == CLASS_IDS["marking"]) & (np.abs(p[:, 1] - 0.006) < 1e-4)
    assert marks.sum() >= 2 * 13 * 6


def test_kerbside_keeps_the_other_streams(world):
    # The kerbside's own streams come after the first four: the road, trees and buildings are what they were.
    from rain_core.world.street import _buildings, _road_and_streetside, _trees

    rng = np.random.default_rng(1)
    r_road, _, r_build, r_trees = (np.random.default_rng(s) for s in rng.bit_generator.seed_seq.spawn(4))
    road = _road_and_streetside(r_road)
    n = sum(len(a) for a in road)
    assert np.array_equal(world.vertices[:n], np.concatenate(road))
    trees, _ = _trees(r_trees, 8, 1)
    build, _, _ = _buildings(r_build, 1.0)
    v = world.vertices["position"]
    for parts in (trees, build):
        first = parts[0]["position"]
        hits = np.nonzero(np.all(v == first[0], axis=1))[0]
        assert any(np.array_equal(v[h:h + len(first)], first) for h in hits)


def test_scenes_share_one_read_only_street_per_seed():
    from rain_core.world import shared_world

    a, b = shared_world(seed=1), shared_world(seed=1)
    assert a is b and shared_world(seed=2) is not a
    with pytest.raises(ValueError):  # read-only: no scene can change another's street
        a.vertices["position"][0] = 0.0
    with pytest.raises(ValueError):
        a.occluder_map.grid[0, 0] = 1.0
    with pytest.raises(ValueError):
        a.lamps[0].position[1] = 0.0
    assert isinstance(a.lamps, tuple)
    private = build_world(seed=1)  # still a fresh, writable one
    assert private is not a and private.vertices.flags.writeable
    assert private.vertices.tobytes() == a.vertices.tobytes()


def test_occluder_height_at_one_point_is_the_array_lookup(world):
    """occluder_height_at (Python scalars, asked every frame by the windshield) gives occluder_height's answer:
    on the fine map, the coarse one, beyond both, at negative and far z (periodic)."""
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(-12.0, 12.0, 3000), rng.uniform(-160.0, 160.0, 1500)])
    z = rng.uniform(-2500.0, 2500.0, len(x))
    want = world.occluder_height(x, z)
    got = np.array([world.occluder_height_at(float(a), float(b)) for a, b in zip(x, z, strict=True)])
    assert np.array_equal(got, want)
    assert np.isfinite(want).sum() > 100 and np.isneginf(want).sum() > 100
