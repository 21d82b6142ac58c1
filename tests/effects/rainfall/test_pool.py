"""rainfall drop pool: the ring buffer never leaks or overflows, the simulation keeps its budget."""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.rainfall import DropPool, RainfallSim

# --- the ring buffer, determinism, rate changes, skipping ---------------------------------------------------------


def test_ring_buffer_never_leaks_or_overflows_in_1e5_frames():
    """The pool's free list and calendar under 10⁵ frames of spawning, expiring and rescheduling."""
    rng = np.random.default_rng(7)
    pool = DropPool(512)
    t, dt = 0.0, 1.0 / 60.0
    peak = 0
    for frame in range(100_000):
        t += dt * (0.5 + rng.random())  # jittered frame times
        due = pool.pop_due(t)
        if due.size:
            dead = due[rng.random(due.size) < 0.7]
            pool.release(dead)
            alive = np.setdiff1d(due, dead)
            pool.schedule(alive, t + rng.exponential(0.5, alive.size), t)
        want = int(rng.poisson(8 if (frame // 5000) % 2 else 3))
        slots = pool.allocate(want)
        assert slots.size == min(want, slots.size) and slots.size <= pool.capacity
        pool.schedule(slots, t + rng.exponential(1.5, slots.size), t)
        peak = max(peak, pool.live)
        if frame % 10_000 == 0:
            pool.check()
    pool.check()
    assert 0 < peak <= pool.capacity and pool.high_water <= pool.capacity
    # Drain: every slot comes back.
    t += 200.0
    for _ in range(3):
        t += 1.0
        pool.release(pool.pop_due(t))
    pool.check()
    assert pool.live == 0 and pool.n_free == pool.capacity


def test_simulation_keeps_its_budget_over_many_frames(rain):
    sim = RainfallSim(1500, seed=5)
    t, rate = 0.0, 8.0
    rng = np.random.default_rng(1)
    heading = 0.0
    pos = np.array([1.75, 1.2, 600.0])
    spawned = 0
    for frame in range(3000):
        dt = 1.0 / 60.0 * (0.5 + rng.random())
        t += dt
        if frame % 300 == 0:
            rate = float(rng.choice([0.0, 0.5, 8.0, 80.0]))
        heading += 0.3 * dt
        fwd = np.array([-math.sin(heading), -0.05, -math.cos(heading)])
        vel = 20.0 * fwd * np.array([1.0, 0.0, 1.0])
        pos = pos + vel * dt
        upd = sim.advance(rain.input(t, pos=pos, vel=vel, rate=rate, wind=(2.0, 0.0, 0.0), forward=fwd))
        spawned += upd.spawn_slots.size
        assert sim.live <= sim.capacity
        if frame % 1000 == 0:
            sim.pool.check()
    sim.pool.check()
    assert spawned > 10 * sim.capacity
    assert sim.pool.overflow < 0.01 * spawned
