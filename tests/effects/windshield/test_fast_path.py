"""The fast path (``sim.WindshieldSim``) against the float64 reference (``reference.WindshieldSimReference``):
the same seed gives the same drops, film and counters (to rounding: the fast path folds constants, keeps the
radius by Newton steps and adds the film with bincount), and over a long drive the same statistics."""

import math

import numpy as np
import pytest

from rain_core.effects.windshield import GlassInputs, WindshieldSim
from rain_core.effects.windshield.grid import PairFinder
from rain_core.effects.windshield.reference import WindshieldSimReference


def _pair(seed: int):
    return WindshieldSim(seed=seed), WindshieldSimReference(seed=seed)


def _assert_same(fast, ref, atol_m=1e-9):
    assert fast.count == ref.count
    assert fast.merges == ref.merges and fast.arrival_count == ref.arrival_count
    assert np.allclose(fast.pos, ref.pos, rtol=0.0, atol=atol_m)
    assert np.allclose(fast.vel, ref.vel, rtol=1e-6, atol=1e-9)
    assert np.allclose(fast.mass, ref.mass, rtol=1e-9, atol=0.0)
    assert np.allclose(fast.radius(), ref.radius(), rtol=1e-7, atol=0.0)
    assert np.allclose(fast.film, ref.film, rtol=1e-9, atol=1e-18)
    assert np.allclose(fast.beads, ref.beads, rtol=1e-9, atol=1e-18)
    for name in ("arrived", "wiped", "shed", "evaporated"):
        assert getattr(fast, name) == pytest.approx(getattr(ref, name), rel=1e-9, abs=1e-15), name
    assert fast.wipers.cycle_starts == ref.wipers.cycle_starts


@pytest.mark.parametrize(
    "speed_kmh, rate_mm_h, mode, budget",
    [(120.0, 8.0, "low", 2000), (0.0, 8.0, "auto", 1500), (60.0, 30.0, "high", 600), (-20.0, 4.0, "off", 800)],
)
def test_same_seed_same_drops(speed_kmh, rate_mm_h, mode, budget, kernel_path):
    fast, ref = _pair(11)
    inputs = GlassInputs.for_speed(speed_kmh, rate_mm_h, drop_budget=budget, wiper_mode=mode, wiper_interval_s=1.0)
    for k in range(60):
        fast.step(1 / 30, inputs)
        ref.step(1 / 30, inputs)
        if k % 20 == 19:
            _assert_same(fast, ref)
    assert fast.count > 50
    # What the effect draws from the step agrees too.
    assert np.allclose(fast.frame_impacts(), ref.frame_impacts(), rtol=1e-9, atol=1e-15)
    assert np.allclose(fast.frame_trails(), ref.frame_trails(), rtol=1e-9, atol=1e-15)


def test_same_state_through_changing_speed_wind_and_long_frames(kernel_path):
    fast, ref = _pair(12)
    for k in range(120):
        inputs = GlassInputs.for_speed(
            130.0 * math.sin(math.pi * k / 120),
            12.0,
            wind_m_s=np.array([6.0 * math.sin(k / 9), 0.0, 4.0]),
            drop_budget=1200,
            wiper_mode="intermittent",
            wiper_interval_s=1.0,
        )
        dt = 0.1 if k % 10 == 0 else 1 / 30  # a 0.1 s frame is three sub-steps
        fast.step(dt, inputs)
        ref.step(dt, inputs)
    _assert_same(fast, ref)


