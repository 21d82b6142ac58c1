"""Small matrix helpers for the per-frame path."""

from __future__ import annotations

import numpy as np

try:  # the gufunc np.linalg.inv calls: the same LAPACK routine, so the same bits
    from numpy.linalg import _umath_linalg as _gufuncs
except ImportError:  # pragma: no cover - a NumPy without it takes the public path
    _gufuncs = None


def inverse(a: np.ndarray) -> np.ndarray:
    """``np.linalg.inv(a)`` of a float64 matrix, bit for bit, without its argument checks and its ``errstate``
    context (half of its ~20 µs for a 4×4; the renderer inverts a few matrices every frame). A singular or
    non-finite input (NumPy then warns of an invalid value) goes through ``np.linalg.inv``, which raises."""
    if _gufuncs is None or type(a) is not np.ndarray or a.dtype != np.float64 or a.ndim != 2:
        return np.linalg.inv(a)
    out = _gufuncs.inv(a, signature="d->d")
    if not np.isfinite(out).all():
        return np.linalg.inv(a)
    return out
