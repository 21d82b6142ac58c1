"""Raindrops on the ripple field, stateless (issue 13): a drop's cell, its place in the cell and its diameter are
an integer hash of (its index in the frame, the frame's key), so the GPU makes a frame's drops in the impulse
vertex shader (``shaders/ripples/raindrops.glsl``) from a few uniforms, and this module is its NumPy twin: the
same hash in exact uint32 arithmetic, the positions exact, the diameter and momentum in float64 (the shader's
float32 differs by roundoff). The NumPy backends lay their drops with it; the tests compare the two.

A frame's drops: ``RainBatch(key, count, peak_per_momentum, law)`` — ``count`` candidates spread uniformly over
the interior cells of the window (the fixed edges excluded), each pressing a dent only where its centre's cell
holds water (a drop on the dry road makes no ripple: Poisson thinning, so the drops on water stay a Poisson
count of the water's area). ``law``: the flux-weighted drop-size law of the rain rate (``drop_law``).

NumPy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from rain_core import physics

# Nodes of the flux-weighted drop-size CDF over [D_MIN_MM, D_MAX_MM] (2^k + 1: the shader's search is k halvings).
DROP_CDF_NODES = 513
# Nodes of the drop momentum table over [D_MIN_MM, D_MAX_MM].
DROP_MOMENTUM_NODES = 4097
# Salt of the raindrop stream (the key of a frame is pcg(frame ^ pcg(seed ^ RAIN_SALT))).
RAIN_SALT = 0x52A1D0F5
# Sub-cell offsets are multiples of 2^-12 cells: with a cell index below 4096 the position is exact in float32.
OFFSET_BITS = 12

_M32 = 0xFFFFFFFF


def pcg_int(v: int) -> int:
    """The PCG hash (Jarzynski & Olano 2020) of one uint32, in Python integers (the shaders' ``pcg``)."""
    state = (v * 747796405 + 2891336453) & _M32
    word = (((state >> ((state >> 28) + 4)) ^ state) * 277803737) & _M32
    return (word >> 22) ^ word


def pcg(v: np.ndarray) -> np.ndarray:
    """``pcg_int`` over a uint32 array (NumPy's uint32 arithmetic wraps modulo 2^32, as GLSL's does); a new
    array, computed in place in two temporaries."""
    state = np.multiply(v, np.uint32(747796405), dtype=np.uint32)
    state += np.uint32(2891336453)
    shift = state >> np.uint32(28)
    shift += np.uint32(4)
    np.right_shift(state, shift, out=shift)
    shift ^= state
    shift *= np.uint32(277803737)
    np.right_shift(shift, np.uint32(22), out=state)
    state ^= shift
    return state


def rain_key(seed: int, frame: int) -> int:
    """The key of a frame's raindrops (uint32) for a field's seed and its raining-frame counter."""
    return pcg_int((int(frame) & _M32) ^ pcg_int((int(seed) ^ RAIN_SALT) & _M32))


@lru_cache(maxsize=1)
def momentum_table() -> tuple[np.ndarray, np.ndarray]:
    """Momentum m·v (kg·m/s) of a drop at DROP_MOMENTUM_NODES equal diameter steps, and its steps."""
    d = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, DROP_MOMENTUM_NODES)
    p = physics.RHO_WATER * math.pi / 6.0 * (d * 1e-3) ** 3 * np.asarray(physics.terminal_velocity(d), np.float64)
    return p, np.diff(p)


@dataclass(frozen=True, eq=False)
class DropLaw:
    """The drops arriving on a surface at one rain rate: ``grid`` (DROP_CDF_NODES diameters, mm), ``cdf`` (the
    flux-weighted CDF there: N(D)·v(D), since faster drops of a size class arrive more often), ``flux`` (drops
    per m² per s), ``p_d`` / ``dp_d`` (``momentum_table``)."""

    rate_mm_h: float
    grid: np.ndarray
    cdf: np.ndarray
    flux: float
    p_d: np.ndarray
    dp_d: np.ndarray


def drop_law(rate_mm_h: float) -> DropLaw:
    """The flux-weighted drop-size law of ``rate_mm_h`` (> 0) on DROP_CDF_NODES diameters."""
    rate = float(rate_mm_h)
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, DROP_CDF_NODES)
    mass = np.diff(np.asarray(physics.drop_diameter_cdf(grid, rate), dtype=np.float64))
    mid = 0.5 * (grid[1:] + grid[:-1])
    weights = mass * np.asarray(physics.terminal_velocity(mid), dtype=np.float64)
    cdf = np.concatenate([[0.0], np.cumsum(weights)])
    cdf /= cdf[-1]
    return DropLaw(rate, grid, cdf, float(physics.flux_horizontal_per_m2_s(rate)), *momentum_table())


