"""Mesa's driver thread: asked for before the first context, the user's choice kept, the option read as Mesa reads
it, no notice on stderr, the same pixels with the thread as without it, and the driver in words."""

import hashlib
import os
import subprocess
import sys

import pytest

from rain_core.gfx import driver
from rain_core.gfx.driver import (
    DRIVER_THREAD_OPTION,
    describe_driver,
    driver_thread_requested,
    request_driver_thread,
)


def test_request_sets_the_option_and_silences_mesas_notice():
    env = {}
    assert request_driver_thread(env) is True
    assert env == {DRIVER_THREAD_OPTION: "true", "MESA_DEBUG": "silent"}


# Mesa takes a boolean option as exactly "true" or "false" after leading white space (anything else: ignored).
@pytest.mark.parametrize("value, on", [("false", False), ("true", True), (" \ttrue", True), ("1", False),
                                       ("TRUE", False), ("true ", False), ("", False)])
def test_a_users_choice_is_kept_and_read_as_mesa_reads_it(value, on):
    env = {DRIVER_THREAD_OPTION: value, "MESA_DEBUG": "flush"}
    assert request_driver_thread(env) is on
    assert env == {DRIVER_THREAD_OPTION: value, "MESA_DEBUG": "flush"}  # neither touched
    assert driver_thread_requested(env) is on


def test_mesas_notice_is_silenced_for_a_users_choice_too():
    env = {DRIVER_THREAD_OPTION: "false"}
    assert request_driver_thread(env) is False
    assert env["MESA_DEBUG"] == "silent"


# The frame benchmark's heavy rain (every effect on, the road wet), small, its pixels hashed, in a process of its
# own: Mesa reads the option when the process makes its first context. The ripples' solver is fixed ("auto" times
# both per process) and the CPU simulations run as NumPy (no kernel compiles in the children).
_FRAME = """
import hashlib
from rain_core.bench.frame import heavy_rain_settings
from rain_core.gfx.driver import driver_threads
from rain_core.gl import create_headless_context
from rain_core.scene import Scene
ctx = create_headless_context()
scene = Scene(ctx, (96, 54), settings=heavy_rain_settings(2000), seed=3, gpu_timing=True)
for effect in scene.effects:
    if effect.name == "ripples":
        effect.backend = "numpy32"
scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 20.0
for _ in range(6):
    scene.step(1 / 30)
    scene.render()
print(hashlib.sha256(scene.image().tobytes()).hexdigest())
print("Mesa" in ctx.info["GL_VERSION"], driver_threads())
"""


def _frame(option: str | None) -> tuple[str, bool, str, str]:
    """(the frame's hash, whether the driver is Mesa, how many Mesa driver threads ran or "None", stderr)."""
    env = {k: v for k, v in os.environ.items() if k not in (DRIVER_THREAD_OPTION, "MESA_DEBUG")}
    env["RAINROAD_JIT"] = "0"
    if option is not None:
        env[DRIVER_THREAD_OPTION] = option
    out = subprocess.run([sys.executable, "-c", _FRAME], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    digest, mesa, workers = out.stdout.split()
    return digest, mesa == "True", workers, out.stderr


def test_the_driver_thread_draws_the_same_pixels_and_prints_nothing():
    threaded, mesa, workers, err = _frame(None)  # the default: asked for by create_headless_context
    direct, _, direct_workers, direct_err = _frame("false")
    assert err == "" and direct_err == ""  # no "ATTENTION: … mesa_glthread overridden by environment"
    assert len(threaded) == len(hashlib.sha256().hexdigest())
    assert threaded == direct
    if not mesa or workers == "None":
        pytest.skip("the pixels agree; whether the thread ran needs Mesa and Linux's thread names")
    assert (workers, direct_workers) == ("1", "0")  # the two runs really differed in the driver thread


class _Info:
    def __init__(self, renderer, version):
        self.info = {"GL_RENDERER": renderer, "GL_VERSION": version}


def test_the_driver_in_words(monkeypatch):
    mesa = _Info("llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile) Mesa 22.3.6")
    monkeypatch.setattr(driver, "driver_threads", lambda: 1)
    assert describe_driver(mesa) == "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 22.3.6, driver thread on"
    monkeypatch.setattr(driver, "driver_threads", lambda: 0)
    assert describe_driver(mesa).endswith("driver thread off")
    # Where the threads cannot be listed: what the environment asks for.
    monkeypatch.setattr(driver, "driver_threads", lambda: None)
    monkeypatch.setenv(DRIVER_THREAD_OPTION, "true")
    assert describe_driver(mesa).endswith("driver thread asked for")
    monkeypatch.setenv(DRIVER_THREAD_OPTION, "false")
    assert describe_driver(mesa).endswith("driver thread not asked for")
    # Other drivers ignore Mesa's option: their renderer alone.
    assert describe_driver(_Info("NVIDIA H200/PCIe/SSE2", "4.6.0 NVIDIA 550.54")) == "NVIDIA H200/PCIe/SSE2"


def test_this_process_lists_mesas_driver_thread(gl_ctx):
    """The test session's context was made by create_headless_context: on Mesa and Linux its thread runs."""
    threads = driver.driver_threads()
    if "Mesa" not in gl_ctx.info["GL_VERSION"] or threads is None or not driver_thread_requested():
        pytest.skip("needs Mesa, Linux's thread names and the thread asked for (mesa_glthread=true)")
    assert threads >= 1
    assert describe_driver(gl_ctx).endswith("driver thread on")


@pytest.mark.parametrize("size, offset", [(0, 0), (5, 0), (driver.QUEUED_WRITE_BYTES, 8),
                                          (3 * driver.QUEUED_WRITE_BYTES + 7, 4)])
def test_queued_writes_come_in_pieces_mesas_thread_queues(gl_ctx, monkeypatch, size, offset):
    import numpy as np

    data = np.random.default_rng(size).integers(0, 256, size, dtype=np.uint8)
    buffer = gl_ctx.buffer(reserve=offset + size + 16)
    buffer.write(b"\xab" * (offset + size + 16))
    pieces = []
    write = type(buffer).write

    def spy(self, piece, offset=0):
        pieces.append((len(piece), offset))
        return write(self, piece, offset=offset)

    monkeypatch.setattr(type(buffer), "write", spy)
    driver.write_queued(buffer, data, offset=offset)
    monkeypatch.undo()
    assert all(n <= driver.QUEUED_WRITE_BYTES for n, _ in pieces)
    assert sum(n for n, _ in pieces) == size
    assert [o for _, o in pieces] == [offset + k * driver.QUEUED_WRITE_BYTES for k in range(len(pieces))]
    back = np.frombuffer(buffer.read(), np.uint8)
    assert np.array_equal(back[offset:offset + size], data)
    assert (back[:offset] == 0xAB).all() and (back[offset + size:] == 0xAB).all()  # nothing else written
    buffer.release()
