"""Mesa's driver thread: asked for before the first context, the user's choice kept, no notice on stderr, and the
same pixels with it as without it."""

import hashlib
import os
import subprocess
import sys

import pytest

from rain_core.gfx.context import (
    DRIVER_THREAD_OPTION,
    describe_driver,
    driver_thread_requested,
    request_driver_thread,
)


def test_request_sets_the_option_and_silences_mesas_notice():
    env = {}
    assert request_driver_thread(env) is True
    assert env == {DRIVER_THREAD_OPTION: "true", "MESA_DEBUG": "silent"}


@pytest.mark.parametrize("value, on", [("false", False), ("0", False), ("true", True), (" TRUE ", True)])
def test_a_users_choice_is_kept(value, on):
    env = {DRIVER_THREAD_OPTION: value, "MESA_DEBUG": "flush"}
    assert request_driver_thread(env) is on
    assert env == {DRIVER_THREAD_OPTION: value, "MESA_DEBUG": "flush"}  # neither touched
    assert driver_thread_requested(env) is on


def test_a_users_mesa_debug_is_kept():
    env = {"MESA_DEBUG": "incomplete_tex"}
    request_driver_thread(env)
    assert env["MESA_DEBUG"] == "incomplete_tex"


# The frame benchmark's heavy rain (every effect on, the road wet), small, its pixels hashed, in a process of its
# own: Mesa reads the option when the process makes its first context.
_FRAME = """
import hashlib
import os
from rain_core.bench.frame import heavy_rain_settings
from rain_core.gl import create_headless_context
from rain_core.scene import Scene
ctx = create_headless_context()
scene = Scene(ctx, (96, 54), settings=heavy_rain_settings(2000), seed=3, gpu_timing=True)
scene.ego.speed_m_s = scene.autopilot.target_speed_m_s = 20.0
for _ in range(6):
    scene.step(1 / 30)
    scene.render()
print(hashlib.sha256(scene.image().tobytes()).hexdigest())
# Mesa's driver thread is its queue's worker, "gl0" (Linux: the task's name ends with it).
tasks = "/proc/self/task"
workers = [t for t in os.listdir(tasks) if open(f"{tasks}/{t}/comm").read().strip().endswith("gl0")]
print("Mesa" in ctx.info["GL_VERSION"] and os.path.isdir(tasks), len(workers))
"""


def _frame(option: str | None) -> tuple[str, bool, int, str]:
    """(the frame's hash, whether the driver is Mesa on Linux, how many Mesa driver threads ran, stderr)."""
    env = {k: v for k, v in os.environ.items() if k not in (DRIVER_THREAD_OPTION, "MESA_DEBUG")}
    if option is not None:
        env[DRIVER_THREAD_OPTION] = option
    out = subprocess.run([sys.executable, "-c", _FRAME], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    digest, checkable, workers = out.stdout.split()
    return digest, checkable == "True", int(workers), out.stderr


def test_the_driver_thread_draws_the_same_pixels_and_prints_nothing():
    threaded, mesa, workers, err = _frame(None)  # the default: asked for by create_headless_context
    assert err == ""  # no "ATTENTION: default value of option mesa_glthread overridden by environment"
    direct, _, direct_workers, _ = _frame("false")
    if mesa:  # the two runs really differ in the driver thread
        assert (workers, direct_workers) == (1, 0)
    assert len(threaded) == len(hashlib.sha256().hexdigest())
    assert threaded == direct


class _Info:
    def __init__(self, renderer, version):
        self.info = {"GL_RENDERER": renderer, "GL_VERSION": version}


def test_the_driver_in_words(monkeypatch):
    mesa = _Info("llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile) Mesa 22.3.6")
    monkeypatch.setenv(DRIVER_THREAD_OPTION, "true")
    assert describe_driver(mesa) == "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 22.3.6, driver thread on"
    monkeypatch.setenv(DRIVER_THREAD_OPTION, "false")
    assert describe_driver(mesa).endswith("driver thread off")
    # Other drivers ignore Mesa's option: their renderer alone.
    assert describe_driver(_Info("NVIDIA H200/PCIe/SSE2", "4.6.0 NVIDIA 550.54")) == "NVIDIA H200/PCIe/SSE2"