def drops_at_quantiles(law: DropLaw, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(diameter mm, momentum kg·m/s) of drops at quantiles ``u`` ∈ [0, 1) of ``law``: the inverse of the
    piecewise-linear CDF, then the momentum table (exact at its nodes, linear between: under 1e-3 relative even
    where v ∝ D²). The shader does the same with a binary search over the CDF."""
    diam = np.interp(u, law.cdf, law.grid)
    p_d, dp_d = law.p_d, law.dp_d
    t = (diam - physics.D_MIN_MM) * ((len(p_d) - 1) / (physics.D_MAX_MM - physics.D_MIN_MM))
    i = np.minimum(t.astype(np.intp), len(p_d) - 2)
    t -= i
    return diam, p_d.take(i) + t * dp_d.take(i)


@dataclass(frozen=True, eq=False)
class RainBatch:
    """A frame's raindrops as the GPU gets them: ``count`` candidates of the stream ``key`` over the interior
    cells, each dent ``peak_per_momentum`` (m per kg·m/s, < 0) × its momentum, over a crater of
    ``crater_m_per_mm`` × its diameter (mm), drawn from ``law``."""

    key: int
    count: int
    peak_per_momentum: float
    crater_m_per_mm: float
    law: DropLaw


def _unit(h: np.ndarray) -> np.ndarray:
    """[0, 1) from the top 24 bits of a hash: exact in float32 and float64."""
    return (h >> np.uint32(8)).astype(np.float64) * (1.0 / 16777216.0)


def _interior_cell(h: np.ndarray, n: int) -> np.ndarray:
    """A cell in [1, n − 2] from the top 24 bits k of a hash: 1 + ⌊k·(n − 2) / 2^24⌋, exactly, in 32-bit
    integers as the shader computes it (k split in 12-bit halves so no product overflows)."""
    k = h >> np.uint32(8)
    m = np.uint32(n - 2)
    q = (k >> np.uint32(12)) * m + (((k & np.uint32(0xFFF)) * m) >> np.uint32(12))
    return (q >> np.uint32(12)).astype(np.int64) + 1


def _cells(key: int, count: int, n: int):
    """(h0, h2, ix, iz) of candidates 0 … count − 1: the first hash (the size quantile), the third (the next one
    gives the offsets) and the centres' cells."""
    h0 = pcg(np.arange(count, dtype=np.uint32) ^ np.uint32(key))
    h1 = pcg(h0)
    h2 = pcg(h1)
    return h0, h2, _interior_cell(h1, n), _interior_cell(h2, n)


def _centres(h2: np.ndarray, ix: np.ndarray, iz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The centres in cells: each cell ± ½ by 12-bit offsets from the fourth hash pcg(h2)."""
    h3 = pcg(h2)
    scale = 1.0 / (1 << OFFSET_BITS)
    half = 1 << (OFFSET_BITS - 1)
    ox = ((h3 & np.uint32(0xFFF)).astype(np.int64) - half) * scale
    oz = (((h3 >> np.uint32(OFFSET_BITS)) & np.uint32(0xFFF)).astype(np.int64) - half) * scale
    return ix + ox, iz + oz


def raindrop_sites(key: int, count: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Where the candidates 0 … count − 1 of the stream ``key`` fall on an n-cell window: (ix, iz) their centres'
    cells (each uniform over [1, n − 2]) and (x, z) their centres in cells (cell ± ½, multiples of 2^-12 cells:
    exact in float32 as in the shader)."""
    _, h2, ix, iz = _cells(key, count, n)
    x, z = _centres(h2, ix, iz)
    return ix, iz, x, z


def raindrop_quantiles(key: int, index: np.ndarray) -> np.ndarray:
    """The drop-size quantile u ∈ [0, 1) of candidates ``index`` of the stream ``key``."""
    return _unit(pcg(np.asarray(index, dtype=np.uint32) ^ np.uint32(key)))


def raindrops(batch: RainBatch, n: int, cell_m: float, water: np.ndarray | None = None):
    """The drops of ``batch`` that land on water (``water``: (n, n) > 0.5 where the cell holds water; None: every
    interior cell), as the shader makes them: (index, x m, z m from cell (0, 0), crater radius m, dent m) — the
    dent before the solver widens footprints narrower than MIN_FOOTPRINT_CELLS (volume kept)."""
    h0, h2, ix, iz = _cells(batch.key, batch.count, n)
    if water is None:
        index = np.arange(batch.count)
    else:  # the offsets and sizes of the drops on water only (a few in five: taken by index, not by mask)
        # take(): the same elements as fancy indexing, for less (tens of thousands of candidates a frame).
        index = (np.asarray(water).reshape(-1).take(iz * n + ix) > 0.5).nonzero()[0]
        h0, h2, ix, iz = h0.take(index), h2.take(index), ix.take(index), iz.take(index)
    x, z = _centres(h2, ix, iz)
    diam, momentum = drops_at_quantiles(batch.law, _unit(h0))
    return (index, x * cell_m, z * cell_m, batch.crater_m_per_mm * diam, batch.peak_per_momentum * momentum)
