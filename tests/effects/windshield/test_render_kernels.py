"""The windshield water pass's compiled kernels (render_kernels) against their NumPy twins: the drop rows, the film
deposits' rows and the coarse film's half-float bits, bit for bit over frames of a real scenario."""

import numpy as np
import pytest

from rain_core import jit
from rain_core.effects.windshield import render_kernels
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.sim import WindshieldSim
from rain_core.effects.windshield.splats import DROP_ROW, DropRows, FilmRows, film_splats, half_bits
from rain_core.physics import RHO_WATER

needs_numba = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")


def _twin_coarse(thickness_m: np.ndarray) -> np.ndarray:
    """WindshieldEffect._coarse_bits's NumPy path on a thickness array (m)."""
    f32 = np.minimum(thickness_m * 1e6, 6e4).astype(np.float32)
    return half_bits(f32).astype(np.uint16)


def _kernel_coarse(film_kg: np.ndarray, area_m2: np.ndarray, kernel=render_kernels.coarse_half_bits) -> np.ndarray:
    flat = np.ascontiguousarray(film_kg, np.float64).ravel()
    f32 = np.empty(len(flat), np.float32)
    out = np.empty(len(flat), np.uint16)
    kernel(flat, np.ascontiguousarray(area_m2, np.float64).ravel(), RHO_WATER, f32, f32.view(np.uint32), out)
    return out.reshape(film_kg.shape)


@needs_numba
def test_rows_and_film_bits_are_the_twins_bits_frame_after_frame():
    # Rain at speed with the wipers on high: drops sliding and merging, trails, splashes, beads along the blades
    # (the bins fill and empty with the strokes). Each frame's rows by the kernels are the twins' to the bit.
    sim = WindshieldSim(seed=11)
    inputs = GlassInputs.for_speed(90.0, 30.0, wiper_mode="high")
    fast_drops, twin_drops = DropRows(), DropRows()
    fast_film = FilmRows()
    texel = 1.2 / 512
    seen = {"beads": 0, "trails": 0, "impacts": 0, "capped": 0}
    for _ in range(90):
        sim.step(1 / 30, inputs)
        with jit.forced(True):
            rows = fast_drops.rows(sim)
            film = fast_film.rows(sim, texel)
        with jit.forced(False):
            want = twin_drops.rows(sim)
            want_film = film_splats(sim, texel)
        assert rows.dtype == DROP_ROW and rows.tobytes() == want.tobytes()
        assert film.dtype == np.float32 and film.shape == want_film.shape
        assert film.tobytes() == want_film.tobytes()
        thickness = sim.film_thickness_m()
        assert np.array_equal(_kernel_coarse(sim.film, sim.cell_areas), _twin_coarse(thickness))
        seen["beads"] += int(np.count_nonzero(sim.beads) > 0)
        seen["trails"] += int(len(sim.frame_trails()) > 0)
        seen["impacts"] += int(len(sim.frame_impacts()) > 0)
        seen["capped"] += int((thickness * 1e6 > 6e4).any())
    # The scenario reached each branch the kernels have (not the cap: a film that thick beads into drops).
    assert seen["beads"] > 10 and seen["trails"] > 10 and seen["impacts"] > 10
    assert sim.count > 500


@needs_numba
def test_many_splashes_keep_the_first_4096_and_seed_them_as_the_twin():
    # More impacts than a frame draws, some under half a texel (left out), a radius under a trail's least width.
    rng = np.random.default_rng(3)
    impacts = np.column_stack([rng.uniform(-0.6, 0.6, 6000), rng.uniform(0, 0.9, 6000),
                               rng.uniform(0.0, 4e-3, 6000), rng.uniform(0, 1e-5, 6000)])
    trails = np.column_stack([rng.uniform(-0.6, 0.6, (40, 4)), rng.uniform(1e-4, 3e-3, 40)])

    class Frame:
        arrival_count = 123457

        def frame_trails(self):
            return trails

        def frame_impacts(self):
            return impacts

    texel = 2.4e-3
    with jit.forced(True):
        got = FilmRows().rows(Frame(), texel).copy()
    want = film_splats(Frame(), texel)
    assert len(got) == 40 + 4096 and got.tobytes() == want.tobytes()
    assert (got[:40, 4] > trails[:, 4].astype(np.float32)).any()  # some trails widened to 0.6 texel


def test_coarse_bits_match_numpys_float16_over_the_range():
    # Zero, below the smallest normal half, the roundings' ties, the cap at 6e4 µm; the kernel's plain Python
    # version (small input) where Numba is missing or not.
    um = np.concatenate([[0.0, 1e-9, 3e-5, 6.1e-5, 6.2e-5, 1.0, 1.00048828125, 2047.5, 59999.0, 6e4, 7e4, 1e9],
                         np.random.default_rng(0).uniform(0, 300, 200)])
    area = np.random.default_rng(1).uniform(1e-4, 3e-4, len(um))  # m², a film cell's
    film = um * 1e-6 * (RHO_WATER * area)  # kg
    thickness = film / (RHO_WATER * area)  # film_thickness_m
    kernel = getattr(render_kernels.coarse_half_bits, "py_func", render_kernels.coarse_half_bits)
    got = _kernel_coarse(film, area, kernel)
    assert np.array_equal(got, _twin_coarse(thickness))
    f32 = np.minimum(thickness * 1e6, 6e4).astype(np.float32)
    # half_bits's floor is the smallest normal half (no subnormals), and its ties go up (NumPy's to even).
    plain = (f32 >= 6.2e-5) & ((f32.view(np.uint32) & 0x1FFF) != 0x1000)
    assert np.count_nonzero(~plain) == 6  # four below the floor, two ties (1.00048828125, 2047.5)
    assert np.array_equal(got[plain], f32.astype(np.float16).view(np.uint16)[plain])
    if jit.AVAILABLE:
        assert np.array_equal(_kernel_coarse(film, area), got)


