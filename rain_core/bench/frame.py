"""Whole frames at heavy rain: CPU ms outside the GL driver, GL calls and bytes uploaded per frame, by effect.

``python -m rain_core.bench frame [--quick] [--size 320x180] [--budgets 10000,50000] [--frames 30]``

Each case is a whole ``Scene`` (``rain_core.scene``) on a headless context: heavy rain 8 mm/h, wetness, cracks
and puddles pinned at 1, the driver camera, noon, the default traffic, the ego car parked (braked, 0 km/h) or
at 100 km/h (autopilot), for the streak budgets ``quality.particle_budget`` 10k, 50k, 200k and 1M. The frame is
small (default 320×180) so llvmpipe's emulated GPU work stays small: what is measured is the CPU side.

Method (also printed in the header):

* Every moderngl method that enters the driver is wrapped, at class level, by a counting wrapper that adds to
  the current bucket the call, the bytes written and the time spent inside it: ``VertexArray.render``,
  ``Buffer.write/read/orphan``, ``Texture.write/read/use/build_mipmaps`` (and the 3D, array and cube kinds),
  ``Framebuffer.use/clear/read`` and its viewport/scissor setters, ``Uniform.write/read`` (every uniform write,
  ``prog[name].value = …`` included), ``Context.enable/disable/clear/finish/blend_func/…`` and object creation,
  ``Query`` begin/end/elapsed (timer queries are counted apart from the other calls). A call made inside
  another wrapped call counts once.
* Buckets are the renderer's passes: ``Renderer._timed(name, fn)`` is wrapped to switch the bucket, so a GL
  call lands in the pass that made it; ``Scene.step`` is its own bucket ("sim: scene.step"); what the renderer
  does between passes is "renderer (between passes)".
* CPU ms outside the driver of a pass = its CPU time — measured around its ``Renderer._timed`` call, i.e.
  what the renderer's ``PassStat.cpu_ms`` covers — minus the time inside wrapped GL calls of that pass minus the
  wrapper's own cost outside the time it records (measured at start-up on a no-op, per call). The renderer reads
  the timer queries before the frame's first pass (``PassTimer.collect``): "renderer (between passes)" holds
  them, with their waits counted inside GL (trees before 27b694d read each after its pass). ``Scene.step`` is
  timed alone the same way. The whole frame is the time of ``Scene.step`` + ``Scene.render`` minus all time
  inside wrapped calls (and the wrapper cost).
* "GPU ms" is the pass's GPU time from the renderer's timer queries (read two frames late, so nothing stalls) and
  "GPU %" its share of the frame's; they need the timer queries, on by default here. On llvmpipe, which emulates
  the GPU on the CPU and defers draws to a later flush, only the ratios mean anything; on a real GPU both are
  real (the header names the driver). "rain GPU ms" in the summary is the sum over the rain's own effects
  (``RAIN_EFFECTS``: streaks and splashes, spray, drips, windshield, ripples); the wet road and the atmosphere
  are rows of their own.
* ``--pass-wall`` puts each pass's wall time between a ``ctx.finish()`` before it and one after it in the GPU
  columns instead (no timer queries): what the pass costs the device. On llvmpipe that is the honest per-pass
  figure: it does a draw's vertex work when the draw is issued, and its timer queries misplace it (at 1M streaks
  they gave the drips' pass ~500 ms of the streaks'). The CPU columns leave the waits out, but each pass then
  starts on the caches the wait left cold: not comparable with a run without it.
* Clock (``--clock``): by default the main thread's CPU time (``time.thread_time_ns``), so time the process
  spent waiting for a core — this machine is shared — and llvmpipe's own rasterizer threads do not count;
  ``--clock wall`` uses wall time. "ms inside GL" is then the main thread's CPU time inside the driver; the
  frame's wall time (step + render + ``ctx.finish()``) is always wall time. "CPU ms, all threads" in the summary
  is the CPU time of every thread of the process over the same span (``time.process_time``): the driver's thread
  and, on llvmpipe, its rasterizer threads included, so work that moved off the main thread still shows there.
* ``--skip-draws`` counts the draws (``VertexArray.render``/``transform``/``render_indirect``,
  ``build_mipmaps``) without entering the driver. llvmpipe runs a draw's vertex work on the calling thread, and
  Python's code and data are then cold for whatever follows (measured: the same glue costs 3–10× its warm time
  between draws). Without the draws, the CPU figures bracket what a GPU driver that works on threads of its own
  leaves to this thread. The pixels are meaningless then and the simulations run as usual. "auto" is
  resolved before, with the draws made (``auto_solver_with_draws``): timed without them, the GPU solver's steps
  would look free, and the case would time another solver than a run with draws.
* The driver thread: the context asks Mesa for its driver thread (``mesa_glthread``, see
  ``rain_core.gfx.driver``; the header says whether it runs). GL calls are then queued for that
  thread, and the draws' vertex work runs there, not on this thread. "ms inside GL" is the queueing plus what
  the calls that must wait for that thread wait for (e.g. reads, a texture written from memory, a buffer write
  over 8 KiB, object creation, a query read, ``finish``); such a call also runs, on this thread, the calls not
  yet handed to the driver thread. Run with ``mesa_glthread=false`` for the driver on this thread.
* Python lines (``--py-frames``, default 3): after the timed frames, a few more frames run under ``sys.settrace``
  and every Python line executed is counted in the bucket of the pass running it (the bench's own wrappers are
  left out), as are the Python calls (in the JSON); each bucket's median over those frames (a one-off, such as a
  kernel's first call, is left out). NumPy's and the compiled kernels' work is not counted: it runs
  in C. Unlike a time, the count is the same from run to run: a change to the frame's Python glue shows as an
  exact difference, while this machine's noise hides most of what a few hundred lines cost (~0.1–0.25 µs each
  here, more for code that has not run for a while).
* Every figure is the median over the measured frames after a warm-up (shader compiles, the ripples' backend
  choice and the rain's first fill happen there), except "worst frame, CPU ms": the whole frame's highest CPU ms
  outside GL among them (with ``--rounds``, among all rounds'), the stutter a median hides. The kernels cached
  on disk are loaded before the first frame, as the window does (``jit.preload``). ``--rounds N`` measures every
  case N times, one case after the other in each round, and reports the median of the rounds' medians, with the
  whole frame's lowest and highest CPU ms in the summary: on a shared machine one run of a case varies by more
  than most changes save.

It uses only APIs older trees have as well (``Scene``, ``set_value``, ``Renderer._timed``, ``PassStat``), so it
measures another checkout when run as a file from that checkout's root:
``cd /path/to/old && python /path/to/new/rain_core/bench/frame.py`` (the header prints which ``rain_core`` ran).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

if __name__ == "__main__":  # run as a file: measure the rain_core of the current directory, not this file's tree
    _here = os.path.dirname(os.path.abspath(__file__))
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or ".") != _here]
    sys.path.insert(0, os.getcwd())

import moderngl

from rain_core.checks import MAX_FRAME_DT_S

BUDGETS = (10_000, 50_000, 200_000, 1_000_000)
SPEEDS_KMH = (0.0, 100.0)
# The rain's own effects, whose GPU time the summary adds up ("all rain" in issue 13); the wet road and the
# atmosphere are drawn without rain too and keep rows of their own.
RAIN_EFFECTS = ("rainfall", "spray", "drips", "windshield", "ripples")
RAIN_MM_H = 8.0
# The wrappers below are the bench's, not the frame's: their lines are not counted (trace_python).
_OWN_FILE = os.path.abspath(__file__)
STEP_BUCKET = "sim: scene.step"
BETWEEN_BUCKET = "renderer (between passes)"
# CPU time of the main thread (not counting time the process waited for a core: this machine is shared, and
# llvmpipe's own threads do the emulated GPU work), or wall time.
CLOCKS = {"thread": time.thread_time_ns, "wall": time.perf_counter_ns}

# (class, attribute, kind, index of the data argument among the positional args (self = 0) or None)
# kind: "draw" | "upload" | "uniform" | "read" | "state" | "create" | "query"
_METHODS = [
    ("VertexArray", "render", "draw", None), ("VertexArray", "render_indirect", "draw", None),
    ("VertexArray", "transform", "draw", None),
    ("Buffer", "write", "upload", 1), ("Buffer", "write_chunks", "upload", 1), ("Buffer", "read", "read", None),
    ("Buffer", "read_into", "read", None), ("Buffer", "orphan", "state", None), ("Buffer", "clear", "state", None),
    ("Buffer", "bind_to_uniform_block", "state", None), ("Buffer", "bind_to_storage_buffer", "state", None),
    ("Framebuffer", "use", "state", None), ("Framebuffer", "clear", "state", None),
    ("Framebuffer", "read", "read", None), ("Framebuffer", "read_into", "read", None),
    ("Sampler", "use", "state", None),
    ("Context", "enable", "state", None), ("Context", "disable", "state", None),
    ("Context", "enable_only", "state", None), ("Context", "enable_direct", "state", None),
    ("Context", "disable_direct", "state", None), ("Context", "clear", "state", None),
    ("Context", "finish", "state", None), ("Context", "copy_buffer", "state", None),
    ("Context", "copy_framebuffer", "state", None), ("Context", "detect_framebuffer", "state", None),
    ("Context", "clear_samplers", "state", None), ("Context", "memory_barrier", "state", None),
    ("Context", "buffer", "create", 1), ("Context", "texture", "create", 3), ("Context", "depth_texture", "create", 2),
    ("Context", "texture_array", "create", 3), ("Context", "texture3d", "create", 3),
    ("Context", "framebuffer", "create", None), ("Context", "vertex_array", "create", None),
    ("Context", "simple_vertex_array", "create", None), ("Context", "program", "create", None),
    ("Context", "query", "create", None), ("Context", "sampler", "create", None),
    ("Context", "renderbuffer", "create", None), ("Context", "depth_renderbuffer", "create", None),
    ("Query", "__enter__", "query", None), ("Query", "__exit__", "query", None),
]
for _tex in ("Texture", "Texture3D", "TextureArray"):
    _METHODS += [(_tex, "write", "upload", 1), (_tex, "read", "read", None), (_tex, "read_into", "read", None),
                 (_tex, "use", "state", None), (_tex, "build_mipmaps", "draw", None),
                 (_tex, "bind_to_image", "state", None)]
_METHODS += [("TextureCube", "write", "upload", 2), ("TextureCube", "read", "read", None),
             ("TextureCube", "use", "state", None), ("TextureCube", "build_mipmaps", "draw", None)]
# Property setters (and one getter) that enter the driver.
_SETTERS = [
    ("Context", n, "state") for n in ("blend_func", "blend_equation", "depth_func", "viewport", "scissor",
                                      "front_face", "cull_face", "point_size", "line_width", "wireframe",
                                      "polygon_offset", "multisample", "provoking_vertex")
] + [("Framebuffer", n, "state") for n in ("viewport", "scissor", "color_mask", "depth_mask")] + [
    (t, n, "state") for t in ("Texture", "Texture3D", "TextureArray", "TextureCube", "Sampler")
    for n in ("filter", "repeat_x", "repeat_y", "repeat_z", "swizzle", "compare_func", "anisotropy")
] + [("VertexArray", "vertices", "state"), ("VertexArray", "instances", "state")]
_GETTERS = [("Query", "elapsed", "query")]


def _nbytes(data) -> int:
    """Bytes sent to the driver by a write of ``data`` (0 for a GPU-side source such as a moderngl Buffer)."""
    if data is None or isinstance(data, moderngl.Buffer):
        return 0
    if isinstance(data, bytes | bytearray):
        return len(data)
    nbytes = getattr(data, "nbytes", None)
    if nbytes is not None:
        return int(nbytes)
    try:
        return memoryview(data).nbytes
    except TypeError:
        return 0


class Tally:
    """What one bucket's wrapped GL calls did: calls and ns by kind, bytes uploaded / as uniforms / read back."""

    __slots__ = ("calls", "ns", "upload_bytes", "uniform_bytes", "read_bytes", "by_kind")

    def __init__(self):
        self.calls = 0
        self.ns = 0
        self.upload_bytes = 0
        self.uniform_bytes = 0
        self.read_bytes = 0
        self.by_kind: dict[str, int] = defaultdict(int)

    @property
    def gl_calls(self) -> int:
        """Calls other than timer queries."""
        return self.calls - self.by_kind.get("query", 0)