def test_long_drive_statistics_agree():
    """Over 30 s of driving the two may part ways (one rounding flips one merge, then the random draws
    differ); what is measured on the glass must not."""
    fast, ref = _pair(13)
    stats = {id(fast): [], id(ref): []}
    for k in range(900):
        speed = 120.0 * (0.5 + 0.5 * math.sin(2 * math.pi * k / 450))
        inputs = GlassInputs.for_speed(speed, 8.0, drop_budget=800, wiper_mode="auto")
        for sim in (fast, ref):
            sim.step(1 / 30, inputs)
            if k >= 300 and k % 30 == 0:
                covered = float((np.pi * sim.radius() ** 2).sum() / sim.glass.area_m2)
                stats[id(sim)].append((sim.count, sim.mass_on_glass(), covered))
    f, r = np.array(stats[id(fast)]).mean(axis=0), np.array(stats[id(ref)]).mean(axis=0)
    assert f == pytest.approx(r, rel=0.05)  # drop count, water on the glass, coverage
    assert abs(fast.balance_error_kg()) <= 1e-9 * fast.arrived


def test_pair_finder_finds_every_touching_pair_of_any_reach():
    rng = np.random.default_rng(2)
    finder = PairFinder()
    for trial in range(12):
        n = int(rng.integers(50, 800))
        p = rng.uniform([-0.7, 0.0], [0.7, 1.1], (n, 2))
        reach = rng.exponential(0.002, n) * rng.choice([1.0, 1.0, 1.0, 12.0, 60.0], n)
        active = rng.random(n) < 0.3
        i, j, deferred = finder.pairs(p[:, 0], p[:, 1], reach, active, p[:, 0], p[:, 1], reach)
        assert deferred is None
        found = set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))
        dist = np.linalg.norm(p[:, None] - p[None], axis=2)
        ii, jj = np.nonzero((dist <= reach[:, None] + reach[None]) & np.triu(np.ones((n, n), bool), 1))
        want = {(a, b) for a, b in zip(ii.tolist(), jj.tolist(), strict=True) if active[a] or active[b]}
        assert want <= found, trial


def test_pair_finder_work_is_capped_for_a_flood_of_fast_drops():
    from rain_core.effects.windshield.constants import MERGE_PAIRS_MAX

    rng = np.random.default_rng(3)
    n = 20_000
    p = rng.uniform([-0.7, 0.0], [0.7, 1.1], (n, 2))
    reach = np.full(n, 0.4)  # every drop sweeping 0.8 m this sub-step: all pairs would be 2·10⁸
    end = p + 0.01
    i, j, deferred = PairFinder().pairs(p[:, 0], p[:, 1], reach, np.ones(n, bool), end[:, 0], end[:, 1],
                                         np.full(n, 0.002))
    assert len(i) <= MERGE_PAIRS_MAX and deferred is not None and deferred.any()


def test_a_copy_runs_on_like_the_original(kernel_path):
    import copy
    import pickle

    sim = WindshieldSim(seed=14)
    inputs = GlassInputs.for_speed(90.0, 10.0, drop_budget=700, wiper_mode="high")
    for _ in range(30):
        sim.step(1 / 30, inputs)
    twins = [copy.deepcopy(sim), pickle.loads(pickle.dumps(sim))]
    for _ in range(30):
        for s in (sim, *twins):
            s.step(1 / 30, inputs)
    for twin in twins:
        assert np.array_equal(twin.pos, sim.pos) and np.array_equal(twin.film, sim.film)
    # And a fast path started from a reference's state follows the reference.
    ref = WindshieldSimReference(seed=15)
    for _ in range(30):
        ref.step(1 / 30, inputs)
    fast = WindshieldSim(seed=0)
    fast.load_state(ref)
    for _ in range(20):
        fast.step(1 / 30, inputs)
        ref.step(1 / 30, inputs)
    _assert_same(fast, ref)


