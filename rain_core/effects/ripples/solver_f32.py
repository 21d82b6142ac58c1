"""The float32 NumPy fast path of the wave solver: the same scheme as ``WaveSolver``, stepped in place."""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.ripples import kernels
from rain_core.effects.ripples.constants import FOOTPRINT_BATCH_CELLS, MIN_FOOTPRINT_CELLS
from rain_core.effects.ripples.scroll import RowWindow
from rain_core.effects.ripples.solver import WaveSolver

# The kernels' stand-in for "no mask" (a fixed (1, 1) bool array: one compiled signature).
_NO_MASK = np.ones((1, 1), np.bool_)


class WaveSolverF32(WaveSolver):
    """The same solver on float32 arrays with in-place, allocation-free vectorised steps (the CPU fast path).

    Same interface as ``WaveSolver``; ``height`` is float32. Energy and the retime guard accumulate their sums
    in float64."""

    dtype = np.float32
    # The mask as bytes, not float32: the steps multiply by it as 0.0 / 1.0 all the same (the same bits), and at
    # 512² it is 256 KB instead of 1 MB: a quarter of the stencil's reads and of the scroll's moves, and the
    # raindrops' and bumps' scattered reads of it stay in L2.
    mask_dtype = np.bool_

    def _alloc(self):
        super()._alloc()
        # One scratch row block for the stencil, flat: rows 1 … n − 2 whole (see _advance).
        self._scratch = np.zeros(self.n * (self.n - 2), np.float32)
        self._scratch4 = np.zeros(self.n * (self.n - 2), np.float32)
        # The deposit kernel's per-bump scratch (grown as batches grow) and its reach histogram (reach ≤ n + 1).
        self._bump_scratch = np.zeros((2, 1024))
        self._bump_order = np.empty((2, 1024), np.int64)
        self._reach_starts = np.empty(self.n + 3, np.int64)
        self._row_windows: list[RowWindow | None] = [None, None, None]  # where the mask and the levels scroll

    def shift(self, dx_cells: int, dz_cells: int):
        """``WaveSolver.shift``; along z (the car drives along the road: ~20 rows a frame at 100 km/h) the mask
        and both levels scroll as row windows (``scroll.RowWindow``: the same values, but only the rows that
        enter are written, instead of three n² moves a frame)."""
        dx, dz = int(dx_cells), int(dz_cells)
        if dx != 0 or dz == 0:
            super().shift(dx, dz)
            return
        if self._mask is not None:
            self._mask = self._row_window(0, self._mask).scrolled(self._mask, dz, True)
        if self._asleep:
            return
        # The steps swap the levels: each scrolls in the window whose view it is (one replaced since, e.g. by a
        # reset, is copied into a window the other does not use).
        z, zp = self._z, self._zp
        first = self._row_window(1, z)
        second = self._row_window(2, zp)
        if first.view is zp or second.view is z:
            first, second = second, first
        self._z, self._zp = first.scrolled(z, dz, 0.0), second.scrolled(zp, dz, 0.0)
        for a in (self._z, self._zp):
            a[0, :] = a[-1, :] = a[:, 0] = a[:, -1] = 0.0

    def _row_window(self, slot: int, a: np.ndarray) -> RowWindow:
        """The row window in ``slot`` (0 the mask, 1 and 2 the levels), made for ``a``'s shape and dtype."""
        windows = self._row_windows
        window = windows[slot]
        if window is None or not window.fits(a):
            window = windows[slot] = RowWindow(a, self.n // 2)
        return window

    def _kernel_mask(self) -> tuple[np.ndarray, bool]:
        return (_NO_MASK, False) if self._mask is None else (self._mask, True)

    def _advance(self, k: int, alpha: float, kc2: float):
        if jit.active():  # all k sub-steps in one fused loop (the twin below makes ~12 passes over n² a step)
            mask, use_mask = self._kernel_mask()
            if kernels.leapfrog(self._z, self._zp, mask, use_mask, k, alpha, kc2):
                self._z, self._zp = self._zp, self._z
            return
        # The stencil runs over rows 1 … n − 2 as one flat, contiguous range (edge columns included): NumPy
        # walks a 2-D interior view row by row, and that per-row overhead cost several times the arithmetic.
        # A neighbour one cell left or right in the flat range is the cell beside it, except at the edge
        # columns, whose results (from the row's other end) are thrown away: set back to 0 after each step.
        # The levels are C-contiguous (made by np.zeros / _set_state), so reshape(-1) views them.
        n = self.n
        lo, hi = n, n * (n - 1)
        z, zp, s, t = self._z, self._zp, self._scratch, self._scratch4
        a, kk = np.float32(alpha), np.float32(kc2)
        mask = None if self._mask is None else self._mask.reshape(-1)[lo:hi]
        for _ in range(k):
            zf, pf = z.reshape(-1), zp.reshape(-1)
            zi, pi = zf[lo:hi], pf[lo:hi]
            # The previous level becomes the new one, z + α(z − z⁻) + k(Σ − 4z), in the shader's order: Σ − 4z
            # is exactly 0 for a flat patch, so smooth (slow) modes keep their frequency in float32; folding
            # it into (1 − 4k)z + kΣ would detune them by the rounding of the coefficients.
            np.subtract(zi, pi, out=pi)
            pi *= a
            pi += zi
            np.add(zf[lo - n:hi - n], zf[lo + n:hi + n], out=s)
            s += zf[lo - 1:hi - 1]
            s += zf[lo + 1:hi + 1]
            np.multiply(zi, np.float32(4.0), out=t)
            s -= t
            s *= kk
            pi += s
            if mask is not None:
                pi *= mask
            zp[1:-1, 0] = 0.0
            zp[1:-1, -1] = 0.0
            z, zp = zp, z
        self._z, self._zp = z, zp

    def add_impulses_unchecked(self, xs: np.ndarray, zs: np.ndarray, radii: np.ndarray, amounts: np.ndarray):
        if not jit.active():
            super().add_impulses_unchecked(xs, zs, radii, amounts)
            return
        if xs.size == 0:
            return
        # _bumps, _footprint and _deposit in one loop: the same values added in the same order.
        f64 = np.float64
        mask, use_mask = self._kernel_mask()
        if self._bump_scratch.shape[1] < xs.size:  # grown by doubling: a frame's batch reallocates rarely
            size = max(xs.size, 2 * self._bump_scratch.shape[1])
            self._bump_scratch, self._bump_order = np.zeros((2, size)), np.empty((2, size), np.int64)
        cells = kernels.deposit_bumps(self._z, self._zp, mask, use_mask, np.ascontiguousarray(xs, f64),
                                      np.ascontiguousarray(zs, f64), np.ascontiguousarray(radii, f64),
                                      np.ascontiguousarray(amounts, f64), self.cell_m,
                                      MIN_FOOTPRINT_CELLS * self.cell_m, self.length_m, FOOTPRINT_BATCH_CELLS,
                                      self._bump_scratch, self._bump_order, self._reach_starts)
        if cells < 0:  # bumps wider than the span: outside the kernel's contract, the twin copes
            with jit.forced(False):
                super().add_impulses_unchecked(xs, zs, radii, amounts)
        elif cells:
            self._sourced = True
            self._asleep = False

    def _footprint_group(self, xs, zs, r_eff, amounts, reach: int, flats: list, values: list) -> None:
        """The reference's footprint of bumps of one reach: the same values in the same order (so the same
        float32 sums), in fewer and cheaper passes. A cell at offset o from the centre's cell lies |o − f| cells
        off (f ∈ [0, 1) the centre's fraction), so o = −reach is never inside a rim of at most reach cells: the
        window is 2·reach per side (16 cells for a raindrop instead of 25). The rim test runs on the dense
        block laid out offset-major (every pass runs along the K bumps, not along a row of 4); the kept cells
        are found by one flatnonzero in the reference's bump-major order, and only the bumps near the fixed
        edges are clipped to the interior."""
        h, n = self.cell_m, self.n
        if r_eff.max() > (reach - 1e-6) * h:  # a rim within rounding of reach cells: the reference's window
            super()._footprint_group(xs, zs, r_eff, amounts, reach, flats, values)
            return
        w, count = 2 * reach, len(xs)
        offsets = np.arange(1 - reach, reach + 1)[:, None]
        c0 = np.floor(xs / h).astype(np.int64)
        r0 = np.floor(zs / h).astype(np.int64)
        dx2 = ((offsets + c0) * h - xs) ** 2  # (w, K), as the reference's cols·h − x
        dz2 = ((offsets + r0) * h - zs) ** 2
        rel = dz2[:, None, :] + dx2[None, :, :]  # d² (w rows, w cols, K), then d / r in place
        np.sqrt(rel, out=rel)
        rel /= r_eff[0] if r_eff[0] == r_eff[-1] and (r_eff == r_eff[0]).all() else r_eff
        inside = rel < 1.0  # the reference's rim test (its squared-distance pre-test only saves work there)
        edge = (c0 < reach) | (c0 > n - 2 - reach) | (r0 < reach) | (r0 > n - 2 - reach)
        if edge.any():  # windows that reach the fixed edges: only their interior cells
            e = edge.nonzero()[0]
            rows, cols = offsets + r0[e], offsets + c0[e]
            inside[:, :, e] &= ((rows >= 1) & (rows <= n - 2))[:, None, :] & ((cols >= 1) & (cols <= n - 2))[None]
        idx = inside.transpose(2, 0, 1).ravel().nonzero()[0]  # bump-major, as the reference lists them
        if w & (w - 1) == 0:  # w² a power of two: shifts and masks instead of a division
            k, m = idx >> ((w * w).bit_length() - 1), idx & (w * w - 1)
        else:
            k, m = np.divmod(idx, w * w)
        vals = 0.5 * (1.0 + np.cos(np.pi * rel.reshape(-1)[m * count + k])) * amounts[k]
        i, j = np.divmod(np.arange(w * w), w)
        flat = ((r0 + (1 - reach)) * n + (c0 + (1 - reach)))[k] + (i * n + j)[m]
        if not vals.all():
            nonzero = vals != 0.0
            flat, vals = flat[nonzero], vals[nonzero]
        flats.append(flat)
        values.append(vals)
