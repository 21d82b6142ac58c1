"""rain_core.jit: the switch between compiled kernels and their NumPy twins."""

from __future__ import annotations

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
