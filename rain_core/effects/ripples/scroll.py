"""Scrolling a grid by whole cells (the ripple window follows the car): ``shifted`` makes a moved copy,
``shift_in_place`` moves an array itself and fills the strips that enter. Used by the wave solvers' state and
mask and by the field's bookkeeping of which cells' water depth is known."""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.ripples import kernels

# The dtypes the row-moving kernel is compiled for (the solvers' levels and masks, the field's bookkeeping).
_KERNEL_DTYPES = (np.dtype(np.float32), np.dtype(np.bool_))


def shifted(a: np.ndarray, dx: int, dz: int, fill) -> np.ndarray:
    """out[iz, ix] = a[iz + dz, ix + dx] where that exists, else ``fill``."""
    n_z, n_x = a.shape
    out = np.full_like(a, fill)
    if abs(dx) < n_x and abs(dz) < n_z:
        out[max(0, -dz):n_z - max(0, dz), max(0, -dx):n_x - max(0, dx)] = \
            a[max(0, dz):n_z - max(0, -dz), max(0, dx):n_x - max(0, -dx)]
    return out


def shift_in_place(a: np.ndarray, dx: int, dz: int, fill) -> np.ndarray:
    """``shifted`` into ``a`` itself (returned): the window scrolls every frame at speed, and a fresh n² array
    filled and copied each time costs more than moving the part that stays and filling the strips that enter."""
    n_z, n_x = a.shape
    if abs(dx) >= n_x or abs(dz) >= n_z:
        a[...] = fill
        return a
    # NumPy copies overlapping views as if through a temporary, so the move is exact in either direction.
    if dx == 0 and a.flags.c_contiguous and a.ndim == 2 and a.dtype in _KERNEL_DTYPES and jit.active():
        kernels.shift_rows(a, dz)  # whole rows, in place: no temporary
    elif dx == 0 and a.flags.c_contiguous:  # whole rows: one contiguous move (the car drives along z)
        flat, k = a.reshape(-1), abs(dz) * n_x
        if dz > 0:
            flat[:flat.size - k] = flat[k:]
        elif dz < 0:
            flat[k:] = flat[:flat.size - k]
    else:
        a[max(0, -dz):n_z - max(0, dz), max(0, -dx):n_x - max(0, dx)] = \
            a[max(0, dz):n_z - max(0, -dz), max(0, dx):n_x - max(0, -dx)]
    if dz > 0:
        a[n_z - dz:, :] = fill
    elif dz < 0:
        a[:-dz, :] = fill
    if dx > 0:
        a[:, n_x - dx:] = fill
    elif dx < 0:
        a[:, :-dx] = fill
    return a
