"""When and where lightning flashes, and how bright a flash is over a camera's shutter (NumPy, no GL).

Statistics of negative cloud-to-ground flashes (Rakov & Uman 2003, "Lightning: Physics and Effects", ch. 4;
Rakov 2007, "Lightning return stroke speed"):
- a flash has several return strokes; 3–5 is typical (here uniform over 3, 4, 5), about 60 ms apart (geometric
  mean; here uniform in 40–80 ms);
- subsequent strokes are dimmer: their peak currents are typically 1/3–1/2 of the first stroke's (here the
  luminous peak is scaled the same way, uniform in 0.3–0.6);
- a return stroke's light rises in microseconds; the channel as a whole fades over about a millisecond (here
  τ = 1 ms); about half the flashes carry a continuing current after a stroke that glows for some 100 ms at a
  few per cent of the peak (here an afterglow τ = 100 ms at 3 %).
The luminous intensity of the whole channel at a stroke's peak is ``PEAK_CD``, set from the energy budget: a
flash dissipates ~10⁹ J, of which ~1 % leaves as light (Rakov & Uman 2003, ch. 1), ~10⁷ J over ~0.3 s; at
~100 lm/W that is ~10⁸ cd on average over the flash, which these strokes and afterglows give. The user scales it.

Flashes come from a seeded Poisson process evaluated in fixed one-minute blocks, each block's draws from its own
generator, so what happens at time t depends only on (seed, t) and never on how the time was stepped. Bolts land
at a uniform random bearing and at distances drawn uniformly over the disc's area between ``NEAR_M`` and the
farthest distance set (a storm's flashes over the ground around the viewer).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PEAK_CD = 5.0e9  # cd, luminous intensity of the whole channel at a first stroke's peak
STROKE_TAU_S = 1.0e-3  # s, a return stroke's light decay
AFTERGLOW_TAU_S = 0.1  # s, continuing-current glow
AFTERGLOW_SHARE = 0.03  # of the stroke's peak
STROKES = (3, 5)  # per flash, inclusive
STROKE_GAP_S = (0.040, 0.080)  # s between strokes
SUBSEQUENT_SCALE = (0.3, 0.6)  # peak of strokes after the first, relative to the first
NEAR_M = 500.0
BLOCK_S = 60.0
SPEED_OF_SOUND_M_S = 343.0  # dry air at 20 °C: 2.9 s per km, the "3 seconds per kilometre" rule
CONVECTIVE_RATE_MM_H = 16.0  # rain rates from here on come from convective cells (thunderstorms)


def auto_flashes_per_min(rate_mm_h: float) -> float:
    """The flash rate (1/min) a storm at rain rate R (mm/h) gets when none is set: 0 below 16 mm/h (stratiform
    rain rarely has lightning), then 1/min rising by 1/min per 10 mm/h, up to 6/min (a single active cell within
    ~10 km flashes a few times a minute)."""
    if rate_mm_h < CONVECTIVE_RATE_MM_H:
        return 0.0
    return min(6.0, 1.0 + (rate_mm_h - CONVECTIVE_RATE_MM_H) / 10.0)


@dataclass(frozen=True)
class Flash:
    """One flash: start time (s), ground point bearing (rad, from +X towards +Z) and distance (m) from the
    origin of the schedule, stroke times (s, absolute) and peak intensities (cd), and which strokes glow after
    (continuing current), and its own seed (for the bolt's shape)."""

    start_s: float
    bearing_rad: float
    distance_m: float
    stroke_s: tuple[float, ...]
    stroke_cd: tuple[float, ...]
    afterglow: tuple[bool, ...]
    seed: int

    @property
    def end_s(self) -> float:
        """When its light has faded below 1e-4 of the peak (s)."""
        return self.stroke_s[-1] + AFTERGLOW_TAU_S * math.log(AFTERGLOW_SHARE / 1e-4)

    def thunder_delay_s(self) -> float:
        return self.distance_m / SPEED_OF_SOUND_M_S


class FlashSchedule:
    """The flashes of a storm: ``flashes_per_min`` (1/min, ≥ 0), ``far_m`` (m, ≥ NEAR_M), ``seed``."""

    def __init__(self, flashes_per_min: float, far_m: float = 10_000.0, seed: int = 0):
        if not (math.isfinite(flashes_per_min) and flashes_per_min >= 0.0):
            raise ValueError(f"flashes_per_min must be a finite number ≥ 0 1/min, got {flashes_per_min!r}")
        if not (math.isfinite(far_m) and far_m >= NEAR_M):
            raise ValueError(f"far_m must be ≥ {NEAR_M:g} m, got {far_m!r}")
        self.flashes_per_min = float(flashes_per_min)
        self.far_m = float(far_m)
        self.seed = int(seed)
        self._blocks: dict[int, list[Flash]] = {}

    def block(self, index: int) -> list[Flash]:
        """The flashes starting in [index·60 s, (index + 1)·60 s), sorted by start (cached, a few blocks)."""
        cached = self._blocks.get(index)
        if cached is not None:
            return cached
        if len(self._blocks) > 8:
            self._blocks.clear()
        rng = np.random.default_rng([self.seed, 0x11647, index & 0x7FFFFFFF, index >> 31 & 0x7FFFFFFF])
        count = int(rng.poisson(self.flashes_per_min * BLOCK_S / 60.0))
        starts = np.sort(rng.uniform(0.0, BLOCK_S, count)) + index * BLOCK_S
        flashes = []
        for start in starts:
            n = int(rng.integers(STROKES[0], STROKES[1] + 1))
            gaps = rng.uniform(*STROKE_GAP_S, n - 1)
            times = start + np.concatenate([[0.0], np.cumsum(gaps)])
            scale = np.concatenate([[1.0], rng.uniform(*SUBSEQUENT_SCALE, n - 1)])
            glow = rng.random(n) < 0.5
            r = math.sqrt(rng.uniform(NEAR_M**2, self.far_m**2))
            flashes.append(Flash(float(start), float(rng.uniform(0.0, 2.0 * math.pi)), r,
                                 tuple(float(t) for t in times), tuple(float(PEAK_CD * s) for s in scale),
                                 tuple(bool(g) for g in glow), int(rng.integers(0, 2**31 - 1))))
        self._blocks[index] = flashes
        return flashes

    def flashes_between(self, t0_s: float, t1_s: float) -> list[Flash]:
        """Flashes whose light overlaps [t0_s, t1_s] (s)."""
        if self.flashes_per_min <= 0.0 or not (math.isfinite(t0_s) and math.isfinite(t1_s)):
            return []
        first = math.floor((t0_s - 2.0) / BLOCK_S)  # a flash lasts < 1 s: one block back is plenty
        last = math.floor(t1_s / BLOCK_S)
        if last - first > 1000:  # an absurd window: only its end matters to a frame
            first = last - 1
        return [f for b in range(first, last + 1) for f in self.block(b) if f.start_s <= t1_s and f.end_s >= t0_s]

    def last_flash(self, t_s: float, lookback_s: float = 120.0) -> Flash | None:
        """The latest flash started at or before t_s (s), within lookback_s."""
        if self.flashes_per_min <= 0.0 or not math.isfinite(t_s):
            return None
        for b in range(math.floor(t_s / BLOCK_S), math.floor((t_s - lookback_s) / BLOCK_S) - 1, -1):
            started = [f for f in self.block(b) if f.start_s <= t_s]
            if started:
                return started[-1]
        return None


def _exp_integral(t0: np.ndarray, t1: np.ndarray, start: float, tau: float) -> np.ndarray:
    """∫ exp(−(u − start)/τ) du over [t0, t1] ∩ [start, ∞) (s)."""
    a = np.maximum(t0, start)
    b = np.maximum(t1, start)
    return tau * (np.exp(-(a - start) / tau) - np.exp(-(b - start) / tau))


def mean_intensity_cd(flash: Flash, t0_s, t1_s):
    """The flash's luminous intensity (cd) averaged over the shutter [t0_s, t1_s] (s): exact integrals of each
    stroke's decay and afterglow, so it is the same at any frame rate (a 0.1 ms stroke lands in the one frame
    whose shutter holds it). t1 − t0 ≤ 0 gives the instantaneous intensity at t1."""
    t0 = np.asarray(t0_s, dtype=np.float64)
    t1 = np.asarray(t1_s, dtype=np.float64)
    width = t1 - t0
    total = np.zeros(np.broadcast(t0, t1).shape)
    for ts, cd, glow in zip(flash.stroke_s, flash.stroke_cd, flash.afterglow, strict=True):
        terms = [(STROKE_TAU_S, cd)] + ([(AFTERGLOW_TAU_S, cd * AFTERGLOW_SHARE)] if glow else [])
        for tau, peak in terms:
            inst = peak * np.where(t1 >= ts, np.exp(-np.maximum(t1 - ts, 0.0) / tau), 0.0)
            avg = peak * _exp_integral(t0, t1, ts, tau) / np.where(width > 0, width, 1.0)
            total = total + np.where(width > 0, avg, inst)
    return total
