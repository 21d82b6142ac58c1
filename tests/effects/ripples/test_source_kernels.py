"""The compiled kernels of the frame's sources against their NumPy twins, bit for bit: the GPU solver's instance
rows (``kernels.gpu_bump_rows`` vs ``WaveSolver._bumps`` + the float32 packing) and the spray droplets' dents
(``kernels.droplet_dents`` vs ``RippleField.add_droplet_impacts``'s NumPy arithmetic). No GL needed."""

from __future__ import annotations

import numpy as np
import pytest

from rain_core import jit
from rain_core.effects.ripples.field import RippleField
from rain_core.effects.ripples.gpu import WaveSolverGPU
from rain_core.effects.ripples.solver import WaveSolver

needs_numba = pytest.mark.skipif(not jit.AVAILABLE, reason="Numba not installed (pip install 'rainroad[fast]')")


class _Grid:
    """What ``WaveSolverGPU._bump_rows`` reads of its solver (no GL context)."""

    cell_m = 4.75 / 95
    length_m = 4.75
    _bumps = WaveSolver._bumps
    _bump_rows = WaveSolverGPU._bump_rows


@needs_numba
def test_gpu_bump_rows_kernel_gives_the_twins_rows():
    """Bumps inside, across the edges and beyond the grid, narrower than the smallest footprint, with zero
    peaks: the twin's kept rows in its order, the same float32 bits."""
    rng = np.random.default_rng(3)
    k = 500
    xs, zs = rng.uniform(-0.5, 5.3, k), rng.uniform(-0.5, 5.3, k)
    radii = rng.uniform(0.0, 0.3, k)
    radii[::5] = 0.01  # widened to the smallest footprint, volume kept
    amounts = rng.uniform(-1e-3, 1e-3, k)
    amounts[::11] = 0.0  # dropped
    grid = _Grid()
    twin, kernel = jit.twin_and_kernel(lambda: grid._bump_rows(xs, zs, radii, amounts))
    assert kernel.dtype == np.float32 and 0 < len(twin) < k  # some kept, some dropped: a real test
    np.testing.assert_array_equal(kernel, twin)


@needs_numba
def test_droplet_dents_kernel_gives_the_twins_dents():
    """Droplets with NaN and inf rows, zero and huge momenta (clamped): the twin's dents, in its order."""
    rng = np.random.default_rng(4)
    impacts = np.column_stack([rng.uniform(-2.0, 8.0, 300), rng.uniform(-2.0, 8.0, 300),
                               rng.uniform(-1e-4, 1e-4, 300)])
    impacts[::17, 0] = np.nan
    impacts[::23, 2] = np.inf
    impacts[::13, 2] = 0.0
    impacts[5, 2] = 1e15  # beyond MAX_IMPULSE_M once scaled

    def run():
        field = RippleField(n=96, extent_m=4.75, seed=1, wake_gain=1.7)
        field.recenter(3.0, 2.0)
        field._batch = []
        laid = field.add_droplet_impacts(impacts, radius_m=0.03)
        return laid, [np.concatenate(parts) for parts in zip(*field._batch, strict=True)]

    (n0, b0), (n1, b1) = jit.twin_and_kernel(run)
    assert n1 == n0 == len(b0[0]) and 0 < n0 < len(impacts)
    for got, want in zip(b1, b0, strict=True):
        np.testing.assert_array_equal(got, want)
