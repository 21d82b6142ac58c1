"""Physics of the visible rain: the share of the particle budget drawn at a rate, and the visible splashes (their
flux per m² of ground, their lifetime, and the sizes of the drops that make them)."""

from __future__ import annotations

import numpy as np

from rain_core import physics
from rain_core.effects.rainfall.constants import BUDGET_FULL_AT_MM_H, SPLASH_D_MIN_MM, SPLASH_LIFE_S


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


def sample_truncated_exp(rng: np.random.Generator, lam: float, lo: float, hi: float, n: int) -> np.ndarray:
    u = rng.random(n)
    return lo - np.log1p(u * np.expm1(-lam * (hi - lo))) / lam