class GLCounter:
    """Wraps the driver-entering moderngl methods while active (a context manager); see the module docstring.

    ``bucket`` names where calls go now; ``tallies[bucket]`` is a ``Tally``. ``overhead_ns`` is the wrapper's
    own cost per call outside the time it measures (subtract calls × it from CPU times that include calls)."""

    def __init__(self, clock: str = "thread", skip_draws: bool = False):
        if clock not in CLOCKS:
            raise ValueError(f"clock must be one of {', '.join(CLOCKS)}, got {clock!r}")
        self.clock = clock
        self.skip_draws = bool(skip_draws)  # draws counted, not made (see the module docstring)
        self.clock_ns = CLOCKS[clock]
        self.tallies: dict[str, Tally] = defaultdict(Tally)
        self.pass_ms: dict[str, float] = {}  # wall ms of each Renderer._timed call this frame, by pass
        self.bucket = BETWEEN_BUCKET
        self._inside = False
        self._saved: list[tuple[type, str, object]] = []
        self.overhead_ns = 0.0

    def reset(self) -> None:
        self.tallies = defaultdict(Tally)
        self.pass_ms: dict[str, float] = {}

    def _wrap(self, fn, kind: str, data_index: int | None, data_kw: str = "data"):
        counter = self
        clock = self.clock_ns
        if kind == "draw" and self.skip_draws:
            def skipped(*args, **kwargs):
                return None

            fn = skipped

        def wrapper(*args, **kwargs):
            if counter._inside:  # a wrapped call made by another: counted once, by the outer one
                return fn(*args, **kwargs)
            counter._inside = True
            result = None
            t0 = clock()
            try:
                result = fn(*args, **kwargs)
                return result
            finally:
                dt = clock() - t0
                counter._inside = False
                tally = counter.tallies[counter.bucket]
                tally.calls += 1
                tally.ns += dt
                tally.by_kind[kind] += 1
                if kind == "read" and isinstance(result, bytes):
                    tally.read_bytes += len(result)
                if data_index is not None:
                    data = args[data_index] if len(args) > data_index else kwargs.get(data_kw)
                    n = _nbytes(data)
                    if kind == "uniform":
                        tally.uniform_bytes += n
                    else:
                        tally.upload_bytes += n

        wrapper.__wrapped__ = fn
        return wrapper

    def _patch(self, cls, name: str, value) -> None:
        self._saved.append((cls, name, cls.__dict__[name]))
        setattr(cls, name, value)

    def __enter__(self):
        import _moderngl

        for cls_name, attr, kind, data_index in _METHODS:
            cls = getattr(moderngl, cls_name, None)
            if cls is not None and attr in cls.__dict__:
                self._patch(cls, attr, self._wrap(cls.__dict__[attr], kind, data_index))
        for cls_name, attr, kind in _SETTERS:
            cls = getattr(moderngl, cls_name, None)
            prop = None if cls is None else cls.__dict__.get(attr)
            if isinstance(prop, property) and prop.fset is not None:
                self._patch(cls, attr, property(prop.fget, self._wrap(prop.fset, kind, None), prop.fdel))
        for cls_name, attr, kind in _GETTERS:
            cls = getattr(moderngl, cls_name, None)
            prop = None if cls is None else cls.__dict__.get(attr)
            if isinstance(prop, property):
                self._patch(cls, attr, property(self._wrap(prop.fget, kind, None), prop.fset, prop.fdel))
        uniform = _moderngl.Uniform  # prog[name].value = … goes through Uniform.write
        self._patch(uniform, "write", self._wrap(uniform.__dict__["write"], "uniform", 1))
        self._patch(uniform, "read", self._wrap(uniform.__dict__["read"], "read", None))
        self.overhead_ns = self._calibrate()
        return self

    def __exit__(self, *exc):
        while self._saved:
            cls, name, value = self._saved.pop()
            setattr(cls, name, value)
        return False

    def _calibrate(self, n: int = 50_000) -> float:
        """The wrapper's cost per call outside the time it records (ns): wrap a no-op, time n calls."""
        def noop(*args, **kwargs):
            return None

        wrapped = self._wrap(noop, "state", None)
        saved_bucket, self.bucket = self.bucket, "_calibrate"
        best = math.inf
        for _ in range(3):
            self.tallies.pop("_calibrate", None)
            t0 = self.clock_ns()
            for _ in range(n):
                wrapped(1)
            total = self.clock_ns() - t0
            best = min(best, (total - self.tallies["_calibrate"].ns) / n)
        self.tallies.pop("_calibrate", None)
        self.bucket = saved_bucket
        return max(best, 0.0)


