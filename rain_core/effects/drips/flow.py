"""How much water drips, when each drop lets go, how it falls and where it lands (NumPy, no GL; float64 twin of
shaders/drips/drip.vert).

- Each roof is a linear reservoir (the standard lumped model of surface runoff, e.g. Nash 1957): it holds S (m³),
  gains the rain it catches, R·A, and drains over its edges at S/τ, τ its drainage time constant
  (edges.DripSites.drain_s). dS/dt = R·A − S/τ is integrated exactly over any step, so nothing depends on the
  frame rate and no step can overshoot; at a constant rate the outflow tends to R·A, and after the rain it
  decays as e^(−t/τ).
- Drops hang at an edge and let go at the pendant-drop limit, where surface tension no longer holds their weight
  (Tate's law with the Harkins–Brown correction): about 4.5 mm across for water from a flat edge, here
  ``DROP_D_MM`` ± 10 % per site. A site's period is the drop's volume over its share of the roof's outflow.
- A released drop falls from rest under gravity and quadratic drag, v(t) = v_t·tanh(g·t/v_t),
  y(t) = y₀ − (v_t²/g)·ln cosh(g·t/v_t), v_t its measured terminal speed (physics.terminal_velocity).
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import physics
from rain_core.physics import G_M_S2, RHO_WATER

DROP_D_MM = 4.5  # mm, pendant-drop limit of water from an edge
MAX_PERIOD_S = 1.0e6  # s: a site slower than this is dry (no drop drawn)
MIN_OUTFLOW_M3_S = 1.0e-12


def drop_diameters_mm(phase: np.ndarray) -> np.ndarray:
    """Each site's drop diameter (mm): DROP_D_MM ± 10 %, from its phase hash (the same in the shader)."""
    return DROP_D_MM * (0.9 + 0.2 * np.modf(np.asarray(phase) * 7.31)[0])


class RoofReservoirs:
    """Water held on each roof (m³); ``step(dt, rate)`` integrates exactly; ``outflow_m3_s`` what leaves."""

    # Asked every frame and mostly unchanged between frames (steady rain): kept while the arrays they are made of
    # stay the same objects (step and settle replace storage_m3, never write into it).
    _settled: tuple | None = None  # (rate, storage, area, drain) where storage is settle's S∞ at that rate
    _outflow: tuple | None = None  # (storage, drain, outflow m³/s read-only, its sum)

    def __init__(self, area_m2, drain_s):
        self.area_m2 = np.asarray(area_m2, dtype=np.float64)
        self.drain_s = np.maximum(np.asarray(drain_s, dtype=np.float64), 1e-3)
        self.storage_m3 = np.zeros_like(self.area_m2)

    def settle(self, rate_mm_h: float) -> None:
        """Jump to the steady state at rate_mm_h (mm/h): a scene that starts in rain starts dripping."""
        self.storage_m3 = rate_mm_h / 3.6e6 * self.area_m2 * self.drain_s
        self._settled = (rate_mm_h, self.storage_m3, self.area_m2, self.drain_s)

    def _is_settled_at(self, rate_mm_h: float) -> bool:
        """Whether storage_m3 is still settle's S∞ for this very rate (its sign of zero included)."""
        settled = self._settled
        return (settled is not None and settled[1] is self.storage_m3 and settled[2] is self.area_m2
                and settled[3] is self.drain_s and settled[0] == rate_mm_h
                and math.copysign(1.0, settled[0]) == math.copysign(1.0, rate_mm_h))

    def step(self, dt_s: float, rate_mm_h: float) -> None:
        """Advance dt_s (s, ≥ 0) at a constant rain rate (mm/h): S ← S∞ + (S − S∞)·e^(−dt/τ), S∞ = R·A·τ."""
        if not math.isnan(dt_s) and self._is_settled_at(rate_mm_h):
            return  # S = S∞ already: S∞ + 0·e^(−dt/τ) is S∞ to the bit
        steady = rate_mm_h / 3.6e6 * self.area_m2 * self.drain_s
        self.storage_m3 = steady + (self.storage_m3 - steady) * np.exp(-max(dt_s, 0.0) / self.drain_s)

    @property
    def outflow_m3_s(self) -> np.ndarray:
        """Outflow of each roof (m³/s), S/τ; read-only (kept while the storage stays)."""
        return self._outflow_terms()[2]

    def total_outflow_m3_s(self) -> float:
        """The roofs' outflows summed (m³/s)."""
        return self._outflow_terms()[3]

    def _outflow_terms(self) -> tuple:
        cached = self._outflow
        if cached is None or cached[0] is not self.storage_m3 or cached[1] is not self.drain_s:
            outflow = self.storage_m3 / self.drain_s
            outflow.flags.writeable = False
            cached = self._outflow = (self.storage_m3, self.drain_s, outflow, float(outflow.sum()))
        return cached


