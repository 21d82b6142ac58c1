"""The film depths and the water mask kept up to date incrementally (strips after a scroll, rolling bands only
while the film function changes, the GPU mask shifted in place and written by blocks) equal a full
re-evaluation of the function over the current window (issue 13)."""

from __future__ import annotations

import numpy as np

from rain_core.effects.ripples.field import RAIN_FRACTION_STRIDE, RippleField
from rain_core.effects.ripples.water_mask import _runs

N = 48
EXTENT = 4.7  # m: cells of 0.1 m


class Film:
    """A film-depth function (mm) with puddles in both directions; ``cache_key`` names its levels."""

    def __init__(self, level: float, keyed: bool = True):
        self.level = level
        self.asked = 0
        if keyed:
            self.cache_key = ("test film", level)

    def __call__(self, x, z):
        x, z = np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)
        self.asked += x.size
        return np.maximum(0.0, np.sin(1.3 * x) + np.cos(0.7 * z + 0.4 * x) - self.level)


def full_evaluation(field: RippleField, film) -> RippleField:
    """A new field whose window is where ``field``'s is, its depths and mask evaluated in full."""
    fresh = RippleField(n=field.n, extent_m=field.extent_m, backend="reference")
    fresh._anchor, fresh._centred = field._anchor, True
    fresh.refresh_water_mask(film)
    return fresh


def assert_same_as_full(field: RippleField, film):
    fresh = full_evaluation(field, film)
    np.testing.assert_array_equal(field.solver.water_mask > 0.5, fresh.solver.water_mask > 0.5)
    mask = field.solver.water_mask  # exactly 0 or 1: the field compares asked strips with it as it is
    assert np.all((mask == 0) | (mask == 1))
    assert field._count_water() == fresh._count_water()  # what sizes the raindrop candidates
    # The rain's lattice count, from the rows' counts kept through scrolls and strips: the mask's own count.
    lattice = slice(1, field.n - 1, RAIN_FRACTION_STRIDE)
    assert field._count_water(RAIN_FRACTION_STRIDE) == (np.count_nonzero(mask[lattice, lattice]),
                                                        len(range(1, field.n - 1, RAIN_FRACTION_STRIDE)) ** 2)
    field._rain_water_fraction()
    assert not field._water_fraction_stale
    held = field.solver.water_mask < 0.5
    assert np.all(field.height[held] == 0.0)


# A drive in every direction: (dx, dz) in m per frame, scrolls of a few cells both ways and diagonally.
MOVES = [(0.0, 0.0), (0.0, 0.45), (0.0, 0.45), (0.33, 0.0), (-0.52, 0.21), (0.0, -0.6), (0.0, 0.0), (0.9, 0.9)]


def drive(field: RippleField, film, check):
    x = z = 0.0
    for dx, dz in MOVES * 2:
        x, z = x + dx, z + dz
        field.update(1 / 30, center_xz=(x, z), rate_mm_h=20.0, film_depth_fn=film)
        check()


def test_incremental_refresh_equals_full_after_scrolls():
    film = Film(0.4)
    field = RippleField(n=N, extent_m=EXTENT, backend="numpy32", recenter_margin_cells=2, seed=3)
    drive(field, film, lambda: assert_same_as_full(field, film))


def test_same_cache_key_asks_only_the_strips_that_entered():
    film = Film(0.4)
    field = RippleField(n=N, extent_m=EXTENT, backend="numpy32", recenter_margin_cells=1)
    field.update(1 / 30, center_xz=(0.0, 0.0), film_depth_fn=film)
    assert film.asked == N * N
    film.asked = 0
    parked = [Film(0.4) for _ in range(5)]  # a new function object each frame, with the same levels
    for f in parked:
        field.update(1 / 30, center_xz=(0.0, 0.0), film_depth_fn=f)
    assert sum(f.asked for f in parked) == 0  # parked, the same levels: nothing to ask
    moved = Film(0.4)
    report = field.update(1 / 30, center_xz=(0.3, 0.2), film_depth_fn=moved)
    dx, dz = report["shift"]
    assert dx > 0 and dz > 0
    assert moved.asked == dz * N + dx * (N - dz)  # the entering rows, then the entering columns' other cells
    assert_same_as_full(field, moved)


def test_level_change_renews_every_row_then_stops():
    field = RippleField(n=N, extent_m=EXTENT, backend="numpy32", mask_refresh_s=0.5)
    field.update(1 / 30, center_xz=(0.0, 0.0), film_depth_fn=Film(0.4))
    wetter = Film(0.1)  # the puddles grow: a new key, the rolling bands renew the window within 0.5 s
    for _ in range(16):
        field.update(1 / 30, film_depth_fn=wetter)
    assert_same_as_full(field, wetter)
    wetter.asked = 0
    field.update(1 / 30, film_depth_fn=wetter)
    assert wetter.asked == 0  # renewed: the same key asks nothing more


