"""Scrolling a grid by whole cells (the ripple window follows the car): ``shifted`` makes a moved copy,
``shift_in_place`` moves an array itself and fills the strips that enter (``shift_line`` a 1-D one). Used by the
wave solvers' state and mask and by the field's bookkeeping of which cells' water depth is known."""

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


def shift_line(a: np.ndarray, d: int, fill) -> np.ndarray:
    """``shift_in_place`` of a 1-D array (returned): a[i] = a[i + d] where that exists, else ``fill``. Two slice
    assignments, no kernel call: the field's flags of unknown rows and columns and its rows' water counts
    scroll with every scroll."""
    n = a.shape[0]
    if abs(d) >= n:
        a[...] = fill
    elif d > 0:  # overlapping views copy as if through a temporary: exact in either direction
        a[:n - d] = a[d:]
        a[n - d:] = fill
    elif d < 0:
        a[-d:] = a[:n + d]
        a[:-d] = fill
    return a


class RowWindow:
    """An (n, m) C-contiguous window onto a buffer with ``spare`` extra rows above and below it, for an array that
    scrolls by whole rows every frame (the ripple window at speed: ~20 rows a frame at 100 km/h). A scroll moves
    the window's offset and fills only the rows that enter, instead of moving the n − |dz| rows that stay (an n²
    pass over memory the frame has evicted, per array); the rows are moved back to the middle only when the
    offset runs out of spare rows (every ~spare/|dz| scrolls). ``view`` is the current window: the same values as
    ``shift_in_place`` would leave, in another array object after each scroll."""

    def __init__(self, a: np.ndarray, spare: int):
        n_z, n_x = a.shape
        self.spare = max(1, int(spare))
        self._buffer = np.zeros((n_z + 2 * self.spare, n_x), a.dtype)
        self.adopt(a)

    def fits(self, a: np.ndarray) -> bool:
        """Whether ``a`` can be adopted (same shape and dtype as the window)."""
        return a.shape == self.view.shape and a.dtype == self.view.dtype

    def adopt(self, a: np.ndarray) -> np.ndarray:
        """Copy ``a`` into the middle of the buffer and make it the window (returned)."""
        n_z = a.shape[0]
        self._offset = self.spare
        self.view = self._buffer[self.spare:self.spare + n_z]
        np.copyto(self.view, a)
        return self.view

    def scrolled(self, a: np.ndarray, dz: int, fill) -> np.ndarray:
        """``a`` scrolled by ``dz`` rows (``shift``): ``a`` is adopted first unless it is the window itself (an
        array replaced since, e.g. a new mask, is copied in; the previous view is then no longer valid)."""
        if a is not self.view:
            self.adopt(a)
        return self.shift(dz, fill)

    def shift(self, dz: int, fill) -> np.ndarray:
        """The window scrolled by ``dz`` rows: new[iz] = old[iz + dz] where that exists, else ``fill`` (returned,
        also as ``view``)."""
        buffer, n_z, spare = self._buffer, self.view.shape[0], self.spare
        old = self._offset
        new = old + dz
        if not 0 <= new <= 2 * spare:  # out of spare rows: the rows that stay go back to the middle
            new = spare
            kept = n_z - abs(dz)
            if kept > 0:
                src, dst = old + max(dz, 0), new + max(-dz, 0)
                if src != dst:
                    lo = min(src, dst)
                    shift_in_place(buffer[lo:max(src, dst) + kept], 0, src - dst, fill)
        self._offset = new
        self.view = view = buffer[new:new + n_z]
        if abs(dz) >= n_z:
            view[...] = fill
        elif dz > 0:
            view[n_z - dz:] = fill
        elif dz < 0:
            view[:-dz] = fill
        return view