def trace_python(counter: GLCounter, run_frame, frames: int) -> tuple[dict[str, float], dict[str, float]]:
    """(Python lines, Python calls) executed per frame by bucket, each bucket's median over ``frames`` calls of
    ``run_frame()`` under ``sys.settrace`` (a one-off in one frame, such as a kernel's first call loading it from
    the disk cache, is left out from three frames on): each line and call counts in ``counter.bucket`` as it is
    when it runs. Lines of this file (the GL counter's wrappers, the pass timer) are not counted, nor what runs
    in C (NumPy, the kernels, the driver). Tracing slows Python ~10×: run it after the timed frames."""
    lines: dict[str, int] = defaultdict(int)
    calls: dict[str, int] = defaultdict(int)

    def on_line(frame, event, arg):
        if event == "line":
            lines[counter.bucket] += 1
        return on_line

    def on_call(frame, event, arg):
        if frame.f_code.co_filename == _OWN_FILE:
            return None  # no line events in the bench's own frames
        calls[counter.bucket] += 1
        return on_line

    per_frame = []
    previous = sys.gettrace()
    for _ in range(frames):
        lines.clear()
        calls.clear()
        sys.settrace(on_call)
        try:
            run_frame()
        finally:
            sys.settrace(previous)
        per_frame.append((dict(lines), dict(calls)))

    def medians(which: int) -> dict[str, float]:
        buckets = set().union(*(counts[which] for counts in per_frame))
        return {b: float(statistics.median(counts[which].get(b, 0) for counts in per_frame)) for b in buckets}

    return medians(0), medians(1)


