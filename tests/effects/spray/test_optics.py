"""The phase function and the GLSL twin of flight and optics (rain_core.effects.spray.optics, .probe)."""

import numpy as np
import pytest

from rain_core.effects.spray import optics
from rain_core.effects.spray.flight import flight_position, flight_velocity
from rain_core.effects.spray.optics import phase_function
from rain_core.effects.spray.probe import glsl_probe

RNG = np.random.default_rng(7)


def _probe(gl_ctx, shaders, p0, v0, tau, u, age, mu):
    return glsl_probe(gl_ctx, shaders, p0, v0, tau, u, age, mu)


def test_glsl_flight_and_phase_agree_with_numpy(gl_ctx, shaders):
    n = 512
    p0 = RNG.uniform(-5, 5, (n, 3))
    v0 = RNG.uniform(-30, 30, (n, 3))
    u = RNG.uniform(-3, 3, (n, 3))
    u[:, 1] = -RNG.uniform(0.2, 9.0, n)
    tau = RNG.uniform(0.005, 1.0, n)
    age = RNG.uniform(0.0, 3.0, n)
    age[:16] = RNG.uniform(0, 1e-5, 16)  # the series branch near t = 0
    mu = np.cos(RNG.uniform(0, np.pi, n))
    pos, vel, ph = _probe(gl_ctx, shaders, p0, v0, tau, u, age, mu)
    assert np.allclose(pos, flight_position(p0, v0, u, tau, age), atol=2e-4, rtol=1e-5)
    assert np.allclose(vel, flight_velocity(v0, u, tau, age), atol=1e-4, rtol=1e-5)
    assert np.allclose(ph, phase_function(mu), rtol=2e-4, atol=1e-6)


def test_phase_function_is_normalised():
    mu = 1.0 - np.geomspace(1e-9, 2.0, 400001)[::-1]  # dense near the forward peak
    mu = np.concatenate([[-1.0], mu[mu > -1.0], [1.0]])
    p = phase_function(mu)
    total = 2 * np.pi * np.sum((p[1:] + p[:-1]) / 2 * np.diff(mu))
    assert total == pytest.approx(1.0, abs=2e-3)
    assert 0.05 < optics.REFLECTION_SHARE < 0.08  # water's mean external reflectance (~6.6 %)
