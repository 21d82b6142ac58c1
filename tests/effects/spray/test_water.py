"""The Flintsch/Weir water budget and the hydroplaning risk (rain_core.effects.spray.water)."""

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.effects.spray import water
from rain_core.effects.spray.water import (
    BUCKETS,
    KMH,
    MECHANISMS,
    allocate_water,
    hydroplaning_risk,
)

RNG = np.random.default_rng(7)


def test_allocation_sums_to_what_was_available_and_never_exceeds_it():
    v = np.concatenate([[0.0, 1.0, 60.0], RNG.uniform(0.0, 60.0, 2000)])
    b = np.concatenate([[0.2, 0.0, 0.3], RNG.uniform(0.1, 0.4, 2000)])
    h = np.concatenate([[0.005, 0.005, 0.0], RNG.uniform(0.0, 0.012, 2000)])
    h[RNG.random(len(h)) < 0.1] = 0.0
    w = allocate_water(v, b, h)
    assert np.allclose(w.available, physics.splash_water_flux(v, b, h), rtol=1e-12, atol=0)
    assert np.all(w.allocated >= 0.0)
    assert np.allclose(w.allocated.sum(axis=-1), w.available, rtol=1e-12, atol=1e-15)
    assert np.all(w.allocated.sum(axis=-1) <= w.available * (1 + 1e-12) + 1e-15)
    assert np.all(w.thrown >= 0.0) and np.all(w.thrown <= w.allocated * (1 + 1e-12) + 1e-15)
    assert np.allclose(w.buckets.sum(axis=-1), w.thrown.sum(axis=-1), rtol=1e-12, atol=1e-15)
    assert np.all(w.buckets >= 0.0) and np.all(w.retained >= -1e-12)
    assert w.buckets.shape[-1] == len(BUCKETS) and w.allocated.shape[-1] == len(MECHANISMS)


def test_water_is_spent_in_order_capillary_tread_side_bow():
    v, b = 30.0, 0.2
    per_mm = v * b * 1.0  # kg/s per mm of film
    thin, grooves, side, deep = (allocate_water(v, b, h * 1e-3).allocated for h in (0.05, 1.0, 3.0, 8.0))
    assert np.allclose(thin, [0.05 * per_mm, 0, 0, 0])
    assert np.allclose(grooves, [0.1 * per_mm, 0.9 * per_mm, 0, 0])
    assert np.allclose(side, [0.1 * per_mm, 1.5 * per_mm, 1.4 * per_mm, 0])
    assert np.allclose(deep, [0.1 * per_mm, 1.5 * per_mm, 3.0 * per_mm, 3.4 * per_mm])


def test_nothing_below_the_speed_and_depth_thresholds():
    h = np.linspace(0.0, 0.01, 41)
    slow = allocate_water(47.9 * KMH, 0.22, h)
    assert np.all(slow.spray == 0.0) and np.all(slow.mist == 0.0)  # no spray below 48 km/h
    assert np.all(slow.thrown[..., 0] == 0.0)
    walk = allocate_water(14.9 * KMH, 0.22, h)
    assert np.all(walk.thrown[..., 1] == 0.0)  # grooves keep their water below 15 km/h
    creep = allocate_water(4.9 * KMH, 0.22, h)
    assert np.all(creep.thrown == 0.0) and np.all(creep.retained == creep.available)
    dry = allocate_water(np.linspace(0, 60, 13), 0.22, 0.0)
    assert np.all(dry.available == 0.0) and np.all(dry.thrown == 0.0)
    shallow = allocate_water(30.0, 0.22, 1.59e-3)
    assert shallow.allocated[2] == 0.0 and shallow.allocated[3] == 0.0  # no side waves until grooves are full
    mid = allocate_water(30.0, 0.22, 4.59e-3)
    assert mid.allocated[2] > 0.0 and mid.allocated[3] == 0.0  # no bow wave below 4.6 mm
    fast = allocate_water(64.0 * KMH, 0.22, 0.2e-3)
    assert fast.spray > 0.0 and fast.mist > 0.0  # measurable spray by 64 km/h


def test_emission_is_linear_in_speed_and_film_depth_where_the_model_says_so():
    b = 0.225
    h = np.array([0.05, 0.2, 1.0, 3.0, 6.0]) * 1e-3
    v = np.array([70.0, 90.0]) * KMH  # past every ramp: everything thrown
    one = allocate_water(v[:, None], b, h[None, :]).thrown.sum(axis=-1)
    two_v = allocate_water(2 * v[:, None], b, h[None, :]).thrown.sum(axis=-1)
    two_h = allocate_water(v[:, None], b, 2 * h[None, :]).thrown.sum(axis=-1)
    assert np.allclose(two_v, 2 * one, rtol=1e-12) and np.allclose(two_h, 2 * one, rtol=1e-12)
    assert np.allclose(one, physics.splash_water_flux(v[:, None], b, h[None, :]), rtol=1e-12)
    # Inside one band a mechanism's share is linear in the depth too (capillary below 0.1 mm).
    cap = allocate_water(25.0, b, np.array([0.02, 0.04, 0.08]) * 1e-3).allocated[..., 0]
    assert np.allclose(cap / cap[0], [1, 2, 4], rtol=1e-12)
    # Below the ramps the throw is not linear: half the speed inside the capillary ramp throws less than half.
    a, c = (allocate_water(s * KMH, b, 0.1e-3).thrown[0] for s in (56.0, 112.0))
    assert a < 0.5 * c


def test_hydroplaning_risk():
    car = water.TYRE_PRESSURE_KPA["car"]
    assert water.hydroplaning_speed_m_s(car) / KMH == pytest.approx(6.36 * math.sqrt(car))
    v = np.linspace(0.0, 50.0, 101)
    thin = hydroplaning_risk(v, 0.2e-3, car)
    assert np.all(thin == 0.0)  # a film the tread drains never lifts the tyre
    deep = hydroplaning_risk(v, 8e-3, car)
    assert np.all(np.diff(deep) >= 0.0) and deep[0] == 0.0 and deep[-1] == 1.0
    assert hydroplaning_risk(60 * KMH, 8e-3, car) == 0.0  # below half the load on the water wedge
    depths = np.linspace(0.0, 10e-3, 51)
    assert np.all(np.diff(hydroplaning_risk(90 * KMH, depths, car)) >= 0.0)
    assert hydroplaning_risk(95 * KMH, 8e-3, water.TYRE_PRESSURE_KPA["truck"]) == 0.0  # lorry tyres: 700 kPa
    assert hydroplaning_risk(95 * KMH, 8e-3, car) > 0.8