def heavy_rain_settings(budget: int, rate_mm_h: float = RAIN_MM_H, camera: str = "driver"):
    """Settings of the benchmark: rate mm/h, wetness/cracks/puddles pinned at 1, the camera, the streak budget."""
    from rain_core.settings import Settings, set_value

    settings = Settings()
    set_value(settings, "rain.rate_mm_h", rate_mm_h)
    for level in ("wetness", "cracks", "puddles"):
        set_value(settings, f"rain.{level}", 1.0)
    set_value(settings, "camera.mode", camera)
    set_value(settings, "time_of_day.hour", 12.0)
    set_value(settings, "quality.particle_budget", int(budget))
    return settings


def with_overrides(settings, overrides):
    """``settings`` with each (path, value) of ``overrides`` set through ``set_value`` (which validates it)."""
    from rain_core.settings import set_value

    for path, value in overrides:
        set_value(settings, path, value)
    return settings


def parse_override(text: str) -> tuple[str, object]:
    """``PATH=VALUE`` (``--set``): the value is read as a TOML value, as in a scenario file (``0.5``, ``true``,
    ``"chase"``); a bare word that is not TOML is taken as a string (``camera.mode=chase``)."""
    import tomllib

    path, sep, raw = text.partition("=")
    if not sep or not path.strip():
        raise argparse.ArgumentTypeError(f"--set takes PATH=VALUE (e.g. atmosphere.scatter_lights=2), got {text!r}")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return path.strip(), value


def check_overrides(p: argparse.ArgumentParser, overrides) -> None:
    """``--set``'s (path, value) pairs validated before any frame is drawn: a parser error naming the setting."""
    if not overrides:
        return
    from rain_core.settings import Settings, SettingsError

    if any(path == "quality.render_scale" for path, _ in overrides):
        p.error("--set quality.render_scale: it scales a window's frame; the bench draws --size (pass a smaller "
                "--size instead)")
    try:
        with_overrides(Settings(), overrides)
    except SettingsError as exc:
        p.error(f"--set: {exc}")


class _Brake:
    """A drive input that holds the car still (the parked case)."""

    throttle, brake, steer, reverse = 0.0, 1.0, 0.0, False


def heavy_rain_case(ctx, size, budget: int, speed_kmh: float, seed: int = 1, overrides=(), gpu_timing=False):
    """A case's scene: ``heavy_rain_settings(budget)`` and ``overrides`` at ``size`` px, the ego car parked (braked)
    or driven at ``speed_kmh`` km/h by the autopilot, the cached kernels loaded. Returns (scene, the drive input
    each ``scene.step`` takes)."""
    from rain_core.scene import Scene

    scene = Scene(ctx, size, settings=with_overrides(heavy_rain_settings(budget), overrides), seed=seed,
                  gpu_timing=gpu_timing)
    _preload_kernels()
    speed = speed_kmh / 3.6
    scene.ego.speed_m_s = speed
    if speed > 0.0:
        scene.autopilot.target_speed_m_s = speed
    return scene, (_Brake() if speed == 0.0 else None)


def _effect_of(pass_name: str) -> str:
    return pass_name.split(".", 1)[0] if "." in pass_name else pass_name


def measure_case(ctx, size=(320, 180), budget: int = 50_000, speed_kmh: float = 0.0, frames: int = 30,
                 warmup: int = 8, gpu_timing: bool = True, dt_s: float = 1.0 / 30.0, seed: int = 1,
                 counter: GLCounter | None = None, ripples_backend: str = "auto", overrides=(),
                 py_frames: int = 3, draw: bool = True, pass_wall: bool = False) -> dict:
    """Render ``warmup + frames`` frames of one case; medians over the last ``frames``. ``ripples_backend``:
    the ripples effect's solver ("auto" times the paths on this machine; on llvmpipe it picks numpy32).
    ``overrides``: (settings path, value) pairs set on top of the heavy-rain settings (``--set``). ``py_frames``:
    frames traced after the timed ones for the Python lines and calls (``trace_python``; 0: none). ``draw``
    False: frames nobody looks at (``Renderer.render(frame, draw=False)``: the updates and the state stages).
    ``pass_wall``: each pass's wall time between a ``ctx.finish()`` before it and one after it, as its "GPU ms"
    (``--pass-wall``; the CPU columns leave the waits out, but each pass then starts on cold caches: not comparable
    with a run without it).

    Returns {"rows": {name: {cpu_ms, gl_ms, gl_calls, queries, upload_kb, uniform_kb, read_kb, gpu_ms, gpu_share}},
    "frame": {…the same for the whole frame…, wall_ms}, "passes": [pass names in order], …}. Rows are the
    renderer's passes, the scene's step, what the renderer does between passes, and effect totals
    ("effect: NAME")."""
    from rain_core.gfx.renderer import Renderer

    own_counter = counter is None
    counter = counter or GLCounter()
    if own_counter:
        counter.__enter__()
    original_timed = Renderer._timed
    clock = counter.clock_ns

    walls: dict[str, float] = {}  # --pass-wall: this frame's pass → wall ms between the finishes around it
    frame_waited = [0]  # --pass-wall: ns this frame's finishes took on this thread (not the frame's CPU)

    def walled(name, fn, waited):
        def wait():  # neither a GL call of the pass nor its CPU time
            counter.bucket = "finish"
            c0 = clock()
            ctx.finish()
            waited[0] += clock() - c0
            frame_waited[0] += clock() - c0
            counter.bucket = name

        def run():
            wait()
            w0 = time.perf_counter()
            fn()
            wait()
            walls[name] = walls.get(name, 0.0) + (time.perf_counter() - w0) * 1e3
        return run

    def timed(self, name, fn):
        saved, counter.bucket = counter.bucket, name
        waited = [0]  # ns the finishes took on this thread (--pass-wall)
        t0 = clock()
        try:
            return original_timed(self, name, walled(name, fn, waited) if pass_wall else fn)
        finally:
            counter.pass_ms[name] = counter.pass_ms.get(name, 0.0) + (clock() - t0 - waited[0]) * 1e-6
            counter.bucket = saved

    Renderer._timed = timed
    scene = None
    # (a tree before undrawn frames has no draw argument: measured drawn only)
    render = (lambda: scene.render()) if draw else (lambda: scene.render(draw=False))
    try:
        scene, drive = heavy_rain_case(ctx, size, budget, speed_kmh, seed, overrides, gpu_timing)
        for effect in scene.effects:
            if effect.name == "ripples":
                effect.backend = ripples_backend  # read when the field is built, on the first active frame
        samples: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
        order: list[str] = []
        for index in range(warmup + frames):
            counter.reset()
            walls.clear()
            frame_waited[0] = 0
            counter.bucket = STEP_BUCKET
            wall0 = time.perf_counter()
            process0 = time.process_time_ns()
            t0 = clock()
            scene.step(dt_s, drive)
            t1 = clock()
            counter.bucket = BETWEEN_BUCKET
            render()
            t2 = clock()
            counter.bucket = "finish"
            ctx.finish()
            wall = (time.perf_counter() - wall0) * 1e3
            process = (time.process_time_ns() - process0) * 1e-6
            counter.bucket = BETWEEN_BUCKET
            if index < warmup:
                continue
            _collect(samples, order, scene.renderer.stats, counter, (t1 - t0) * 1e-6,
                     (t2 - t1 - frame_waited[0]) * 1e-6, wall, process, walls if pass_wall else None)

        def run_frame() -> None:  # one more frame of the case, its calls and lines sorted as the timed ones'
            counter.reset()
            counter.bucket = STEP_BUCKET
            scene.step(dt_s, drive)
            counter.bucket = BETWEEN_BUCKET
            render()
            counter.bucket = "finish"
            ctx.finish()
            counter.bucket = BETWEEN_BUCKET

        py_lines, py_calls = trace_python(counter, run_frame, py_frames) if py_frames > 0 else (None, None)
        field = next((getattr(e, "field", None) for e in scene.effects if e.name == "ripples"), None)
        solver = getattr(field, "backend", None) or "not built"  # what "auto" chose
    finally:
        Renderer._timed = original_timed
        if scene is not None:
            scene.release()
        if own_counter:
            counter.__exit__(None, None, None)
    rows = {name: {key: statistics.median(values) for key, values in cols.items()} for name, cols in samples.items()}
    frame = rows.pop("frame")
    frame["cpu_ms_max"] = max(samples["frame"]["cpu_ms"])
    if py_lines is not None:
        _add_python(rows, frame, py_lines, py_calls)
    return {"size": tuple(size), "budget": int(budget), "speed_kmh": float(speed_kmh), "frames": frames,
            "ripples_backend": ripples_backend, "ripples_solver": solver, "skip_draws": counter.skip_draws,
            "drawn": bool(draw),
            "warmup": warmup, "dt_s": float(dt_s), "gpu_timing": gpu_timing or pass_wall,
            "gpu_source": "finish" if pass_wall else "timer queries", "overhead_ns": counter.overhead_ns,
            "clock": counter.clock,
            "passes": order,
            "rows": rows, "frame": frame}


