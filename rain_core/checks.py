"""Argument checks for the public boundary (DESIGN §2): a bad value raises ``ValueError`` naming the field, the
value and the allowed range. Internals may then assume valid values; per-frame loops call none of these.
"""

from __future__ import annotations

import math

import numpy as np

MAX_FRAME_DT_S = 0.25  # s; a longer stall (debugger, window drag) is simulated as this much time
_QUOTE_CHARS = 80  # an error message quotes at most this much of a bad value


def quote(value) -> str:
    """``repr(value)``, cut to a readable length (a 10 MB string must not make a 10 MB message)."""
    text = repr(value) if not isinstance(value, np.ndarray) or value.size <= 8 else f"<array shape {value.shape}>"
    return text if len(text) <= _QUOTE_CHARS else text[:_QUOTE_CHARS - 5] + "…" + text[-4:]


def _bound(x: float) -> str:
    return ("-inf" if x < 0 else "inf") if math.isinf(x) else f"{x:g}"


def _range(lo: float, hi: float, lo_open: bool) -> str:
    return f"{'(' if lo_open or math.isinf(lo) else '['}{_bound(lo)}, {_bound(hi)}{')' if math.isinf(hi) else ']'}"


def _float64(value) -> np.ndarray:
    """``value`` as a float64 array; TypeError for text. NumPy would parse "1" or ["0"] as numbers, but a string
    where a number belongs is a caller's mistake (a TOML value quoted by accident), not a number."""
    if isinstance(value, str | bytes):
        raise TypeError("text")
    raw = np.asarray(value)
    if raw.dtype.kind in "USV" or (raw.dtype.kind == "O" and any(isinstance(v, str | bytes) for v in raw.flat)):
        raise TypeError("text")
    return np.asarray(raw, dtype=np.float64)


def array(name: str, value, lo: float = 0.0, hi: float = math.inf, unit: str = "", lo_open: bool = False):
    """``value`` as a float64 array; ValueError naming ``name`` and the range if any entry is bad (or is text)."""
    try:
        arr = _float64(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number{' in ' + unit if unit else ''}, got {quote(value)}") from None
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(arr) | (arr > hi) | ((arr <= lo) if lo_open else (arr < lo))
    if bad.any():
        first = arr[bad].flat[0] if arr.ndim else float(arr)
        where = f" (at index {tuple(int(i) for i in np.argwhere(bad)[0])})" if arr.ndim else ""
        unit_s = f" {unit}" if unit else ""
        raise ValueError(f"{name} must be finite and in {_range(lo, hi, lo_open)}{unit_s}, got {first!r}{where}")
    return arr


def number(name: str, value, lo: float = -math.inf, hi: float = math.inf, unit: str = "",
           lo_open: bool = False) -> float:
    """A finite scalar in [lo, hi] (or (lo, hi] with ``lo_open``) as a float; booleans and strings are refused."""
    if type(value) in (float, int):  # the common case without NumPy (sub-µs): some callers run per frame
        try:
            x = float(value)
        except OverflowError:
            x = math.nan
        if math.isfinite(x) and (x > lo if lo_open else x >= lo) and x <= hi:
            return x
    if isinstance(value, (bool, str, bytes)) or np.ndim(value) != 0:
        raise ValueError(f"{name} must be a number in {_range(lo, hi, lo_open)}{' ' + unit if unit else ''}, "
                         f"got {quote(value)}")
    return float(array(name, value, lo, hi, unit, lo_open))


def vec3(name: str, value, unit: str = "m/s", max_abs: float = math.inf) -> np.ndarray:
    """A finite (..., 3) float64 array, each component within ±``max_abs``."""
    try:
        arr = _float64(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a 3-vector in {unit}, got {quote(value)}") from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3) ({unit}), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite ({unit}), got {quote(value)}")
    if (np.abs(arr) > max_abs).any():
        raise ValueError(f"{name} must have every component in [-{max_abs:g}, {max_abs:g}] {unit}, "
                         f"got {quote(value)}")
    return arr


def finite_array(name: str, value, shape=None) -> np.ndarray:
    """A float64 array with no NaN or inf (and the given shape, if any); text is refused."""
    try:
        a = _float64(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be an array of numbers, got {quote(value)}") from None
    if shape is not None and a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return a


def clamped(name: str, value, lo: float, hi: float) -> float:
    """A finite control input clamped into [lo, hi] (a pedal pushed past its stop is at its stop)."""
    x = number(name, value)
    return min(max(x, lo), hi)


def time_step(dt_s, cap_s: float = MAX_FRAME_DT_S, name: str = "dt_s") -> float:
    """A finite dt ≥ 0 s, clamped to ``cap_s`` (a stall is simulated as ``cap_s``)."""
    return min(number(name, dt_s, 0.0, unit="s"), cap_s)
