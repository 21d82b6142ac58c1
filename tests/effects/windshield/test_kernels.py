"""The windshield's compiled kernels (``kernels``) against their NumPy twins: the same seed gives the same glass,
bit for bit (the kernels do the twins' operations in the same order; cube roots and pairwise sums stay in NumPy),
through driving, parking, a tailwind, changing frames and the merge test's work budget."""

import math

import numpy as np
import pytest

from rain_core import jit
from rain_core.effects.windshield import GlassInputs, WindshieldSim, drop_mass, kernels

pytestmark = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")


def _assert_identical(twin: WindshieldSim, sim: WindshieldSim) -> None:
    n = twin.count
    assert sim.count == n
    assert np.array_equal(sim._buf[:n], twin._buf[:n])  # every column: position, motion, mass, cached, bounds
    assert np.array_equal(sim.fresh, twin.fresh)
    assert np.array_equal(sim.film, twin.film) and np.array_equal(sim.beads, twin.beads)
    for name in ("arrived", "wiped", "shed", "evaporated", "merges", "arrival_count"):
        assert getattr(sim, name) == getattr(twin, name), name
    assert np.array_equal(sim.frame_trails(), twin.frame_trails())
    assert np.array_equal(sim.frame_impacts(), twin.frame_impacts())


def _drive(scenario, frames: int, seed: int, check_every: int = 10) -> WindshieldSim:
    twin, sim = WindshieldSim(seed=seed), WindshieldSim(seed=seed)
    for k in range(frames):
        inputs, dt = scenario(k)
        with jit.forced(False):
            twin.step(dt, inputs)
        with jit.forced(True):
            sim.step(dt, inputs)
        if k % check_every == check_every - 1:
            _assert_identical(twin, sim)
    return sim


SCENARIOS = {
    "motorway, wipers low": lambda k: (GlassInputs.for_speed(120.0, 8.0, drop_budget=2000, wiper_mode="low"), 1 / 30),
    "speed, crosswind and long frames": lambda k: (
        GlassInputs.for_speed(130.0 * math.sin(math.pi * k / 120), 12.0,
                              wind_m_s=np.array([6.0 * math.sin(k / 9), 0.0, 4.0]), drop_budget=1200,
                              wiper_mode="intermittent", wiper_interval_s=1.0),
        0.1 if k % 10 == 0 else 1 / 30,
    ),
    "parked, downpour, full glass": lambda k: (GlassInputs.for_speed(0.0, 40.0, drop_budget=900, wiper_mode="off"),
                                               1 / 30),
    "tailwind, auto": lambda k: (GlassInputs.for_speed(-25.0, 10.0, drop_budget=1500, wiper_mode="auto"), 1 / 30),
    "storm at 200 km/h": lambda k: (GlassInputs.for_speed(200.0, 40.0, drop_budget=5000, wiper_mode="high"), 1 / 30),
}


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_kernels_give_the_twins_glass_bit_for_bit(name):
    sim = _drive(SCENARIOS[name], 90, seed=31)
    assert sim.count > 100 and sim.merges > 0


def _fresh_flood(seed: int, n: int, speed_m_s: float, spread_m: float) -> WindshieldSim:
    """A glass with ``n`` new small drops within ``spread_m`` of one point, moving at up to ``speed_m_s``."""
    rng = np.random.default_rng(seed)
    sim = WindshieldSim(seed=seed)
    pos = np.array([0.0, 0.5]) + rng.uniform(-spread_m, spread_m, (n, 2))
    vel = rng.normal(0.0, speed_m_s, (n, 2))
    sim._append(pos, vel, drop_mass(rng.uniform(0.1e-3, 0.3e-3, n)))
    return sim


