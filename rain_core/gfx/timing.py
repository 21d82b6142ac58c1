"""Per-pass timing: CPU time of the Python side, GPU time from a timer query where the driver has one."""

from __future__ import annotations

import time

import moderngl


class PassTimer:
    """Measures one pass: CPU time of the Python side, and GPU time from a timer query where the driver has one
    (else the wall time up to ``ctx.finish()``, which includes the CPU side). ``gpu_source`` says which."""

    def __init__(self, ctx: moderngl.Context, gpu: bool = True):
        self.ctx = ctx
        self.gpu = gpu
        self._query = None
        self.gpu_source = "none"
        if gpu:
            try:
                self._query = ctx.query(time=True)
                self.gpu_source = "timer query"
            except Exception:  # drivers without ARB_timer_query
                self._query = None
                self.gpu_source = "wall time after finish"

    def measure(self, fn) -> tuple[float, float | None]:
        """Run fn(); return (cpu_ms, gpu_ms or None)."""
        if not self.gpu:
            t0 = time.perf_counter()
            fn()
            return (time.perf_counter() - t0) * 1e3, None
        if self._query is not None:
            t0 = time.perf_counter()
            with self._query:
                fn()
            cpu = (time.perf_counter() - t0) * 1e3
            elapsed_ns = self._query.elapsed
            # Some drivers answer a query they could not time (e.g. across a shader compile) with 2³²−1 ns.
            return cpu, (None if elapsed_ns >= 0xFFFFFFFF else elapsed_ns * 1e-6)
        t0 = time.perf_counter()
        fn()
        cpu = (time.perf_counter() - t0) * 1e3
        self.ctx.finish()
        return cpu, (time.perf_counter() - t0) * 1e3

