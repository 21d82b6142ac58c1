"""rain_core.jit: the switch between compiled kernels and their NumPy twins."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rain_core import jit


def test_environment_switch(monkeypatch):
    for raw in ("0", "off", "False", " no "):
        monkeypatch.setenv(jit.ENV_VAR, raw)
        assert jit._from_environment() is False
    for raw in ("1", "on", "yes", ""):
        monkeypatch.setenv(jit.ENV_VAR, raw)
        assert jit._from_environment() is jit.AVAILABLE
    monkeypatch.setenv(jit.ENV_VAR, "maybe")
    with pytest.raises(ValueError, match="RAINROAD_JIT='maybe'"):
        jit._from_environment()


def test_forced_restores_the_previous_state():
    before = jit.active()
    with jit.forced(False):
        assert not jit.active()
    assert jit.active() is before


def test_turning_on_without_numba_is_a_clear_error(monkeypatch):
    monkeypatch.setattr(jit, "AVAILABLE", False)
    with pytest.raises(RuntimeError, match=r"rainroad\[fast\]"):
        jit.set_active(True)


@jit.kernel
def _dot(a, b):
    s = 0.0
    for i in range(a.shape[0]):
        s += a[i] * b[i]
    return s


def test_kernel_runs_compiled_or_plain():
    a = np.arange(5.0)
    assert _dot(a, a) == 30.0
    plain = getattr(_dot, "py_func", _dot)
    assert plain(a, a) == 30.0
    assert isinstance(jit.describe(), str)


class _FakeProcess:
    def __init__(self, *args, **kwargs):
        self.args = args
        self.done = False

    def poll(self):
        return 0 if self.done else None


def test_a_cold_start_runs_the_twins_until_the_warm_up_ends(monkeypatch):
    monkeypatch.setattr(jit, "AVAILABLE", True)
    monkeypatch.setattr(jit, "_active", True)
    monkeypatch.setattr(jit, "cold", lambda: True)
    monkeypatch.setattr(jit.subprocess, "Popen", _FakeProcess)
    warm = jit.WarmUp.start()
    try:
        assert warm is not None and warm.process.args[0][1:] == ["-m", "rain_core.warmup"]
        assert not jit.active() and "compile" in jit.describe()
        assert not warm.poll() and not jit.active()
        loads = []
        monkeypatch.setattr(jit, "preload", lambda: loads.append(jit.active()))
        warm.process.done = True
        assert warm.poll() and jit.active()
        assert loads == [True]  # the kernels it compiled are loaded at once, not frame by frame
    finally:
        jit._warming = None


def test_no_warm_up_when_warm_or_off(monkeypatch):
    monkeypatch.setattr(jit.subprocess, "Popen", _FakeProcess)
    monkeypatch.setattr(jit, "cold", lambda: False)
    assert jit.WarmUp.start() is None
    monkeypatch.setattr(jit, "cold", lambda: True)
    with jit.forced(False):
        assert jit.WarmUp.start() is None


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed")
def test_cold_reads_the_disk_cache_and_the_stamp(monkeypatch, tmp_path):
    monkeypatch.setattr(jit, "_KERNELS", [_dot, _dot, _dot])
    _dot(np.ones(2), np.ones(2))  # compiled (or loaded) and saved: current on disk
    monkeypatch.setattr(jit, "_loads_from_disk", lambda d: d is not _dot)
    stamp = tmp_path / "k.warm"
    monkeypatch.setattr(jit, "_stamp_path", lambda: stamp)
    assert jit.cold() and jit.cold_count() == 3
    monkeypatch.setattr(jit, "_KERNELS", [_dot, _dot.py_func])  # one cold, one "on disk"
    assert jit.cold() and jit.cold_count() == 1
    jit.mark_warm()
    assert stamp.exists() and not jit.cold() and jit.cold_count() == 0


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed")
def test_the_stamp_names_the_sources():
    assert jit._KERNELS  # this module's _dot at least
    path = jit._stamp_path()
    assert path is not None and path.name.startswith("rainroad-kernels-") and path.suffix == ".warm"


def test_the_stamp_covers_the_files_kernels_take_code_from(monkeypatch, tmp_path):
    """An edit of only a callee's or a constants file recompiles kernels: the warm-up's stamp must change too, or
    the window would think the kernels warm and compile them on its first frame."""
    if not jit._KERNELS:
        pytest.skip("no compiled kernels")
    stamps = []
    for text in ("C = 1\n", "C = 2\n"):
        dependency = tmp_path / f"consts_{len(stamps)}.py"
        dependency.write_text(text)
        monkeypatch.setattr(jit, "_DEPENDS", {**jit._DEPENDS, "kernel_file": frozenset({str(dependency)})})
        stamps.append(jit._stamp_path())
    assert stamps[0] != stamps[1]


def test_warm_up_scene_runs():
    from rain_core import warmup

    with jit.forced(jit.AVAILABLE):
        if not jit.AVAILABLE:
            pytest.skip("Numba not installed")
        loadable, total = warmup.warm_up(frames_at_speed=3, frames_parked=2)
    assert 0 < total and 0 <= loadable <= total


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba's disk cache")
def test_an_edit_of_a_callee_or_a_constant_alone_recompiles_the_kernel(tmp_path):
    """Numba keys a cached kernel to its own file, but the kernel carries its callees' code and its globals' values.
    An edit of a callee's file alone, or of the module a constant comes from (through a re-export here), must not
    leave the kernel running old code from the disk cache (a git pull)."""
    import subprocess
    import sys

    (tmp_path / "mid.py").write_text("from consts import C  # noqa: F401 - passed on\n")
    (tmp_path / "caller.py").write_text("from rain_core import jit\nfrom callee import g\nfrom mid import C\n\n\n"
                                        "@jit.kernel\ndef f(x):\n    return g(x) * 10 + C\n")

    def run(step: int, constant: int) -> int:
        (tmp_path / "callee.py").write_text(f"from rain_core import jit\n\n\n@jit.kernel\ndef g(x):\n"
                                            f"    return x + {step}\n")
        (tmp_path / "consts.py").write_text(f"C = {constant}\n")
        code = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import caller; print(caller.f(1))"
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
        return int(out.stdout.strip())

    assert run(1, 0) == 20
    assert run(1, 0) == 20  # from the disk cache
    assert run(22, 0) == 230
    assert run(22, 5) == 235


@pytest.mark.skipif(not jit.AVAILABLE, reason="the dispatchers' dependencies")
def test_a_kernel_depends_on_the_files_of_the_kernels_it_calls():
    from rain_core.effects.spray.kernels import spawn_frame
    from rain_core.effects.windshield.kernels import rows

    files = {Path(p).name for p in jit.dependency_files(spawn_frame.launch_to_records.py_func)}
    assert {"records.py", "flight.py", "launches.py", "body_test.py"} <= files
    # and on the modules whose constants it takes (Numba freezes them into the code)
    assert {"common.py", "motion.py", "constants.py", "drop_rows.py"} <= {
        Path(p).name for p in jit.dependency_files(rows.sort_rows.py_func)}
    assert jit.dependency_files(_dot.py_func) == frozenset()  # NumPy's functions are not followed


class _FakeCacheFile:
    def __init__(self, keys):
        self.keys = keys

    def _load_index(self):
        return dict.fromkeys(self.keys, "file.nbc")


class _FakeCache:
    def __init__(self, keys, current):
        self._cache_file = _FakeCacheFile(keys)
        self.current = current

    def _index_key(self, signature, codegen):
        return (signature, codegen, self.current)


class _FakeDispatcher:
    def __init__(self, keys, current="code v2"):
        self._cache = _FakeCache(keys, current)
        self.targetctx = type("Ctx", (), {"codegen": lambda self: "this cpu"})()
        self.overloads = {}
        self.compiled = []

    def compile(self, signature):
        self.compiled.append(signature)
        self.overloads[signature] = object()


def test_preload_loads_only_entries_for_this_machine_and_source(monkeypatch):
    """An index entry made on another CPU or for an older bytecode would compile (seconds) instead of load."""
    mine = (("float64",), "this cpu", "code v2")
    other_cpu = (("int64",), "another cpu", "code v2")
    old_code = (("float32",), "this cpu", "code v1")
    kernel = _FakeDispatcher([mine, other_cpu, old_code])
    monkeypatch.setattr(jit, "_KERNELS", [kernel])
    monkeypatch.setattr(jit, "_active", True)
    assert jit.preload() == 1 and kernel.compiled == [("float64",)]
    assert jit.preload() == 0  # loaded already
    monkeypatch.setattr(jit, "_active", False)
    kernel.overloads.clear()
    assert jit.preload() == 0  # the kernels are off: nothing to load


def test_preload_survives_a_cache_it_cannot_read_or_load(monkeypatch):
    broken = _FakeDispatcher([])
    broken._cache = None  # e.g. a Numba whose cache internals differ
    failing = _FakeDispatcher([(("float64",), "this cpu", "code v2")])
    failing.compile = lambda signature: 1 / 0  # e.g. a cache file that cannot be read any more
    fine = _FakeDispatcher([(("int64",), "this cpu", "code v2")])
    monkeypatch.setattr(jit, "_KERNELS", [broken, failing, fine])
    monkeypatch.setattr(jit, "_active", True)
    assert jit.preload() == 1 and fine.compiled == [("int64",)]  # the others load on their first calls


_COUNT_LOADS = """
import sys
from numba.core import dispatcher
loads = []
original = dispatcher.Dispatcher._compile_for_args
def counted(self, *args, **kwargs):
    loads.append(self.py_func.__qualname__)
    return original(self, *args, **kwargs)
