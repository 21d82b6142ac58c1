"""Passes over the drop rows folded into the kernels that pass over them anyway: the placing of dirty rows into the
motion and the sort, the rain sensor's drops and the largest radius into the shed's compaction. The same glass as
the twins' separate passes, and the radius bound the sweeps read never outlives the drops it was taken from."""

import copy

import numpy as np
import pytest

from rain_core import jit
from rain_core.effects.windshield import GlassInputs, WindshieldSim, drop_mass
from rain_core.effects.windshield.drop_rows import DIRTY, KEY

pytestmark = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")


def _wet_glass(seed: int = 5) -> WindshieldSim:
    sim = WindshieldSim(seed=seed)
    inputs = GlassInputs.for_speed(90.0, 20.0, drop_budget=1500, wiper_mode="auto")
    with jit.forced(True):
        for _ in range(40):
            sim.step(1 / 30, inputs)
    return sim


def test_sort_places_the_dirty_rows_as_the_twin_does():
    rng = np.random.default_rng(7)
    twin = _wet_glass()
    n = twin.count
    twin._append(twin.glass.from_uv(rng.uniform(0.0, 1.0, (300, 2))), np.zeros((300, 2)), np.full(300, 2e-6))
    twin._buf[: n : 5, KEY] = DIRTY  # some old rows placed again too
    twin._dirty = True
    sim = copy.deepcopy(twin)
    for on, s in ((False, twin), (True, sim)):
        with jit.forced(on):
            s._sort_drops()
    assert not sim._dirty and not np.any(sim._buf[: sim.count, KEY] == DIRTY)
    assert np.array_equal(sim._buf[: sim.count], twin._buf[: twin.count])
    assert np.array_equal(sim.fresh, twin.fresh)


def test_shed_takes_the_sensor_drops_and_the_largest_radius():
    sim = _wet_glass()
    with jit.forced(True):
        sim._shed_outside(True)
        n = sim.count
        assert sim._a_bound == float(sim._buf[:n, 6].max())
        k = sim._shed_sensor
        assert k is not None and k > 0
        assert sim._sensor_of(sim._ks.sensor_m[:k]) == sim.sensor_reading()
        sim._shed_outside(False)
        assert sim._shed_sensor is None


def test_radius_bound_is_dropped_when_drops_change(monkeypatch):
    # The sweeps' wedges are widened by the bound: one left from before a drop grew or came would let the blade
    # miss it. Every change from outside drops it, and so does the end of each sub-step's sweeps (the film step,
    # which may add drops itself, is left out here).
    sim = _wet_glass()
    monkeypatch.setattr(sim, "_film_step", lambda *args: None)
    with jit.forced(True):
        sim._shed_outside()
        assert sim._a_bound is not None
        sim._append(np.array([[0.0, 0.3]]), np.zeros((1, 2)), drop_mass(np.array([4e-3])))  # a big one
        assert sim._a_bound is None
        sim._shed_outside()
        sim.mass = sim.mass * 2.0
        assert sim._a_bound is None
        sim.step(1 / 30, GlassInputs.for_speed(90.0, 20.0, drop_budget=1500, wiper_mode="high"))
        assert sim._a_bound is None


def test_sweeps_with_the_shed_bound_are_the_twins():
    # Fast wipers, big drops left at the strokes' ends and long frames (several sub-steps, several segments a
    # sub-step): the kernels' sweeps (the shed's bound) and the twin's (its own maximum each segment).
    twin, sim = WindshieldSim(seed=9), WindshieldSim(seed=9)
    for k in range(60):
        inputs = GlassInputs.for_speed(60.0, 60.0, drop_budget=800, wiper_mode="high")
        dt = 0.1 if k % 7 == 0 else 1 / 30
        with jit.forced(False):
            twin.step(dt, inputs)
        with jit.forced(True):
            sim.step(dt, inputs)
    assert sim.wiped > 0.0 and sim.wiped == twin.wiped
    assert np.array_equal(sim._buf[: sim.count], twin._buf[: twin.count])
    assert np.array_equal(sim.beads, twin.beads) and np.array_equal(sim.film, twin.film)
