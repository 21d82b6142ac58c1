"""The closed-form flight, its drag time constant and landing times (rain_core.effects.spray.flight)."""

import numpy as np
import pytest

from rain_core import layout, physics
from rain_core.effects.spray import flight
from rain_core.effects.spray.flight import (
    drag_time_constant,
    flight_position,
    flight_velocity,
    ground_time,
)


def test_closed_form_solves_linear_drag():
    p0, v0, u, tau = np.array([0.5, 0.3, 2.0]), np.array([3.0, 8.0, -20.0]), np.array([1.0, -2.0, 0.0]), 0.3
    x, v, dt = p0.copy(), v0.copy(), 1e-4
    for _ in range(10000):  # RK4 of dv/dt = (u − v)/τ to t = 1 s
        def f(state):
            return np.concatenate([state[3:], (u - state[3:]) / tau])
        s = np.concatenate([x, v])
        k1 = f(s)
        k2 = f(s + 0.5 * dt * k1)
        k3 = f(s + 0.5 * dt * k2)
        k4 = f(s + dt * k3)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        x, v = s[:3], s[3:]
    assert np.allclose(flight_position(p0, v0, u, tau, 1.0), x, atol=1e-9)
    assert np.allclose(flight_velocity(v0, u, tau, 1.0), v, atol=1e-9)
    assert np.allclose(flight_position(p0, v0, u, tau, 0.0), p0)


def test_drag_time_constant_matches_quadratic_drag():
    d = np.array([0.1, 0.3, 1.0, 3.0])
    vt = np.asarray(physics.terminal_velocity(d))
    assert np.allclose(drag_time_constant(d, vt), vt / physics.G_M_S2)  # at terminal speed: plain v_t/g
    assert np.allclose(drag_time_constant(d, vt * (1 + 1e-9)), vt / physics.G_M_S2, rtol=1e-6)  # continuous there
    # The distance to slow from s0 to v_t is quadratic drag's (v_t²/g)·ln(s0/v_t) (1-D, no gravity), stretched
    # by at most DRAG_TAIL_FIT for quadratic drag's long tail.
    s0 = 25.0
    tau = drag_time_constant(d, s0)
    linear = tau * (s0 - vt)
    quadratic = vt**2 / physics.G_M_S2 * np.log(s0 / vt)
    assert np.all(linear >= quadratic) and np.all(linear <= flight.DRAG_TAIL_FIT * quadratic)
    # Where a drop lands: within 25 % of an RK4 quadratic-drag flight (the bench tabulates this).
    for d_mm, launch in ((2.0, (0.0, 3.0, -6.0)), (0.3, (0.0, 4.0, -12.0)), (3.0, (2.0, 2.0, 8.0))):
        ref, t_ref = flight.quadratic_drag_reference((0, 0.3, 0), launch, d_mm)
        vt1 = physics.terminal_velocity(d_mm)
        u = np.array([0.0, -vt1, 0.0])
        tau1 = drag_time_constant(d_mm, np.linalg.norm(np.asarray(launch) - u))
        t = ground_time(np.array([[0, 0.3, 0]]), np.array([launch]), u[None], np.array([tau1]))[0]
        land = flight_position(np.array([0, 0.3, 0]), np.array(launch), u, tau1, t)
        reach = np.hypot(ref[0], ref[2])
        assert abs(np.hypot(land[0], land[2]) - reach) < 0.25 * reach + 0.02


def test_ground_time_lands_on_the_road_and_on_the_kerb_top():
    p0 = np.array([[1.0, 0.4, 0.0], [6.5, 0.4, 0.0]])
    v0 = np.array([[0.0, 3.0, 0.0], [6.0, 3.0, 0.0]])
    u = np.array([[0.0, -6.5, 0.0], [0.0, -6.5, 0.0]])
    tau = np.array([0.5, 0.5])
    t = ground_time(p0, v0, u, tau)
    y = flight_position(p0, v0, u, tau, t)[:, 1]
    assert y[0] == pytest.approx(0.0, abs=1e-9)
    assert y[1] == pytest.approx(layout.KERB_HEIGHT_M, abs=1e-9)  # flew over the kerb onto the sidewalk