dispatcher.Dispatcher._compile_for_args = counted
"""


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba's disk cache")
def test_a_preloaded_kernel_loads_nothing_on_its_first_calls(tmp_path):
    """After ``preload`` a kernel's first calls with the argument types cached earlier go straight to the code."""
    import subprocess
    import sys

    (tmp_path / "k.py").write_text("from rain_core import jit\n\n\n@jit.kernel\ndef f(x):\n    return x * 2\n")
    code = (f"import sys; sys.path.insert(0, {str(tmp_path)!r})\n" + _COUNT_LOADS
            + "import k\nfrom rain_core import jit\nn = jit.preload() if sys.argv[1] == 'preload' else 0\n"
              "k.f(1); k.f(1.5)\nprint(n, len(loads))\n")

    def run(mode: str) -> tuple[int, int]:
        out = subprocess.run([sys.executable, "-c", code, mode], capture_output=True, text=True, check=True)
        return tuple(int(v) for v in out.stdout.split())

    assert run("lazy") == (0, 2)  # compiled and cached: one load (here a compile) per argument type
    assert run("lazy") == (0, 2)  # loaded from the disk cache on each first call
    assert run("preload") == (2, 0)


@pytest.mark.skipif(not jit.AVAILABLE, reason="Numba's disk cache")
def test_after_the_warm_up_a_preloaded_drive_loads_no_kernel_mid_frame():
    """The window preloads the kernels; then no frame of a heavy-rain drive (at speed with traffic, the glass
    filling, then parked) stops to load or compile one: the warm-up scene takes every path the frames take."""
    import subprocess
    import sys

    code = _COUNT_LOADS + """
from rain_core import jit
from rain_core.bench.frame import _Brake, heavy_rain_settings
from rain_core.gl import create_headless_context
from rain_core.scene import Scene
ctx = create_headless_context()
scene = Scene(ctx, (96, 54), settings=heavy_rain_settings(10_000), seed=3, gpu_timing=False)
for effect in scene.effects:
    if effect.name == "ripples":
        effect.backend = "numpy32"
if jit.cold():  # the window would start the warm-up (its kernels are defined now): the caller runs it first
    print("cold")
    sys.exit()
before = len(loads)
preloaded = jit.preload()
assert len(loads) == before, "preload must load, not dispatch"
scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 100.0 / 3.6
for _ in range(30):
    scene.step(1.0 / 30.0, None); scene.render()
for _ in range(8):
    scene.step(1.0 / 30.0, _Brake()); scene.render()
print(preloaded, len(loads), sorted(set(loads)))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    if out.stdout.strip() == "cold":
        subprocess.run([sys.executable, "-m", "rain_core.warmup"], capture_output=True, check=True)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    preloaded, loads, names = out.stdout.split(maxsplit=2)
    assert int(preloaded) > 20 and int(loads) == 0, names