def _preload_kernels() -> None:
    """Load the cached kernels before the first frame, as the window does (``jit.preload``; a tree without it
    loads each on its first call, in the frames)."""
    from rain_core import jit

    preload = getattr(jit, "preload", None)
    if preload is not None:
        preload()


def _collect(samples, order, stats, counter: GLCounter, step_ms: float, render_ms: float, wall_ms: float,
             process_ms: float, walls: dict | None = None) -> None:
    """Add one frame's figures to ``samples`` (name → column → list); ``process_ms``: the CPU time of all the
    process's threads over the frame (step, render and finish); ``walls``: pass → wall ms between the finishes
    around it (``--pass-wall``), the passes' "GPU ms" instead of their timer queries'."""
    ovh_ms = counter.overhead_ns * 1e-6
    tallies = counter.tallies
    if walls is not None:
        stats = [dataclasses.replace(s, gpu_ms=walls.get(s.name, 0.0)) for s in stats]
    total_gpu = sum(s.gpu_ms for s in stats if s.ran and s.gpu_ms is not None) or math.nan

    def row(tally: Tally, cpu_ms: float) -> dict:
        gl_ms = tally.ns * 1e-6
        return {"cpu_ms": max(cpu_ms - gl_ms - tally.calls * ovh_ms, 0.0), "gl_ms": gl_ms,
                "gl_calls": tally.gl_calls, "queries": tally.calls - tally.gl_calls,
                "uniform_writes": tally.by_kind.get("uniform", 0),
                "upload_kb": tally.upload_bytes / 1024, "uniform_kb": tally.uniform_bytes / 1024,
                "read_kb": tally.read_bytes / 1024}

    def add(name: str, values: dict) -> None:
        if name not in order and name != "frame":
            order.append(name)
        for key, value in values.items():
            samples[name][key].append(value)

    empty = Tally()
    pass_cpu = 0.0
    effects: dict[str, dict] = {}
    for stat in stats:
        if not stat.ran:
            continue
        wall = counter.pass_ms.get(stat.name, stat.cpu_ms)
        pass_cpu += wall
        values = row(tallies.get(stat.name, empty), wall)
        values["gpu_ms"] = stat.gpu_ms or 0.0
        values["gpu_share"] = values["gpu_ms"] / total_gpu * 100.0
        add(stat.name, values)
        effect = _effect_of(stat.name)
        if effect != stat.name:
            acc = effects.setdefault(effect, dict.fromkeys(values, 0.0))
            for key, value in values.items():
                acc[key] += value
    no_gpu = {"gpu_ms": 0.0, "gpu_share": 0.0}
    add(STEP_BUCKET, {**row(tallies.get(STEP_BUCKET, empty), step_ms), **no_gpu})
    add(BETWEEN_BUCKET, {**row(tallies.get(BETWEEN_BUCKET, empty), render_ms - pass_cpu), **no_gpu})
    for effect, acc in effects.items():
        add(f"effect: {effect}", acc)
    total = Tally()
    for name, tally in tallies.items():
        if name == "finish":  # ctx.finish after the frame waits for llvmpipe: in the wall time, not the CPU
            continue
        total.calls += tally.calls
        total.ns += tally.ns
        total.upload_bytes += tally.upload_bytes
        total.uniform_bytes += tally.uniform_bytes
        total.read_bytes += tally.read_bytes
        for kind, n in tally.by_kind.items():
            total.by_kind[kind] += n
    rain_gpu = sum(acc["gpu_ms"] for effect, acc in effects.items() if effect in RAIN_EFFECTS)
    add("frame", {**row(total, step_ms + render_ms), "gpu_ms": total_gpu, "gpu_share": 100.0,
                  "rain_gpu_ms": rain_gpu, "wall_ms": wall_ms, "process_cpu_ms": process_ms})