def site_periods_s(outflow_m3_s: np.ndarray, edges: np.ndarray, roof: np.ndarray, diam_mm: np.ndarray) -> np.ndarray:
    """Seconds between drops at each site: drop volume over the site's share of its roof's outflow (m³/s);
    MAX_PERIOD_S where the roof no longer drains."""
    per_site = outflow_m3_s[roof] / np.maximum(edges[roof], 1)
    volume = math.pi / 6.0 * (diam_mm * 1e-3) ** 3
    return np.where(per_site > MIN_OUTFLOW_M3_S, np.minimum(volume / np.maximum(per_site, 1e-300), MAX_PERIOD_S),
                    MAX_PERIOD_S)


def fall_m(t_s, v_terminal_m_s):
    """Distance (m) fallen t_s seconds after letting go from rest, quadratic drag (v_t in m/s)."""
    vt = np.asarray(v_terminal_m_s, dtype=np.float64)
    t = np.maximum(np.asarray(t_s, dtype=np.float64), 0.0)
    x = G_M_S2 * t / vt
    # ln cosh x = x + log1p(e^(−2x)) − ln 2: exact and overflow-free for large x.
    return vt * vt / G_M_S2 * (x + np.log1p(np.exp(-2.0 * x)) - math.log(2.0))


def fall_time_s(height_m, v_terminal_m_s):
    """Seconds to fall height_m (m) from rest (the inverse of fall_m)."""
    vt = np.asarray(v_terminal_m_s, dtype=np.float64)
    h = np.maximum(np.asarray(height_m, dtype=np.float64), 0.0)
    # cosh(x) = e^(g·h/v_t²) → x = arccosh(e^y), written stably as y + ln(1 + sqrt(1 − e^(−2y))).
    y = G_M_S2 * h / (vt * vt)
    x = y + np.log1p(np.sqrt(np.maximum(-np.expm1(-2.0 * y), 0.0)))
    return vt / G_M_S2 * x


def fall_speed_m_s(t_s, v_terminal_m_s):
    vt = np.asarray(v_terminal_m_s, dtype=np.float64)
    return vt * np.tanh(G_M_S2 * np.maximum(np.asarray(t_s, dtype=np.float64), 0.0) / vt)


def landing_terms(height_m, diam_mm) -> tuple[np.ndarray, np.ndarray]:
    """(fall time s, momentum kg·m/s of one landing drop) of drops of diam_mm (mm) let go height_m (m) above the
    ground: what ``landings`` needs besides the clock and the period, fixed per site (callers keep them)."""
    vt = physics.terminal_velocity(diam_mm)
    t_fall = fall_time_s(height_m, vt)
    mass = RHO_WATER * math.pi / 6.0 * (np.asarray(diam_mm) * 1e-3) ** 3
    return t_fall, mass * fall_speed_m_s(t_fall, vt)


def landing_counts(t0_s: float, t1_s: float, period_s, phase, t_fall_s) -> np.ndarray:
    """Per site, how many drops land in (t0, t1] (s), int64: drop j lets go at (j + phase)·period (s) and lands
    t_fall_s later; none at an unsteady period (≥ MAX_PERIOD_S)."""
    period = np.asarray(period_s, dtype=np.float64)
    live = period < MAX_PERIOD_S
    released0 = np.floor((t0_s - t_fall_s) / period - phase)
    released1 = np.floor((t1_s - t_fall_s) / period - phase)
    count = np.where(live, np.maximum(released1 - released0, 0.0), 0.0)
    return count.astype(np.int64)


def landings(t0_s: float, t1_s: float, period_s, phase, height_m, diam_mm):
    """Per site, the drops that land in (t0, t1] (s): (count, momentum kg·m/s of one landing drop). A site's
    drop j lets go at (j + phase)·period and lands fall_time later. Only whole drops at a steady period count."""
    t_fall, momentum = landing_terms(height_m, diam_mm)
    return landing_counts(t0_s, t1_s, period_s, phase, t_fall), momentum
