"""Helpers shared by the ripple tests, handed out as fixtures (tests are imported by path): ``waves`` (standing
modes, their discrete frequency, a smooth test field) and ``gpu_solver_factory``."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rain_core.effects.ripples.gpu import WaveSolverGPU

H = 0.05


def mode(n: int, h: float, p: int, q: int) -> np.ndarray:
    """sin(pπx/L)·sin(qπz/L) on the grid, indexed [iz, ix]."""
    length = (n - 1) * h
    x = np.arange(n) * h
    return np.outer(np.sin(q * np.pi * x / length), np.sin(p * np.pi * x / length))


def discrete_omega(n: int, h: float, speed: float, dt: float, p: int, q: int) -> float:
    """ω_d of mode (p, q): cos(ω_d Δt) = 1 − 2C²[sin²(pπh/2L) + sin²(qπh/2L)]."""
    length = (n - 1) * h
    c2 = (speed * dt / h) ** 2
    cos_w = 1.0 - 2.0 * c2 * (math.sin(p * math.pi * h / (2 * length)) ** 2
                              + math.sin(q * math.pi * h / (2 * length)) ** 2)
    return math.acos(cos_w) / dt


def smooth_field(n: int, seed: int = 0) -> np.ndarray:
    """A few Gaussian bumps, zero at the edges (mm scale)."""
    rng = np.random.default_rng(seed)
    x = np.arange(n) * H
    xx, zz = np.meshgrid(x, x)
    length = (n - 1) * H
    out = np.zeros((n, n))
    for _ in range(4):
        cx, cz = rng.uniform(0.3, 0.7, 2) * length
        out += rng.uniform(-1e-3, 1e-3) * np.exp(-((xx - cx) ** 2 + (zz - cz) ** 2) / (0.1 * length) ** 2)
    out[0, :] = out[-1, :] = out[:, 0] = out[:, -1] = 0.0
    return out


@pytest.fixture
def waves():
    """``waves.mode``, ``waves.discrete_omega``, ``waves.smooth_field`` (see each)."""
    return SimpleNamespace(mode=mode, discrete_omega=discrete_omega, smooth_field=smooth_field)


@pytest.fixture(scope="module")
def gpu_solver_factory(gl_ctx, shaders):
    made = []

    def make(*args, **kwargs):
        solver = WaveSolverGPU(gl_ctx, *args, shaders=shaders, **kwargs)
        made.append(solver)
        return solver

    yield make
    for solver in made:
        solver.release()