def test_unkeyed_function_keeps_rolling():
    field = RippleField(n=N, extent_m=EXTENT, backend="numpy32", mask_refresh_s=0.5)
    film = Film(0.4, keyed=False)
    field.update(1 / 30, center_xz=(0.0, 0.0), film_depth_fn=film)
    for _ in range(40):
        film.asked = 0
        field.update(1 / 30, film_depth_fn=film)
        assert 0 < film.asked < N * N  # a band every frame, as before
    assert_same_as_full(field, film)


def test_runs():
    assert _runs(np.array([], np.int64)) == []
    assert _runs(np.array([0, 1, 2, 5, 7, 8])) == [(0, 3), (5, 6), (7, 9)]


def test_gpu_mask_follows_the_scrolls_and_the_strips(gl_ctx, shaders):
    """The GPU field: its mask texture (shifted on the GPU, written by blocks) equals the CPU mask, which
    equals a full evaluation, and its water follows the float64 reference field frame by frame."""
    from rain_core.effects.ripples.backend import make_field

    gpu = make_field(gl_ctx, n=N, extent_m=EXTENT, backend="gpu", seed=5, shaders=shaders,
                     recenter_margin_cells=2)
    ref = RippleField(n=N, extent_m=EXTENT, backend="reference", seed=5, recenter_margin_cells=2)
    film = Film(0.4)
    try:
        def check():
            assert_same_as_full(gpu, film)
            texels = np.frombuffer(gpu.solver.mask_texture.read(), np.uint8).reshape(N, N)
            np.testing.assert_array_equal(texels > 127, gpu.solver.water_mask > 0.5)
            np.testing.assert_array_equal(gpu.solver.water_mask, ref.solver.water_mask)

        x = z = 0.0
        for dx, dz in MOVES * 2:
            x, z = x + dx, z + dz
            for field in (ref, gpu):
                field.update(1 / 30, center_xz=(x, z), rate_mm_h=20.0, film_depth_fn=film)
            check()
        scale = np.max(np.abs(ref.height))
        assert scale > 0.0
        assert np.max(np.abs(gpu.height - ref.height)) < 1e-3 * scale
    finally:
        gpu.release()


class CountingFilm(Film):
    def __init__(self, level: float):
        super().__init__(level)
        self.calls = 0

    def __call__(self, x, z):
        self.calls += 1
        return super().__call__(x, z)


def test_wheel_depths_are_asked_beside_the_strips():
    """While the window scrolls, the strips are asked as a grid (one call per strip) and the wheels' film depths
    in one call of their own, and they give the wake the depths given with the wheels."""
    from rain_core.effects.ripples.wheels import WheelBatch

    film = CountingFilm(0.2)
    fields = [RippleField(n=N, extent_m=EXTENT, backend="numpy32", recenter_margin_cells=1, seed=2)
              for _ in range(2)]
    x = z = 0.0
    for frame, (dx, dz) in enumerate(MOVES * 2):
        p0 = np.array([[x - 0.5, z], [x + 0.5, z], [x, z + 0.4]])
        x, z = x + dx, z + dz
        p1 = np.array([[x - 0.5, z], [x + 0.5, z], [x, z + 0.4]])
        speed, width = np.full(3, 9.0), np.full(3, 0.2)
        asked = WheelBatch(p0, p1, speed, width)
        mid = 0.5 * (p0 + p1)
        given = WheelBatch(p0, p1, speed, width, Film(0.2)(mid[:, 0], mid[:, 1]))
        film.calls = 0
        report = fields[0].update(1 / 30, center_xz=(x, z), rate_mm_h=10.0, wheels=asked, film_depth_fn=film)
        fields[1].update(1 / 30, center_xz=(x, z), rate_mm_h=10.0, wheels=given, film_depth_fn=Film(0.2))
        if frame and report["shift"] != (0, 0):
            assert film.calls == 2 + (report["shift"][0] != 0 and report["shift"][1] != 0)
        assert report["wake_bumps"] > 0
        np.testing.assert_array_equal(fields[0].height, fields[1].height)


def test_rain_lattice_count_follows_scrolls_over_unbroken_water():
    """Rows that scroll in over water everywhere write no block (the mask already says water): the rows' counts
    of the rain's lattice take them as water, as the mask does; then a drier film's strips and bands recount."""
    lattice = slice(1, N - 1, RAIN_FRACTION_STRIDE)
    for film in (Film(-3.0), Film(0.4)):
        field = RippleField(n=N, extent_m=EXTENT, backend="numpy32", recenter_margin_cells=1, seed=3)
        x = z = 0.0
        for dx, dz in MOVES * 2:
            x, z = x + dx, z + dz
            field.update(1 / 30, center_xz=(x, z), rate_mm_h=20.0, film_depth_fn=film)
            assert field._count_water(RAIN_FRACTION_STRIDE)[0] == np.count_nonzero(
                field.solver.water_mask[lattice, lattice])
        field.update(1 / 30, center_xz=(x, z), film_depth_fn=Film(1.1))  # a drier film: bands and blocks
        assert field._count_water(RAIN_FRACTION_STRIDE)[0] == np.count_nonzero(
            field.solver.water_mask[lattice, lattice])
