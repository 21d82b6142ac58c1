"""Per-pass timing: CPU time of the Python side always (two clock reads), GPU time only when asked for.

A timer query's result is only ready once the GPU has done the pass: reading it at once stalls the CPU until
then. The renderer therefore times the GPU only while a performance table is shown (``Renderer.gpu_timing``)
and reads each query two frames late (``PassTimer(lagged=True)``), when the result is long ready. It reads them
all before the frame's first pass (``PassTimer.collect``): with a driver thread (``gfx.driver``) every read waits
until the thread has run all the calls queued before it, so a read after each pass made the driver's work run
in step with the passes, ~24 times a frame. Two frames, not one: at the start of a frame the GPU may still be
drawing the last one, and waiting for it would stall the CPU."""

from __future__ import annotations

import time

import moderngl


def cpu_ms(fn) -> float:
    """Run fn(); return its CPU side's wall time in ms (a pass without GPU timing: two clock reads)."""
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1e3


class PassTimer:
    """Measures one pass. ``measure(fn, gpu=None)`` runs fn() and returns (cpu_ms, gpu_ms or None).

    GPU time (``gpu`` true) comes from a timer query around fn(); where the driver has none, from the wall time
    up to ``ctx.finish()`` (which includes the CPU side). ``gpu_source`` says which. ``lagged``: a ring of
    LAG + 1 queries, and ``measure`` returns the GPU time of the measurement LAG calls before (None until there
    is one), so nothing waits; otherwise the query is read at once (a stall, fine for a benchmark of one pass)."""

    LAG = 2  # measurements between a lagged query's use and its read

    def __init__(self, ctx: moderngl.Context, gpu: bool = True, lagged: bool = False):
        self.ctx = ctx
        self.gpu = gpu
        self.lagged = lagged
        self._queries: list | None = None  # one timer query (lagged: LAG + 1), made on first use
        self._index = 0  # the query the next measurement uses (lagged: the ring's oldest)
        self._pending = [False] * (self.LAG + 1)  # whether query i holds an unread measurement (lagged)
        self._collected_ms: float | None = None  # GPU ms of the measurement LAG ago, read by collect() (lagged)
        self.gpu_source = "none"
        if gpu:
            self._make_queries()

    def _make_queries(self) -> None:
        try:
            self._queries = [self.ctx.query(time=True) for _ in range(self.LAG + 1 if self.lagged else 1)]
            self.gpu_source = f"timer query ({self.LAG} frames late)" if self.lagged else "timer query"
        except Exception:  # drivers without ARB_timer_query
            self._queries = []
            self.gpu_source = "wall time after finish"

    def forget(self) -> None:
        """Drop unread lagged measurements (GPU timing was switched off: a later read would be stale)."""
        self._pending = [False] * (self.LAG + 1)
        self._collected_ms = None

    def collect(self) -> None:
        """Read now (lagged only) the query the next ``measure`` returns, that of the measurement LAG calls before
        it: a renderer collects all its timers before its first pass, so they wait for a threaded driver once a
        frame, not once a pass."""
        if not (self.lagged and self._queries):
            return
        due = (self._index + 1) % len(self._queries)  # after the next measurement, the ring's oldest
        if self._pending[due]:
            self._pending[due] = False
            self._collected_ms = _gpu_ms(self._queries[due].elapsed)

    def measure(self, fn, gpu: bool | None = None) -> tuple[float, float | None]:
        """Run fn(); return (cpu_ms, gpu_ms or None). ``gpu``: time the GPU too (default: ``self.gpu``)."""
        if not (self.gpu if gpu is None else gpu):
            return cpu_ms(fn), None
        if self._queries is None:
            self._make_queries()
        if not self._queries:
            t0 = time.perf_counter()
            fn()
            cpu = (time.perf_counter() - t0) * 1e3
            self.ctx.finish()
            return cpu, (time.perf_counter() - t0) * 1e3
        query = self._queries[self._index]
        t0 = time.perf_counter()
        with query:
            fn()
        cpu = (time.perf_counter() - t0) * 1e3
        if not self.lagged:
            return cpu, _gpu_ms(query.elapsed)
        self._pending[self._index] = True
        self._index = (self._index + 1) % len(self._queries)
        gpu_ms, self._collected_ms = self._collected_ms, None
        if self._pending[self._index]:  # not collected: the ring's oldest (this pass LAG calls ago) is read now
            self._pending[self._index] = False
            gpu_ms = _gpu_ms(self._queries[self._index].elapsed)
        return cpu, gpu_ms


def _gpu_ms(elapsed_ns: int) -> float | None:
    # Some drivers answer a query they could not time (e.g. across a shader compile) with 2³²−1 ns.
    return None if elapsed_ns >= 0xFFFFFFFF else elapsed_ns * 1e-6
