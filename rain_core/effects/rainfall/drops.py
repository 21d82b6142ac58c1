"""Drops without state: the integer hash, the drop table and the closed-form drop position — the float64 NumPy
twin of ``shaders/rainfall/drops.glsl`` (keep the two in step).

Instance i of layer k has, from its index alone, a diameter (the table bin ``(i·φ32) >> (32 − TABLE_BITS)``, a
Weyl sequence, so the instance sizes are an evenly spread sample of the instance distribution) and a phase φ_i.
Its fall speed is quantised so that it passes through its box a whole number m_i of times per TIME_PERIOD_S:
the pass count is then exact from t mod TIME_PERIOD_S (whole seconds and a fraction, sent as two numbers) and
the epoch, in float32 on the GPU, at any t. The c-th pass ("cycle") draws from hash(i, c) the spawn point, the
keep decision (thinning) and the turbulence step; so the pattern never repeats.

Units: m, s, m/s; D in mm."""

from __future__ import annotations

import math

import numpy as np

from rain_core import physics
from rain_core.effects.rainfall.constants import (
    TABLE_BITS,
    TABLE_SIZE,
    TIME_PERIOD_S,
    TURBULENCE,
    TURBULENCE_STEPS,
)

WEYL = np.uint32(2654435769)  # 2^32 / golden ratio
SALT_SEED = np.uint32(0x9E3779B9)
SALT_PHASE = np.uint32(0x68E31DA4)
SALT_X = np.uint32(0xB5297A4D)
SALT_Z = np.uint32(0x1B56C4E9)
SALT_KEEP = np.uint32(0x3C6EF372)
SALT_TURB_X = np.uint32(0xA54FF53A)
SALT_TURB_Z = np.uint32(0x510E527F)
SALT_SPLASH = np.uint32(0x9B05688C)
SALT_D = (np.uint32(0x1F83D9AB), np.uint32(0x5BE0CD19), np.uint32(0xCBBB9D5D), np.uint32(0x629A292A))
SALT_V = (np.uint32(0x9159015A), np.uint32(0x152FECD8), np.uint32(0x67332667), np.uint32(0x8EB44A87))
SALT_KIND = np.uint32(0xDB0C2E0D)
TURB_EPS = TURBULENCE / 2.0  # the wind factor is 1 + j·TURB_EPS, j uniform in [−3, 3] (std 2·TURB_EPS)


def hash32(x) -> np.ndarray:
    """Chris Wellons' lowbias32 integer hash on uint32 arrays (wrapping arithmetic, as GLSL's uint)."""
    x = np.array(x, dtype=np.uint32, ndmin=1)
    x ^= x >> np.uint32(16)
    x *= np.uint32(0x7FEB352D)
    x ^= x >> np.uint32(15)
    x *= np.uint32(0x846CA68B)
    x ^= x >> np.uint32(16)
    return x


def u01(h) -> np.ndarray:
    """A uint32 hash → [0, 1) with 24 bits (exact in float32, as the shader's ``rain_u01``)."""
    return (np.asarray(h, dtype=np.uint32) >> np.uint32(8)).astype(np.float64) * (1.0 / 16777216.0)


def seed_key(seed: int) -> np.uint32:
    """The uint32 every instance key is mixed with (the effect's seed)."""
    return hash32(np.uint32(int(seed) & 0xFFFFFFFF) + SALT_SEED)[0]


def instance_keys(index, key: np.uint32) -> np.ndarray:
    return hash32(np.asarray(index, dtype=np.uint32) ^ key)


def cycle_hash(keys: np.ndarray, cycle: np.ndarray) -> np.ndarray:
    return hash32(keys ^ hash32(cycle))


def table_bin(index) -> np.ndarray:
    """Drop-table bin of instances (a Weyl sequence of the index: evenly spread sizes in every index range)."""
    return ((np.asarray(index, dtype=np.uint32) * WEYL) >> np.uint32(32 - TABLE_BITS)).astype(np.int64)


def instance_quantiles() -> np.ndarray:
    """Quantiles (TABLE_SIZE,) of the instance size distribution at the table's bin centres."""
    return (np.arange(TABLE_SIZE) + 0.5) / TABLE_SIZE


def truncated_exp_quantile(u, lam: float, lo: float, hi: float) -> np.ndarray:
    """Inverse CDF of the exponential density ∝ e^(−λ·D) on [lo, hi] (mm)."""
    return lo - np.log1p(-np.asarray(u) * -np.expm1(-lam * (hi - lo))) / lam


def drop_table(heights_m, lam_instances: float) -> np.ndarray:
    """(L, TABLE_SIZE, 4) float32: per layer and bin (D mm, m passes per TIME_PERIOD_S, quantised fall speed
    m/s, true fall speed m/s). heights_m (L,): the boxes' heights (m), the vertical periods."""
    d = truncated_exp_quantile(instance_quantiles(), lam_instances, physics.D_MIN_MM, physics.D_MAX_MM)
    v = np.asarray(physics.terminal_velocity(d))
    out = np.zeros((len(heights_m), TABLE_SIZE, 4), dtype=np.float32)
    for k, h in enumerate(heights_m):
        m = np.maximum(np.round(v * TIME_PERIOD_S / h), 1.0)
        out[k, :, 0] = d
        out[k, :, 1] = m
        out[k, :, 2] = m * h / TIME_PERIOD_S
        out[k, :, 3] = v
    return out


def time_split(t: float) -> tuple[int, float, int]:
    """t (s, float64) → (whole seconds of t mod TIME_PERIOD_S, the fraction, the epoch mod 2^32): what the GPU
    gets, so that float32 keeps full precision at any t."""
    # In Python floats (twice a frame): np.floor's value is x itself where x is whole (-0.0 kept), else math.floor's;
    # the rest is the same float64 arithmetic (tests/effects/rainfall/test_cpu_paths.py keeps NumPy's as the oracle).
    x = t / TIME_PERIOD_S
    fl = math.floor(x)
    epoch = x if fl == x else float(fl)
    tau = t - epoch * TIME_PERIOD_S
    whole = min(math.floor(tau), TIME_PERIOD_S - 1)
    return whole, tau - whole, int(epoch) & 0xFFFFFFFF


def cycles(m: np.ndarray, phase: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    """(pass count mod 2^32 as uint32, fraction s in [0, 1) of the current pass) at time t (s), float64."""
    whole, frac, epoch = time_split(t)
    m_int = m.astype(np.int64)
    prod = m_int * whole
    part = (prod % TIME_PERIOD_S) / TIME_PERIOD_S + m * frac / TIME_PERIOD_S + phase
    fl = np.floor(part)
    count = (prod // TIME_PERIOD_S + fl.astype(np.int64) + m_int * epoch) & 0xFFFFFFFF
    return count.astype(np.uint32), part - fl


def turbulence_steps(hc: np.ndarray, salt: np.uint32) -> np.ndarray:
    """Integer j in [−TURBULENCE_STEPS, TURBULENCE_STEPS] of a cycle (its wind factor is 1 + j·TURB_EPS)."""
    n = 2 * TURBULENCE_STEPS + 1
    return np.minimum(np.floor(u01(hash32(hc ^ salt)) * n), n - 1) - TURBULENCE_STEPS
