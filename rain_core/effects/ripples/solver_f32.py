"""The float32 NumPy fast path of the wave solver: the same scheme as ``WaveSolver``, stepped in place."""

from __future__ import annotations

import numpy as np

from rain_core.effects.ripples.solver import WaveSolver


class WaveSolverF32(WaveSolver):
    """The same solver on float32 arrays with in-place, allocation-free vectorised steps (the CPU fast path).

    Same interface as ``WaveSolver``; ``height`` is float32. Energy and the retime guard accumulate their sums
    in float64."""

    dtype = np.float32

    def _alloc(self):
        super()._alloc()
        self._scratch = np.zeros((self.n - 2, self.n - 2), np.float32)
        self._scratch4 = np.zeros((self.n - 2, self.n - 2), np.float32)

    def _advance(self, k: int, alpha: float, kc2: float):
        z, zp, s, t = self._z, self._zp, self._scratch, self._scratch4
        a, kk = np.float32(alpha), np.float32(kc2)
        mask = None if self._mask is None else self._mask[1:-1, 1:-1]
        for _ in range(k):
            zi, pi = z[1:-1, 1:-1], zp[1:-1, 1:-1]
            # The previous level becomes the new one, z + α(z − z⁻) + k(Σ − 4z), in the shader's order: Σ − 4z
            # is exactly 0 for a flat patch, so smooth (slow) modes keep their frequency in float32; folding
            # it into (1 − 4k)z + kΣ would detune them by the rounding of the coefficients.
            np.subtract(zi, pi, out=pi)
            pi *= a
            pi += zi
            np.add(z[:-2, 1:-1], z[2:, 1:-1], out=s)
            s += z[1:-1, :-2]
            s += z[1:-1, 2:]
            np.multiply(zi, np.float32(4.0), out=t)
            s -= t
            s *= kk
            pi += s
            if mask is not None:
                pi *= mask
            z, zp = zp, z
        self._z, self._zp = z, zp

