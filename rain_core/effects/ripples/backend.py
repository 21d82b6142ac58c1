"""Which wave solver runs: ``make_solver`` builds one by name, ``choose_backend`` times the fast paths on this
machine, ``make_field`` builds the ripple field with the chosen solver."""

from __future__ import annotations

import time

import numpy as np

from rain_core.effects.ripples.constants import BACKENDS, CAPILLARY_SPEED_M_S, DEFAULT_DAMPING_PER_S
from rain_core.effects.ripples.field import CPU_SOLVERS, RippleField
from rain_core.effects.ripples.gpu import WaveSolverGPU
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.window import field_grid


def _time_steps(solver: WaveSolver, steps: int, after=None) -> float:
    """Median ms per step of ``solver`` (one sub-step each), plus ``after()`` per step when given."""
    rng = np.random.default_rng(1)
    solver.sleep_energy = 0.0
    solver.reset(rng.standard_normal((solver.n, solver.n)) * 1e-3)
    dt = solver.dt_max
    samples = []
    for i in range(steps + 2):
        t0 = time.perf_counter()
        solver.step(dt)
        if after is not None:
            after()
        if i >= 2:  # the first steps compile, allocate and retime
            samples.append((time.perf_counter() - t0) * 1e3)
    samples.sort()
    return samples[len(samples) // 2]


def choose_backend(ctx, n: int, steps: int = 8, cell_m: float = 0.05,
                   speed_m_s: float = CAPILLARY_SPEED_M_S) -> tuple[str, dict[str, float]]:
    """Measure a few n×n steps of each fast path and return ("numpy32" | "gpu", timings in ms per step).

    The CPU path's cost includes uploading its height to a texture (the renderer needs it there); the GPU
    path's includes waiting for the GPU (ctx.finish). Without a context the answer is numpy32."""
    timings: dict[str, float] = {}
    cpu = WaveSolverF32(n, cell_m, speed_m_s)
    if ctx is None:
        timings["numpy32_ms"] = _time_steps(cpu, steps)
        return "numpy32", timings
    tex = ctx.texture((n, n), 1, dtype="f4")
    try:
        timings["numpy32_ms"] = _time_steps(cpu, steps, after=lambda: tex.write(cpu.height.tobytes()))
    finally:
        tex.release()
    gpu = WaveSolverGPU(ctx, n, cell_m, speed_m_s)
    try:
        timings["gpu_ms"] = _time_steps(gpu, steps, after=ctx.finish)
    finally:
        gpu.release()
    choice = "gpu" if timings["gpu_ms"] < timings["numpy32_ms"] else "numpy32"
    return choice, timings


def make_solver(backend: str, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0,
                ctx=None, **kwargs) -> WaveSolver:
    """A solver for a named backend ("numpy32", "gpu" (needs ctx), "reference")."""
    if backend in CPU_SOLVERS:
        return CPU_SOLVERS[backend](n, cell_m, speed_m_s, damping_per_s, **kwargs)
    if backend == "gpu":
        if ctx is None:
            raise ValueError("backend 'gpu' needs an OpenGL context")
        return WaveSolverGPU(ctx, n, cell_m, speed_m_s, damping_per_s, **kwargs)
    raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")



def auto_backend(ctx, n: int, extent_m: float, speed_m_s: float) -> tuple[str, dict[str, float]]:
    """What "auto" picks for a field of n cells per side over extent_m (m) at wave speed speed_m_s (m/s), and the
    timings (ms per step) it picked by: ``choose_backend`` on its grid, numpy32 without a context."""
    if ctx is None:
        return "numpy32", {}
    n, _, cell_m = field_grid(n, extent_m)
    return choose_backend(ctx, n, cell_m=cell_m, speed_m_s=speed_m_s)


def make_field(ctx=None, n: int = 512, extent_m: float = 25.0, speed_m_s: float = CAPILLARY_SPEED_M_S,
               damping_per_s: float = DEFAULT_DAMPING_PER_S, backend: str = "auto", *, shaders=None,
               **field_kwargs) -> RippleField:
    """A ``RippleField`` on a named backend (``BACKENDS``): "auto" measures the fast paths with
    ``choose_backend`` (numpy32 without a context) and keeps the timings in ``field.backend_timings``; "gpu"
    needs ``ctx`` (and uses ``shaders``, a ShaderLibrary, when given). ``field_kwargs`` go to ``RippleField``."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    n, extent, cell_m = field_grid(n, extent_m)
    timings: dict[str, float] = {}
    if backend == "auto":
        backend, timings = auto_backend(ctx, n, extent_m, speed_m_s)
    extra = {"shaders": shaders} if backend == "gpu" else {}
    solver = make_solver(backend, n, cell_m, speed_m_s, damping_per_s, ctx=ctx, **extra)
    try:
        return RippleField(n, extent, speed_m_s, damping_per_s, backend, solver=solver, backend_timings=timings,
                           **field_kwargs)
    except Exception:
        getattr(solver, "release", lambda: None)()
        raise