def test_pair_finder_puts_far_reaching_drops_in_the_cells_of_their_boxes():
    # Fast drops are few in ordinary rain: with some of them, every drop sits in the near cells its box touches
    # (PairFinder._box_pairs), without the far grid. Every touching pair must still be found, also at the grid's
    # borders and beyond them.
    from rain_core.effects.windshield.grid import NEAR_CELL_M

    rng = np.random.default_rng(5)
    finder = PairFinder()
    boxed = 0
    original = finder._box_pairs

    def counted(*args):
        nonlocal boxed
        result = original(*args)
        boxed += result is not None
        return result

    finder._box_pairs = counted
    for trial in range(10):
        n = int(rng.integers(300, 1500))
        p = rng.uniform([-1.05, -0.25], [1.05, 1.45], (n, 2))  # a little beyond the grid on every side
        reach = rng.uniform(0.0005, 0.5 * NEAR_CELL_M, n)
        far = rng.choice(n, int(rng.integers(1, 200)), replace=False)
        reach[far] = rng.uniform(0.5 * NEAR_CELL_M, 0.06, len(far))
        active = rng.random(n) < 0.3
        i, j, deferred = finder.pairs(p[:, 0], p[:, 1], reach, active, p[:, 0], p[:, 1], reach)
        assert deferred is None
        found = set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))
        dist = np.linalg.norm(p[:, None] - p[None], axis=2)
        ii, jj = np.nonzero((dist <= reach[:, None] + reach[None]) & np.triu(np.ones((n, n), bool), 1))
        want = {(a, b) for a, b in zip(ii.tolist(), jj.tolist(), strict=True) if active[a] or active[b]}
        assert want <= found, trial
        assert all(active[a] or active[b] for a, b in found) and not (i == j).any()
    assert boxed == 10  # the box table did the far drops each time


def test_arrival_sampling_by_search_and_by_buckets_agree_with_interp():
    from rain_core.effects.windshield import arrivals
    from rain_core.effects.windshield.reference import _D_GRID_MM

    sim = WindshieldSim()
    u = np.random.default_rng(6).random(3 * arrivals._TABLE_FROM)
    u[:4] = [0.0, 1e-17, 0.5, 1.0 - 1e-16]
    for speed in (0.0, 60.0, 200.0, -30.0):
        _, closing, cdf = sim.arrival_rate_per_s(GlassInputs.for_speed(speed, 8.0))
        table = arrivals.ArrivalTable(closing, cdf)
        d_big, c_big = table.sample(u)  # the bucket table
        # A small sample searches the first time a law is sampled, and uses the bucket table once it is built.
        small = [arrivals.ArrivalTable(closing, cdf).sample(part) for part in np.array_split(u, 16)]
        again = [table.sample(part) for part in np.array_split(u, 16)]
        for parts in (small, again):
            assert np.array_equal(d_big, np.concatenate([d for d, _ in parts]))
            assert np.array_equal(c_big, np.concatenate([c for _, c in parts]))
        assert np.allclose(d_big, np.interp(u * cdf[-1], cdf, _D_GRID_MM), rtol=1e-12, atol=1e-12)


def test_position_columns_follow_the_drops(kernel_path):
    # The drop array keeps functions of each drop's position (film cell, air factors, gravity, sort key) written
    # where drops are placed; after arrivals, runs, merges, trails, wipes and beading they must equal a fresh
    # computation, bit for bit.
    from rain_core.effects.windshield.drop_rows import PLACED, S, T

    sim = WindshieldSim(seed=8)
    for speed, mode in ((150.0, "high"), (40.0, "off"), (-15.0, "low")):
        inputs = GlassInputs.for_speed(speed, 25.0, drop_budget=1500, wiper_mode=mode)
        for _ in range(45):
            sim.step(1 / 30, inputs)
            d = sim._buf[: sim.count]
            assert np.array_equal(d[:, PLACED], sim._placed(d[:, S], d[:, T]))
    assert sim.count > 500 and sim.merges > 0


def test_sensor_reading_is_the_references():
    sim = WindshieldSim(seed=9)
    inputs = GlassInputs.for_speed(30.0, 20.0, wiper_mode="off")
    for _ in range(60):
        sim.step(1 / 30, inputs)
    assert sim.sensor_reading() > 0.0
    assert sim.sensor_reading() == WindshieldSimReference.sensor_reading(sim)