def _add_python(rows: dict, frame: dict, lines: dict, calls: dict) -> None:
    """``py_lines`` and ``py_calls`` (per frame, ``trace_python``'s medians) into each pass's row, the effects'
    totals and the whole frame (the sum over every bucket but the wait at ``finish``, as for the CPU). A pass
    without a row (an idle effect's observe: the renderer keeps no stat of it) counts between the passes, as its
    CPU time does."""
    lines, calls = dict(lines), dict(calls)
    if BETWEEN_BUCKET in rows:
        for bucket in [b for b in lines.keys() | calls.keys() if b not in rows and b != "finish"]:
            lines[BETWEEN_BUCKET] = lines.get(BETWEEN_BUCKET, 0.0) + lines.pop(bucket, 0.0)
            calls[BETWEEN_BUCKET] = calls.get(BETWEEN_BUCKET, 0.0) + calls.pop(bucket, 0.0)
    effects: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
    for name, row in rows.items():
        if name.startswith("effect: "):
            continue
        row["py_lines"], row["py_calls"] = lines.get(name, 0.0), calls.get(name, 0.0)
        effect = _effect_of(name)
        if effect != name:
            effects[effect][0] += row["py_lines"]
            effects[effect][1] += row["py_calls"]
    for effect, (n_lines, n_calls) in effects.items():
        row = rows.get(f"effect: {effect}")
        if row is not None:
            row["py_lines"], row["py_calls"] = n_lines, n_calls
    frame["py_lines"] = sum(v for k, v in lines.items() if k != "finish")
    frame["py_calls"] = sum(v for k, v in calls.items() if k != "finish")


def combine_rounds(rounds: list[dict]) -> dict:
    """One case measured ``len(rounds)`` times (``--rounds``) as one result: every figure is the median over the
    rounds of the rounds' medians, and ``cpu_ms_range`` the lowest and highest whole-frame CPU ms outside GL of
    the rounds. On a shared machine the same case varies from run to run by more than a change measures; the
    rounds, alternated with the other cases, and their spread say how far to trust a difference."""
    first = rounds[0]
    if len(rounds) == 1:
        return first

    def median_rows(rows: list[dict]) -> dict:
        return {key: statistics.median(r[key] for r in rows) for key in rows[0]}

    names = [n for n in first["passes"] if all(n in r["rows"] for r in rounds)]
    cpu = [r["frame"]["cpu_ms"] for r in rounds]
    frame = median_rows([r["frame"] for r in rounds])
    frame["cpu_ms_max"] = max(r["frame"]["cpu_ms_max"] for r in rounds)  # the worst frame of them all
    return {**first, "passes": names, "rows": {n: median_rows([r["rows"][n] for r in rounds]) for n in names},
            "frame": frame, "rounds": len(rounds),
            "cpu_ms_range": (min(cpu), max(cpu)),
            "ripples_solver": "/".join(sorted({str(r["ripples_solver"]) for r in rounds}))}


# --- report ------------------------------------------------------------------------------------------------

_COLUMNS = (("CPU ms outside GL", "cpu_ms", "{:.2f}"), ("Python lines", "py_lines", "{:.0f}"),
            ("GL calls", "gl_calls", "{:.0f}"),
            ("uniform writes", "uniform_writes", "{:.0f}"),
            ("upload KB", "upload_kb", "{:.1f}"), ("uniform KB", "uniform_kb", "{:.1f}"),
            ("ms inside GL", "gl_ms", "{:.2f}"), ("GPU ms", "gpu_ms", "{:.3f}"), ("GPU %", "gpu_share", "{:.0f}"))
_GPU_KEYS = ("gpu_ms", "gpu_share")


