"""Compiled kernels for the per-frame hot loops, where Numba (the ``fast`` extra) is installed.

The simulations that stay on the CPU (windshield drops, spray launches, the ripples' CPU solver) are vectorised
NumPy: each step is hundreds of small array calls, and at a few thousand elements the ~1–2 µs each call costs
in Python and NumPy's dispatch is most of the time. A loop compiled by Numba does the same arithmetic in one
call. Every kernel has a NumPy twin that stays the fallback where Numba is missing and the oracle its tests
compare against; ``active()`` says which one runs.

``RAINROAD_JIT=0`` turns the kernels off for a process (A/B benchmarks, bisecting a difference); ``forced`` does
it for a block (tests). Kernels compile on their first call (about a second each) and are cached on disk beside
their module, so later processes load them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

try:
    import numba
except ImportError:  # the fast extra is optional: every kernel has a NumPy twin
    numba = None

F = TypeVar("F", bound=Callable)

ENV_VAR = "RAINROAD_JIT"
AVAILABLE: bool = numba is not None


def _from_environment() -> bool:
    raw = os.environ.get(ENV_VAR, "1").strip().lower()
    if raw in ("1", "on", "true", "yes", ""):
        return AVAILABLE
    if raw in ("0", "off", "false", "no"):
        return False
    raise ValueError(f"{ENV_VAR}={os.environ[ENV_VAR]!r}: expected 1/on or 0/off")


_active: bool = _from_environment()


def active() -> bool:
    """Whether the compiled kernels run (Numba installed and not turned off); otherwise their NumPy twins."""
    return _active


def set_active(on: bool) -> None:
    """Turn the compiled kernels on or off for this process. Turning them on without Numba is an error."""
    global _active
    if on and not AVAILABLE:
        raise RuntimeError("compiled kernels need Numba: pip install 'rainroad[fast]'")
    _active = bool(on)


@contextmanager
def forced(on: bool) -> Iterator[None]:
    """Run a block with the kernels on or off (tests of a kernel against its NumPy twin)."""
    before = _active
    set_active(on)
    try:
        yield
    finally:
        set_active(before)


def kernel(fn: F) -> F:
    """``fn`` compiled by Numba in nopython mode (no GIL, cached on disk), or ``fn`` itself without Numba.

    Callers run a kernel only while ``active()``; tests may also call the plain function (``fn`` without Numba,
    ``kernel.py_func`` with it) on small inputs, so a kernel's logic is checked even where Numba is missing."""
    if numba is None:
        return fn
    return numba.njit(cache=True, nogil=True)(fn)


def describe() -> str:
    """One line for benchmark headers: which path runs and why."""
    if _active:
        return f"compiled kernels (Numba {numba.__version__})"
    if not AVAILABLE:
        return "NumPy (Numba not installed)"
    return f"NumPy ({ENV_VAR}=0 or turned off)"