def test_drop_rows_kernel_logic_in_plain_python():
    # The drop-rows kernel's plain Python version on a few rows: copies the drops, draws the wet bins' lines.
    from rain_core.effects.windshield.drop_rows import COLS, A, S

    kernel = getattr(render_kernels.drop_rows, "py_func", render_kernels.drop_rows)
    block = np.arange(3 * COLS, dtype=np.float64).reshape(3, COLS) * 0.01
    beads = np.array([[0.0, 1e-4, 0.0], [2e-3, 0.0, 0.0]])
    w_scale = np.array([0.5, 2.0])
    ends = np.array([[[0.1, 0.2], [0.2, 0.3], [0.3, 0.4]], [[0.1, 0.2], [0.2, 0.3], [0.3, 0.4]]])
    frames = np.array([[1.0, 0.0, 0.5, -0.1], [0.0, 1.0, -0.5, 0.2]])
    out = np.zeros((8, 5), np.float32)
    assert kernel(block, 2, S, A, beads, w_scale, ends, frames, out) == 4
    assert np.array_equal(out[:2, :4], block[:2, S : S + 4].astype(np.float32))
    assert np.array_equal(out[:2, 4], block[:2, A].astype(np.float32))
    w0, w1 = min(np.sqrt(1e-4 * 0.5), 0.01), min(np.sqrt(2e-3 * 2.0), 0.01)
    np.testing.assert_allclose(out[2], [0.7, -0.1, 0.8, -0.1, -w0], rtol=1e-6)
    np.testing.assert_allclose(out[3], [-0.5, 0.3, -0.5, 0.4, -w1], rtol=1e-6)


@needs_numba
def test_the_effects_coarse_film_bits_are_the_twins(gl_ctx, shaders):
    # WindshieldEffect._coarse_bits, the film texture's upload, both ways on a film that builds up and is wiped.
    from rain_core.effects.windshield.effect import WindshieldEffect

    effect = WindshieldEffect(gl_ctx, seed=8, shaders=shaders)
    inputs = GlassInputs.for_speed(40.0, 25.0, wiper_mode="low")
    wet = 0
    for _ in range(60):
        effect.sim.step(1 / 30, inputs)
        with jit.forced(True):
            got = effect._coarse_bits().copy()
        with jit.forced(False):
            want = effect._coarse_bits().copy()
        assert got.dtype == np.uint16 and np.array_equal(got, want)
        wet += int(np.count_nonzero(want) > 100)
    assert wet > 30
    effect.release()


@needs_numba
def test_film_rows_from_the_impact_columns_over_sub_steps_and_the_cap_are_the_twins():
    # Long frames in a downpour at speed: several sub-steps' blocks of impacts a frame, and past 4,096 of them the
    # rows stop (the cap counted across the blocks). The rows made from the columns are the twin's to the bit.
    sim = WindshieldSim(seed=5)
    inputs = GlassInputs.for_speed(150.0, 80.0, drop_budget=3000, wiper_mode="low")
    film_rows = FilmRows()
    seen = {"blocks": 0, "capped": 0}
    for dt in (0.1, 0.1, 1 / 30, 0.1, 0.05):
        sim.step(dt, inputs)
        with jit.forced(True):
            film = film_rows.rows(sim, 1.2 / 512)
        with jit.forced(False):
            want = film_splats(sim, 1.2 / 512)
        assert film.shape == want.shape and film.tobytes() == want.tobytes()
        seen["blocks"] += int(len(sim.impact_columns()) > 1)
        seen["capped"] += int(len(sim.frame_impacts()) > 4096)
    assert seen["blocks"] >= 3 and seen["capped"] >= 1


@needs_numba
def test_drop_rows_written_by_the_sort_are_used_only_while_the_drops_stay_as_sorted():
    # The sort's full copy writes the drops' float32 rows (drop_rows32); DropRows takes them while the drops'
    # version is the sort's. A change after the step (a setter), a later sort that moves nothing, and a copy of
    # the simulation each leave them out: the rows stay the twin's.
    import copy

    inputs = GlassInputs.for_speed(100.0, 30.0, drop_budget=3000, wiper_mode="low")
    sim = WindshieldSim(seed=7)
    builder = DropRows()

    def assert_rows_are_the_twins(s):
        with jit.forced(True):
            rows = builder.rows(s).tobytes()
        with jit.forced(False):
            assert rows == DropRows().rows(s).tobytes()

    with jit.forced(True):
        for _ in range(25):
            sim.step(1 / 30, inputs)
    assert sim.drop_rows32() is not None  # (drops sliding at speed: the sort copied every row)
    assert_rows_are_the_twins(sim)
    sim.pos = sim.pos + 1e-3
    assert sim.drop_rows32() is None
    assert_rows_are_the_twins(sim)
    with jit.forced(True):
        sim.step(0.1, inputs)  # three sub-steps
        assert sim.drop_rows32() is not None
        assert_rows_are_the_twins(sim)
        sim.mass = sim.mass * 1.5
        assert_rows_are_the_twins(sim)
        sim.step(1 / 30, inputs)
        assert sim.drop_rows32() is not None
        sim._sort_drops()  # in order already: nothing copied, nothing kept
        assert sim.drop_rows32() is None
        sim.step(1 / 30, inputs)
    twin = copy.deepcopy(sim)
    assert twin.drop_rows32() is None
    assert_rows_are_the_twins(twin)
    assert_rows_are_the_twins(sim)