@pytest.mark.parametrize(
    "n, speed_m_s, spread_m, falls_back",
    [
        (3000, 3.0, 0.3, True),  # far-reaching boxes past MERGE_CELLS_MAX: the twin's far grid runs
        (4000, 0.0, 0.02, False),  # all near, packed: lookups past MERGE_PAIRS_MAX are deferred (fresh stays)
    ],
)
def test_merge_over_the_work_budget_is_the_twins(monkeypatch, n, speed_m_s, spread_m, falls_back):
    statuses = []
    merge = kernels.merge_drops

    def spy(*args):
        out = merge(*args)
        statuses.append(out[0])
        return out

    monkeypatch.setattr(kernels, "merge_drops", spy)
    twin = _fresh_flood(5, n, speed_m_s, spread_m)
    sim = _fresh_flood(5, n, speed_m_s, spread_m)
    deferred = []
    pairs = twin._pairs.pairs

    def twin_pairs(*args):
        out = pairs(*args)
        deferred.append(out[2] is not None)
        return out

    twin._pairs.pairs = twin_pairs
    h = 1 / 30
    start = twin.pos.copy()
    disp = h * twin.vel
    with jit.forced(False):
        twin._merge_moves(n, np.arange(n), start[:, 0], start[:, 1], disp[:, 0], disp[:, 1])
    with jit.forced(True):
        sim._merge_moves(n, np.arange(n), start[:, 0], start[:, 1], disp[:, 0], disp[:, 1])
    assert statuses == [-1 if falls_back else 0]
    assert twin.merges > 0 and sim.merges == twin.merges
    assert np.array_equal(sim._merged_away, twin._merged_away)
    _assert_identical(twin, sim)
    if not falls_back:
        assert deferred == [True]  # packed near drops: some lookups wait for the next sub-step, in both


def test_kernels_follow_the_twin_after_a_copy_and_a_grown_array():
    # The work arrays are made per simulation (not copied) and again when the drop array grows.
    import copy

    inputs = GlassInputs.for_speed(90.0, 30.0, drop_budget=3000, wiper_mode="high")
    twin = WindshieldSim(seed=33)
    for _ in range(20):
        twin.step(1 / 30, inputs)
    sim = copy.deepcopy(twin)
    for _ in range(40):  # the array grows past 512, then 1024 rows
        with jit.forced(False):
            twin.step(1 / 30, inputs)
        with jit.forced(True):
            sim.step(1 / 30, inputs)
    assert len(sim._buf) > 1024
    _assert_identical(twin, sim)


def test_place_rows_in_plain_python_is_placed():
    # The kernel's own logic (its plain-Python version, as it runs where Numba is missing), on a few rows.
    from rain_core.effects.windshield.drop_rows import DIRTY, KEY, PLACED, S, T

    sim = WindshieldSim(seed=2)
    rng = np.random.default_rng(2)
    sim._append(sim.glass.from_uv(rng.uniform(0.0, 1.0, (40, 2))), np.zeros((40, 2)), np.full(40, 1e-6))
    d = sim._buf[: sim.count]
    d[::3, KEY] = 0.0  # not dirty: left alone
    before = d.copy()
    place = getattr(kernels.place_rows, "py_func", kernels.place_rows)
    assert place(sim._buf, sim.count, sim._w0, sim._dw, sim._height, sim._g_up, sim._g_sag) == 40 - 14
    dirty = before[:, KEY] == DIRTY
    assert np.array_equal(d[~dirty], before[~dirty])
    assert np.array_equal(d[dirty][:, PLACED], sim._placed(d[dirty, S], d[dirty, T]))


def test_sort_and_removal_of_rows_are_the_twins():
    # Radix-sorted rows (stable, ties and all) and a compaction, against the twin's argsort and row gathers.
    import copy

    from rain_core.effects.windshield.drop_rows import KEY

    rng = np.random.default_rng(4)
    twin = WindshieldSim(seed=4)
    twin._append(twin.glass.from_uv(rng.uniform(0.0, 1.0, (3000, 2))), np.zeros((3000, 2)), np.full(3000, 1e-6))
    twin._flush_placed()
    twin._buf[:3000, KEY] = rng.integers(0, 200_000, 3000).astype(float)
    twin._buf[:3000:7, KEY] = 1234.0  # ties: their row order is kept
    twin.fresh[:] = rng.random(3000) < 0.5
    sim = copy.deepcopy(twin)
    keep = rng.random(3000) < 0.8
    for on, s in ((False, twin), (True, sim)):
        with jit.forced(on):
            s._sort_drops()
            s._keep(keep)
            s._sort_drops()
    assert sim.count == twin.count == np.count_nonzero(keep)
    assert np.array_equal(sim._buf[: sim.count], twin._buf[: twin.count])
    assert np.array_equal(sim.fresh, twin.fresh)


@pytest.mark.parametrize("speed_kmh, rate_mm_h, wind", [(0.0, 8.0, 0.0), (100.0, 30.0, 5.0), (-20.0, 2.0, -8.0),
                                                         (250.0, 120.0, 0.0)])