def test_resting_drops_skipped_by_their_bound_would_not_have_started(monkeypatch, kernel_path):
    # fast_motion tests only the drops whose bound RB (drop_rows) may reach the pinning: the others provably stay
    # at rest. A twin that tests every drop every step (the bound disabled) must give the same glass, bit for bit,
    # through parking, driving, braking, a tailwind, a crosswind and changing frame lengths.
    import copy

    from rain_core.effects.windshield import fast_motion
    from rain_core.effects.windshield.drop_rows import RB

    sim = WindshieldSim(seed=21)
    twin = copy.deepcopy(sim)
    skipped = 0
    for k in range(240):
        speed = (0.0, 130.0, 130.0, 60.0, -25.0, 0.0)[k // 40]
        wind = np.array([5.0 if 120 <= k < 200 else 0.0, 0.0, 0.0])
        inputs = GlassInputs.for_speed(speed, 10.0, wind_m_s=wind, drop_budget=1200, wiper_mode="auto")
        dt = 0.05 if k % 7 == 0 else 1 / 30
        skipped += int((sim._buf[: sim.count, RB] < fast_motion._REST_TEST).sum())
        sim.step(dt, inputs)
        with monkeypatch.context() as m:
            m.setattr(fast_motion, "_REST_TEST", -np.inf)
            twin.step(dt, inputs)
        if k % 40 == 39:
            # Every column but the bound itself (which the twin rewrites each step).
            assert np.array_equal(sim._buf[: sim.count, :RB], twin._buf[: twin.count, :RB])
            assert np.array_equal(sim.film, twin.film) and sim.evaporated == twin.evaporated
    assert sim.count > 300 and skipped > 100 * 240  # most resting drops were spared their test



@pytest.mark.parametrize("slack", [None, 0.2])
def test_resting_drops_skipped_through_a_drifting_air_would_not_have_started(monkeypatch, slack, kernel_path):
    # The bounds hold within an epoch of nearby airs (fast_motion._air_deviation): a car whose speed and crosswind
    # drift a little every frame (an autopilot, gusts) retests only the drops near their pinning, with the same
    # glass, bit for bit, as a twin that tests every drop every step; the epoch restarts as the air leaves it.
    # A wide epoch (slack 0.2: the drag changes by ~70 % within it) stresses the bound's allowance for the air.
    import copy

    from rain_core.effects.windshield import fast_motion
    from rain_core.effects.windshield.drop_rows import RB

    if slack is not None:
        monkeypatch.setattr(fast_motion, "_AIR_SLACK", slack)
    sim = WindshieldSim(seed=22)
    twin = copy.deepcopy(sim)
    skipped = epochs = 0
    for k in range(240):
        speed = 50.0 + 0.4 * k + 10.0 * math.sin(k / 20)  # rising, ~0.2-0.8 % a frame
        wind = np.array([1.0 + 0.5 * math.sin(k / 40), 0.0, 0.3])
        inputs = GlassInputs.for_speed(speed, 10.0, wind_m_s=wind, drop_budget=1500, wiper_mode="off")
        skipped += int((sim._buf[: sim.count, RB] < fast_motion._REST_TEST).sum())
        epoch = sim._rest_air
        sim.step(1 / 30, inputs)
        epochs += sim._rest_air is not epoch
        with monkeypatch.context() as m:
            m.setattr(fast_motion, "_REST_TEST", -np.inf)
            twin.step(1 / 30, inputs)
        if k % 40 == 39:
            assert np.array_equal(sim._buf[: sim.count, :RB], twin._buf[: twin.count, :RB])
            assert np.array_equal(sim.film, twin.film) and sim.evaporated == twin.evaporated
    assert sim.count > 300 and skipped > 100 * 240
    if slack is None:
        assert 5 < epochs < 120  # the epoch follows the air, but not every frame
