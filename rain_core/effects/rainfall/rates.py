"""Physics of the visible rain: the share of the particle budget drawn at a rate, the thinning of the instances
(which are drawn, and the real drops each stands for), and the visible splashes (their flux per m² of ground,
their lifetime, and the sizes of the drops that make them)."""

from __future__ import annotations

import math

import numpy as np

from rain_core import physics
from rain_core.effects.rainfall.constants import (
    BUDGET_FULL_AT_MM_H,
    INSTANCE_RATE_MM_H,
    SPLASH_D_MIN_MM,
    SPLASH_LIFE_S,
    TABLE_SIZE,
)
from rain_core.effects.rainfall.drops import instance_quantiles, truncated_exp_quantile


def drawn_share(rate_mm_h: float) -> float:
    """Share of the budget drawn at rate R (mm/h): N(R)/N(BUDGET_FULL_AT_MM_H), at most 1 (0 at R = 0)."""
    if rate_mm_h <= 0:
        return 0.0
    return min(1.0, physics.number_density_per_m3(rate_mm_h) / physics.number_density_per_m3(BUDGET_FULL_AT_MM_H))


_SPLASH_D = np.linspace(SPLASH_D_MIN_MM, physics.D_MAX_MM, 181)
_SPLASH_V = physics.terminal_velocity(_SPLASH_D)


def splash_flux_per_m2_s(rate_mm_h: float) -> float:
    """Visible impacts per m² of ground per s at R (mm/h): ∫ N_eff(D)·v(D) dD over D ≥ SPLASH_D_MIN_MM."""
    if rate_mm_h <= 0:
        return 0.0
    lam = physics.mp_slope_per_mm(rate_mm_h)
    f = physics.effective_n0(rate_mm_h) * np.exp(-lam * _SPLASH_D) * _SPLASH_V
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(_SPLASH_D)))


def splash_life_s(d_mm) -> np.ndarray:
    """Lifetime (s) of the splash of a drop of diameter d_mm (mm): 0.1 s at 1.5 mm … 0.3 s from 4.5 mm."""
    t = np.clip((np.asarray(d_mm, dtype=np.float64) - SPLASH_D_MIN_MM) / 3.0, 0.0, 1.0)
    return SPLASH_LIFE_S[0] + (SPLASH_LIFE_S[1] - SPLASH_LIFE_S[0]) * t


LAM_INSTANCES = float(physics.mp_slope_per_mm(INSTANCE_RATE_MM_H))  # 1/mm, slope of the instance sizes
_Z_INSTANCES = -math.expm1(-LAM_INSTANCES * (physics.D_MAX_MM - physics.D_MIN_MM))
# The instance diameters at the table's bins (every instance has one of these, evenly often); a sub-sample for
# solving the thinning quickly.
TABLE_D_MM = truncated_exp_quantile(instance_quantiles(), LAM_INSTANCES, physics.D_MIN_MM, physics.D_MAX_MM)
_SOLVE_D = TABLE_D_MM[TABLE_SIZE // 512 // 2:: TABLE_SIZE // 512]


def real_per_instance(rate_mm_h: float, density_scale: float = 1.0) -> tuple[float, float]:
    """(A, B) of r(D) = A·e^(−B·D): real drops per m³ per unit of instance probability density at D (mm),
    N_eff(D)·density_scale / q(D), where q is the instances' size density (∝ e^(−LAM_INSTANCES·D) on
    [D_MIN_MM, D_MAX_MM]). 0 at R = 0."""
    if rate_mm_h <= 0 or density_scale <= 0:
        return 0.0, 0.0
    lam = float(physics.mp_slope_per_mm(rate_mm_h))
    n0 = float(physics.effective_n0(rate_mm_h)) * density_scale
    # q(D) = λ_q·e^(−λ_q·(D − D_min)) / Z
    a = n0 * _Z_INSTANCES / LAM_INSTANCES * math.exp(-LAM_INSTANCES * physics.D_MIN_MM)
    return a, lam - LAM_INSTANCES


def drawn_fraction(a: float, b: float, c: float, d_mm=None) -> float:
    """Share of the instances drawn: the mean of min(1, r(D)/c) over the instance sizes (default: a sub-sample
    of the table)."""
    d = _SOLVE_D if d_mm is None else d_mm
    return float(np.mean(np.minimum(1.0, a * np.exp(-b * d) / c)))


def _c_full() -> tuple[float, float]:
    a, b = real_per_instance(BUDGET_FULL_AT_MM_H)
    c = float(np.max(a * np.exp(-b * TABLE_D_MM)))
    return c, drawn_fraction(a, b, c, TABLE_D_MM)


C_FULL, FRACTION_FULL = _c_full()  # at BUDGET_FULL_AT_MM_H: every instance of the smallest size is drawn


def thinning(rate_mm_h: float, density_scale: float, c_min: float) -> tuple[float, float, float]:
    """(A, B, c) of the thinning at R (mm/h): an instance of diameter D is drawn when its cycle's keep hash is
    below min(1, r(D)/c) and then stands for max(r(D), c)/ρ real drops (ρ: the drawn density of instances there),
    so the expected weighted density is Σ q·r = N_eff exactly. c = C_FULL (the drawn share then follows the
    physical count, as ``drawn_share``) until the drawn share reaches the budget's (FRACTION_FULL, heavy rain),
    then larger; never below c_min (weights ≥ 1 where the instances are densest)."""
    a, b = real_per_instance(rate_mm_h, density_scale)
    c = max(C_FULL, c_min)
    if a > 0 and drawn_fraction(a, b, c) > FRACTION_FULL:
        lo, hi = math.log(c), math.log(c) + 1.0
        while drawn_fraction(a, b, math.exp(hi)) > FRACTION_FULL:
            hi += 1.0
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            if drawn_fraction(a, b, math.exp(mid)) > FRACTION_FULL:
                lo = mid
            else:
                hi = mid
        c = math.exp(hi)
    return a, b, c