def test_arrival_law_and_table_are_the_twins(speed_kmh, rate_mm_h, wind):
    from rain_core.effects.windshield.arrivals import ArrivalTable

    sim = WindshieldSim(seed=1)
    inputs = GlassInputs.for_speed(speed_kmh, rate_mm_h, wind_m_s=np.array([wind, 0.0, 1.0]))
    rate, closing, cdf = sim.arrival_rate_per_s(inputs)
    table = ArrivalTable(closing, cdf)
    k_rate, k_closing, k_cdf, k_table = sim._arrival_law(inputs)
    assert k_rate == rate > 0.0
    assert np.array_equal(k_closing, closing) and np.array_equal(k_cdf, cdf)
    assert np.array_equal(k_table._coef, table._coef) and k_table.total == table.total
    u = np.random.default_rng(0).random(3 * 5000)  # and it samples the same (searched, then by buckets)
    u[:20], u[20:40] = 0.0, np.nextafter(1.0, 0.0)  # the ends of the law
    for _ in range(2):
        assert np.array_equal(np.array(k_table.sample(u[:5000])), np.array(table.sample(u[:5000])))
    # The arrivals kernel finds each sample's interval by its own walk: the same diameters.
    imp, cells, obj = np.empty((7, 5000)), np.empty(5000, np.int64), np.empty(5000, np.int64)
    kernels.sample_arrivals(u, 5000, k_table.cdf, k_table._coef, k_table.total, sim._w0, sim._dw, sim._height, imp,
                            cells, obj)
    assert np.array_equal(imp[2], table.sample(u[:5000])[0])


def test_append_at_rest_is_the_twins():
    # Drops appended at rest by the kernel (and its plain-Python version), from points picked out of columns (the
    # arrivals') and from whole columns (beads, trail droplets), against the twin's gathers and column writes,
    # after rows already there and over a grown array.
    import copy

    from rain_core.effects.windshield.constants import drop_radius
    from rain_core.effects.windshield.drop_array import _ALL

    rng = np.random.default_rng(6)
    twin = WindshieldSim(seed=6)
    twin._append(twin.glass.from_uv(rng.uniform(0.0, 1.0, (30, 2))), rng.normal(size=(30, 2)), np.full(30, 1e-6))
    cols = rng.uniform(-0.5, 0.5, (7, 5000))
    picks = np.sort(rng.choice(5000, 4000, replace=False))
    mass = rng.uniform(1e-7, 1e-5, len(picks))
    radius = rng.uniform(1e-4, 1e-3, len(picks))
    beads = rng.uniform(1e-7, 1e-5, 300)
    sim, plain = copy.deepcopy(twin), copy.deepcopy(twin)
    for on, s in ((False, twin), (True, sim)):
        with jit.forced(on):
            s._append_picked(cols[0], cols[1], picks, mass, radius)
            s._append_at_rest(cols[2, :300], cols[3, :300], beads)
            s._append_at_rest(cols[2, :0], cols[3, :0], beads[:0])
    append = kernels.append_at_rest.py_func
    n = plain.count
    plain._reserve(n + len(picks) + 300)
    append(plain._buf, plain._fresh_buf, n, cols[0], cols[1], picks, mass, radius)
    append(plain._buf, plain._fresh_buf, n + len(picks), cols[2, :300], cols[3, :300], _ALL, beads,
           drop_radius(beads))
    plain._n = n + len(picks) + 300
    assert sim.count == twin.count == 30 + len(picks) + 300
    assert np.array_equal(sim._buf[: sim.count], twin._buf[: twin.count])
    assert np.array_equal(sim.fresh, twin.fresh)
    assert sim._dirty and sim.version > plain.version
    assert np.array_equal(plain._buf[: plain.count], twin._buf[: twin.count])
    assert np.array_equal(plain.fresh, twin.fresh)


def test_bead_points_are_the_twins():
    # Beads placed in their film cells (the kernel and its plain-Python version) against the twin's NumPy steps.
    from rain_core.effects.windshield.constants import FILM_CELLS

    sim = WindshieldSim(seed=8)
    rng = np.random.default_rng(8)
    cells = rng.choice(FILM_CELLS * FILM_CELLS, 500, replace=False)
    r = rng.random(1000)
    iv, iu = np.divmod(cells, FILM_CELLS)
    u = (iu + r[:500]) / FILM_CELLS
    v = (iv + r[500:]) / FILM_CELLS
    t = v * sim._height
    twin = np.stack([(u - 0.5) * (sim._w0 + sim._dw * t), t])
    for kernel in (kernels.bead_points, kernels.bead_points.py_func):
        st = np.empty((2, 500))
        kernel(cells, r, sim._w0, sim._dw, sim._height, st)
        assert np.array_equal(st, twin)