def _table(headers, rows) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(str(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def case_label(result: dict) -> str:
    label = f"{result['speed_kmh']:g} km/h, budget {result['budget']:,}"
    solver = result.get("ripples_solver")
    return label if solver is None or solver == result.get("ripples_backend") else f"{label}, ripples {solver}"


def case_table(result: dict) -> str:
    """One case: a row per pass, the step, the renderer between passes, the effect totals, the whole frame."""
    names = [n for n in result["passes"] if not n.startswith("effect: ")]
    names += [n for n in result["passes"] if n.startswith("effect: ")]
    def cells(r: dict) -> list[str]:  # "-": GPU columns without timer queries, Python lines not traced
        return [fmt.format(r[key]) if key in r and (key not in _GPU_KEYS or result["gpu_timing"]) else "-"
                for _, key, fmt in _COLUMNS]

    body = [[name] + cells(result["rows"][name]) for name in names]
    body.append(["**whole frame**"] + cells(result["frame"]))
    return _table(["pass"] + [c[0] for c in _COLUMNS], body)


def _cpu_with_range(result: dict) -> str:
    """The whole frame's CPU ms outside GL, with the rounds' lowest and highest when there were several."""
    text = f"{result['frame']['cpu_ms']:.2f}"
    if "cpu_ms_range" in result:
        lo, hi = result["cpu_ms_range"]
        text += f" [{lo:.2f}–{hi:.2f}]"
    return text


def summary_table(results: list[dict]) -> str:
    body = [[f"{r['speed_kmh']:g}", f"{r['budget']:,}", _cpu_with_range(r), f"{r['frame']['cpu_ms_max']:.2f}", _py(r),
             f"{r['frame']['gl_calls']:.0f}", f"{r['frame'].get('uniform_writes', 0):.0f}",
             f"{r['frame']['upload_kb']:.1f}", f"{r['frame']['uniform_kb']:.1f}",
             f"{r['frame']['gl_ms']:.1f}", f"{r['frame']['wall_ms']:.1f}",
             f"{r['frame'].get('process_cpu_ms', math.nan):.1f}", _gpu(r, "gpu_ms"), _gpu(r, "rain_gpu_ms")]
            for r in results]
    return _table(["km/h", "streak budget", "CPU ms outside GL", "worst frame, CPU ms", "Python lines / calls",
                   "GL calls", "uniform writes", "upload KB",
                   "uniform KB", "ms inside GL", "frame wall ms", "CPU ms, all threads", "GPU ms", "rain GPU ms"],
                  body)


def _py(result: dict) -> str:
    frame = result["frame"]
    return f"{frame['py_lines']:.0f} / {frame['py_calls']:.0f}" if "py_lines" in frame else "-"


def _gpu(result: dict, key: str) -> str:
    value = result["frame"].get(key)
    return f"{value:.3f}" if result["gpu_timing"] and value is not None and math.isfinite(value) else "-"


def gl_description(ctx) -> str:
    """The GL driver in words: ``gfx.driver.describe_driver`` (renderer, Mesa's version, whether its driver thread
    runs); in an older tree without it, the renderer and what the environment asked of Mesa."""
    try:
        from rain_core.gfx.driver import describe_driver
    except ImportError:
        return f"{ctx.info.get('GL_RENDERER', '?')}, mesa_glthread={os.environ.get('mesa_glthread', 'unset')}"
    return describe_driver(ctx)


def auto_solver_with_draws(ctx, overrides=()) -> str:
    """The ripples solver "auto" picks on this machine for the heavy-rain settings, timed with its draws made.
    Under ``--skip-draws`` the GPU solver's steps would be skipped too and "auto" would pick it as free: the case
    would then time another solver than a run with draws (on llvmpipe: the GPU solver instead of numpy32).
    "auto" in an older tree without ``auto_backend``."""
    try:
        from rain_core.effects.ripples.backend import auto_backend
    except ImportError:
        return "auto"
    settings = with_overrides(heavy_rain_settings(BUDGETS[0]), overrides)
    return auto_backend(ctx, settings.quality.ripple_grid, settings.ripples.extent_m, settings.ripples.speed_m_s)[0]


def header(args, overhead_ns: float, renderer: str = "?") -> str:
    import rain_core

    try:
        from rain_core import jit

        path = jit.describe()
    except ImportError:  # an older tree, measured by running this file
        path = "NumPy (no rain_core.jit in this tree)"

    return (f"# Whole frames at heavy rain ({RAIN_MM_H:g} mm/h, wetness/cracks/puddles 1, driver camera, noon), "
            f"{args.size[0]}x{args.size[1]}, {getattr(args, 'fps', 30.0):g} frames/s, ripples backend "
            f"{args.ripples_backend}"
            + (", draws skipped (--skip-draws; the solver as auto picks it with draws)"
               if getattr(args, "skip_draws", False) else "")
            + (", frames not drawn (--undrawn: the updates and the effects' state stages alone)"
               if getattr(args, "undrawn", False) else "")
            + "".join(f", {path} = {value!r}" for path, value in getattr(args, "overrides", ())) + "\n\n"
            f"rain_core: {Path(rain_core.__file__).parent}; CPU simulations: {path}; GL: {renderer}\n\n"
            "Method: moderngl's driver-entering methods (draws, buffer/texture writes and reads, texture and "
            "framebuffer binds, uniform writes, context state, object creation, timer queries) are wrapped by "
            "counters of calls, bytes written and time inside; CPU outside GL = the pass's CPU time (measured around "
            "Renderer._timed: PassStat.cpu_ms; or Scene.step timed alone; the timer queries are read before the "
            "first pass, in 'renderer (between passes)') minus the time "
            "inside wrapped calls minus the wrapper's own cost "
            f"({overhead_ns / 1e3:.2f} µs a call, measured). Clock: {args.clock} "
            f"({'main-thread CPU time' if args.clock == 'thread' else 'wall time'}). Medians over {args.frames} "
            f"frames after "
            f"{args.warmup} warm-up frames"
            + (f"; {args.rounds} rounds, the cases alternated: the median of the rounds' medians, the summary's "
               "range the rounds' lowest and highest" if getattr(args, "rounds", 1) > 1 else "")
            + (f"; Python lines and calls: {args.py_frames} more frames traced (sys.settrace), each pass's median, "
               "the bench's own wrappers left out" if getattr(args, "py_frames", 0) else "")
            + ". GL calls exclude timer queries; "
            + ("GPU ms = the pass's wall time between a ctx.finish() before it and one after it (--pass-wall: "
               "what the pass costs the device, its vertex work included, which llvmpipe does when a draw is issued "
               "and its timer queries misplace; the CPU columns leave the waits out but run cold: not comparable), "
               if getattr(args, "pass_wall", False) else
               "GPU ms = the pass's timer-query time (on llvmpipe, which emulates the GPU on the CPU and defers "
               "draws, compare ratios only; --pass-wall for each pass's wall time), ")
            + "GPU % its share of the frame's; rain GPU ms = " + " + ".join(RAIN_EFFECTS) + ".\n")


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--size must be WxH, got {text!r}") from None
    if not (1 <= w <= 8192 and 1 <= h <= 8192):
        raise argparse.ArgumentTypeError(f"--size must be within 1..8192 per side, got {text!r}")
    return w, h


def parse_budgets(text: str) -> tuple[int, ...]:
    try:
        values = tuple(int(float(v)) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--budgets must be comma-separated integers, got {text!r}") from None
    if not values or any(not 0 <= v <= 1_000_000 for v in values):
        raise argparse.ArgumentTypeError(f"--budgets must be in [0, 1000000], got {text!r}")
    return values


def parse_args(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m rain_core.bench frame", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="bench_out", help="folder for frame.md and frame.json")
    p.add_argument("--quick", action="store_true", help="budgets 10k and 1M, 6 frames after 4 warm-up frames")
    p.add_argument("--size", type=parse_size, default=(320, 180), help="frame size WxH (default 320x180)")
    p.add_argument("--budgets", type=parse_budgets, default=None, help="streak budgets, e.g. 10000,1000000")
    p.add_argument("--speeds", default=None, help="ego speeds in km/h, e.g. 0,100 (default both)")
    p.add_argument("--frames", type=int, default=None, help="measured frames per case (default 30)")
    p.add_argument("--warmup", type=int, default=None, help="warm-up frames per case (default 8)")
    p.add_argument("--fps", type=float, default=30.0,
                   help="frames per simulated second, 4-240: each frame steps the scene 1/FPS s (default 30, the "
                        "headless recording's rate; a window follows its display, 60 on most)")
    p.add_argument("--rounds", type=int, default=1,
                   help="measure every case this many times, the cases alternated; report the median of the rounds "
                        "and the whole frame's CPU range (default 1)")
    p.add_argument("--clock", choices=tuple(CLOCKS), default="thread",
                   help="thread: the main thread's CPU time (default; robust on a shared machine); wall: wall time")
    p.add_argument("--ripples-backend", choices=("auto", "numpy32", "gpu", "reference"), default="auto",
                   help="the ripples solver (auto: timed at start; on llvmpipe numpy32 wins)")
    # Inline, not bench._common's: this file also measures older trees (run as a file), whose rain_core lacks it.
    p.add_argument("--jit", choices=("auto", "on", "off"), default="auto",
                   help="the CPU simulations' compiled kernels (auto: on where Numba is installed; off: their NumPy "
                        "twins, for before/after on one tree)")
    p.add_argument("--set", dest="overrides", type=parse_override, action="append", default=[],
                   metavar="PATH=VALUE", help="a setting on top of the heavy-rain ones, by its settings path, e.g. "
                                              "atmosphere.scatter_lights=2 (repeatable)")
    p.add_argument("--no-gpu-timing", dest="gpu_timing", action="store_false",
                   help="leave the renderer's timer queries off (no GPU columns)")
    p.add_argument("--py-frames", type=int, default=3,
                   help="frames traced after the timed ones for the Python lines and calls per pass, their median "
                        "(default 3; 0: none)")
    p.add_argument("--skip-draws", action="store_true",
                   help="count the draws without making them: the CPU figures without llvmpipe's vertex work on "
                        "this thread (pixels meaningless; see the module docstring)")
    p.add_argument("--pass-wall", action="store_true",
                   help="each pass's wall time between two ctx.finish() in the GPU columns, instead of timer "
                        "queries: what each pass costs llvmpipe, vertex work included (the CPU columns then run "
                        "cold: not comparable)")
    p.add_argument("--undrawn", action="store_true",
                   help="frames nobody looks at (Session.step(draw=False), a headless run's frames before its "
                        "screenshot): the simulations and their state stages, no view drawn")
    args = p.parse_args(argv)
    if args.jit != "auto":
        try:
            from rain_core import jit

            jit.set_active(args.jit == "on")
        except (ImportError, RuntimeError) as exc:  # an older tree has no kernels at all
            p.error(f"--jit {args.jit}: {exc}")
    args.budgets = args.budgets or ((10_000, 1_000_000) if args.quick else BUDGETS)
    args.speeds = tuple(float(v) for v in args.speeds.split(",")) if args.speeds else SPEEDS_KMH
    args.frames = args.frames or (6 if args.quick else 30)
    args.warmup = args.warmup or (4 if args.quick else 8)
    if args.frames < 1 or args.warmup < 0:
        p.error("--frames must be >= 1 and --warmup >= 0")
    lowest = 1.0 / MAX_FRAME_DT_S  # a longer step is clamped by the scene: not the rate the header would name
    if not lowest <= args.fps <= 240.0:  # (also rejects NaN)
        p.error(f"--fps must be in [{lowest:g}, 240] frames/s, got {args.fps}")
    if not 0 <= args.py_frames <= 100:
        p.error(f"--py-frames must be in [0, 100], got {args.py_frames}")
    if not 1 <= args.rounds <= 100:
        p.error(f"--rounds must be in [1, 100], got {args.rounds}")
    if args.pass_wall and args.skip_draws:
        p.error("--pass-wall times the draws that --skip-draws leaves out: give one of them")
    if args.pass_wall:
        args.gpu_timing = False  # the finishes time the passes; no timer queries beside them
    check_overrides(p, args.overrides)
    return args


def main(argv=None) -> int:
    from rain_core.gl import create_headless_context

    args = parse_args(argv)
    ctx = create_headless_context()
    if args.skip_draws and args.ripples_backend == "auto":
        args.ripples_backend = auto_solver_with_draws(ctx, args.overrides)
    results = []
    with GLCounter(args.clock, skip_draws=args.skip_draws) as counter:
        renderer = gl_description(ctx)
        print(header(args, counter.overhead_ns, renderer), flush=True)
        cases = [(speed, budget) for speed in args.speeds for budget in args.budgets]
        rounds: dict[tuple, list] = {case: [] for case in cases}
        for index in range(args.rounds):  # every case once a round: a slow spell of the machine hits them all
            for speed, budget in cases:
                result = measure_case(ctx, args.size, budget, speed, args.frames, args.warmup, args.gpu_timing,
                                      counter=counter, ripples_backend=args.ripples_backend,
                                      overrides=args.overrides, py_frames=args.py_frames, dt_s=1.0 / args.fps,
                                      draw=not args.undrawn, pass_wall=args.pass_wall)
                rounds[(speed, budget)].append(result)
                if args.rounds > 1:
                    print(f"round {index + 1}/{args.rounds}, {case_label(result)}: "
                          f"{result['frame']['cpu_ms']:.2f} ms outside GL", flush=True)
                if index == args.rounds - 1:  # the case's last round: its table now, as before --rounds
                    results.append(combine_rounds(rounds[(speed, budget)]))
                    print(f"## {case_label(results[-1])}\n\n{case_table(results[-1])}\n", flush=True)
    md = (header(args, counter.overhead_ns, renderer) + "\n## Summary\n\n" + summary_table(results) + "\n\n"
          + "\n\n".join(f"## {case_label(r)}\n\n{case_table(r)}" for r in results))
    print("## Summary\n\n" + summary_table(results))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "frame.md").write_text(md + "\n")
    (out / "frame.json").write_text(json.dumps(results, indent=1, default=float) + "\n")
    print(f"\nwrote {out / 'frame.md'} and {out / 'frame.json'}")
    ctx.release()
    return 0


if __name__ == "__main__":
    sys.exit(main())
