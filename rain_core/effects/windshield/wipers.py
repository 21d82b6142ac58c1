"""Windshield wipers: tandem blade geometry on the glass, the stroke motion and the mode controller (issue 8).

Coordinates are the windshield's own flat frame (``rain_core.effects.windshield.glass.GlassGeometry``): s (m) to
the car's right along the glass, t (m) up the glass from its lower edge. Angles are measured counter-clockwise
from +s, seen from inside the car.

Tandem pattern of a left-hand-drive car: both pivots sit just below the glass (under the cowl), the blades
park lying along the lower edge pointing right and sweep up together (same angle profile); the driver's blade
ends its up-stroke standing near the left A-pillar, the passenger's near the middle. A cycle is an up-stroke
and a down-stroke of equal length; within a stroke the angle follows a crank-like profile (1 − cos πp)/2, so
the blade eases into each reversal as a linkage-driven arm does.

Modes (``settings.wipers.mode``):
  off           a stroke in progress finishes back to park, then the blades rest
  intermittent  one cycle at the low rate, then ``interval_s`` at park (the first cycle starts at once)
  low / high    continuous cycles at ``low_cycles_per_min`` / ``high_cycles_per_min``
  auto          rain sensing: while parked, a cycle starts when the water on the sensor patch (kg/m²) exceeds
                AUTO_THRESHOLD_KG_M2 / sensitivity; that cycle runs at the high rate if the reading is over
                AUTO_HIGH_FACTOR × the threshold, else low. The pause between wipes therefore follows how fast
                water gathers: long in drizzle, zero (continuous wiping) in a downpour.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import checks

MODES = ("off", "intermittent", "low", "high", "auto")

# Rain sensor: 3 g/m² is a few millimetre-sized drops on a credit-card-sized patch — drizzle while parked
# reaches it in ~10 s, moderate rain at motorway speed in well under a second.
AUTO_THRESHOLD_KG_M2 = 3e-3
AUTO_HIGH_FACTOR = 3.0
SENSOR_CENTRE_FRACTION = (-0.04, 0.48)  # (s / bottom width, t / height): behind the mirror, in the driver's sweep
SENSOR_SIZE_M = (0.12, 0.08)  # (across, up the glass)


@dataclass(frozen=True)
class Blade:
    """One wiper: pivot (s, t) m on the glass plane, the blade's rubber from r_inner_m to r_outer_m from the
    pivot, and its angles (rad, counter-clockwise from +s) at park and at the top of the up-stroke."""

    name: str
    pivot: tuple[float, float]
    r_inner_m: float
    r_outer_m: float
    park_rad: float
    top_rad: float

    def angle(self, progress) -> np.ndarray | float:
        """Blade angle (rad) at stroke position ``progress`` in [0, 1] (0 park, 1 top), crank-like easing."""
        # A Python float is clipped in Python (np.clip costs ~8 µs a call); the rest is the same operations.
        p = min(max(progress, 0.0), 1.0) if type(progress) is float else np.clip(progress, 0.0, 1.0)
        return self.park_rad + (self.top_rad - self.park_rad) * 0.5 * (1.0 - np.cos(math.pi * p))

    def segment(self, angle: float) -> tuple[np.ndarray, np.ndarray]:
        """(inner end, outer end) of the rubber blade in (s, t) m at ``angle`` (rad)."""
        d = np.array([math.cos(angle), math.sin(angle)])
        p = np.asarray(self.pivot, dtype=np.float64)
        return p + self.r_inner_m * d, p + self.r_outer_m * d


def tandem_blades(width_bottom_m: float, width_top_m: float, height_m: float) -> tuple[Blade, Blade]:
    """The driver's (left) and passenger's blades for a glass of the given size (m), proportioned on a
    saloon's 1.54 m × 1.1 m windshield: driver's blade ~0.66 m sweeping 3°→100°, passenger's ~0.47 m
    sweeping 4°→86°."""
    w, h = float(width_bottom_m), float(height_m)
    if not (w > 0 and h > 0 and width_top_m > 0):
        raise ValueError("glass dimensions must be > 0 m")
    pivot_t = -0.03 * h
    driver = Blade("driver", (-0.27 * w, pivot_t), 0.13 * h, 0.73 * h, math.radians(3.0), math.radians(100.0))
    passenger = Blade(
        "passenger", (0.105 * w, pivot_t), 0.10 * h, 0.53 * h, math.radians(4.0), math.radians(86.0)
    )
    return driver, passenger


@dataclass(frozen=True)
class StrokeSegment:
    """A piece of blade motion within one time step: stroke position from ``p_start`` to ``p_end`` (0 park,
    1 top), then ``event``: None, "top" (the up-stroke just ended) or "park" (the cycle just ended)."""

    p_start: float
    p_end: float
    event: str | None = None


def stroke_position(cycle_phase: float) -> float:
    """Stroke position in [0, 1] at a phase in [0, 1] of a wipe cycle (up for the first half, down after)."""
    c = min(max(cycle_phase, 0.0), 1.0)
    return 2.0 * c if c <= 0.5 else 2.0 - 2.0 * c


class WiperController:
    """Runs the wiper motor for the chosen mode (see the module docstring). Deterministic, no randomness.

    ``advance(dt_s, mode, interval_s, low_cpm, high_cpm, sensor_kg_m2, sensitivity)`` moves time on by dt_s
    seconds and returns the StrokeSegments the blades travelled (several when a reversal falls inside
    the step).
    ``phase`` is None while parked, else the cycle phase in [0, 1); ``cycles`` counts finished cycles and
    ``cycle_starts`` the simulation times (s) at which cycles began.
    """

    def __init__(self):
        self.phase: float | None = None
        self.rate_cpm = 0.0  # cycles per minute of the cycle in progress
        self.parked_s = math.inf  # time at park since the last cycle ended (inf: never ran)
        self.time_s = 0.0
        self.cycles = 0
        self.cycle_starts: list[float] = []

    @property
    def running(self) -> bool:
        return self.phase is not None

    @property
    def progress(self) -> float:
        """Stroke position now, 0 (park) … 1 (top)."""
        return 0.0 if self.phase is None else stroke_position(self.phase)

    def _start_rate(
        self,
        mode: str,
        interval_s: float,
        low_cpm: float,
        high_cpm: float,
        sensor_kg_m2: float,
        sensitivity: float,
    ) -> float | None:
        """Cycles per minute of a cycle to start now from park, or None to stay parked."""
        if mode in ("low", "high"):
            return low_cpm if mode == "low" else high_cpm
        if mode == "intermittent":
            return low_cpm if self.parked_s >= interval_s else None
        if mode == "auto":
            threshold = AUTO_THRESHOLD_KG_M2 / sensitivity
            if sensor_kg_m2 >= threshold:
                return high_cpm if sensor_kg_m2 >= AUTO_HIGH_FACTOR * threshold else low_cpm
        return None

    def advance(
        self,
        dt_s: float,
        mode: str,
        interval_s: float = 4.0,
        low_cpm: float = 45.0,
        high_cpm: float = 70.0,
        sensor_kg_m2: float = 0.0,
        sensitivity: float = 1.0,
    ) -> list[StrokeSegment]:
        """Advance dt_s (s, ≥ 0) in ``mode``; returns the stroke segments travelled, in order."""
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
        dt_s = checks.number("dt_s", dt_s, 0.0, unit="s")
        interval_s = checks.number("interval_s", interval_s, 0.0, unit="s", lo_open=True)
        low_cpm = checks.number("low_cpm", low_cpm, 0.0, unit="cycles/min", lo_open=True)
        high_cpm = checks.number("high_cpm", high_cpm, 0.0, unit="cycles/min", lo_open=True)
        sensitivity = checks.number("sensitivity", sensitivity, 0.0, lo_open=True)
        sensor_kg_m2 = checks.number("sensor_kg_m2", sensor_kg_m2, 0.0, unit="kg/m²")
        return self._advance(dt_s, mode, interval_s, low_cpm, high_cpm, sensor_kg_m2, sensitivity)

    def _advance(
        self,
        dt_s: float,
        mode: str,
        interval_s: float,
        low_cpm: float,
        high_cpm: float,
        sensor_kg_m2: float,
        sensitivity: float,
    ) -> list[StrokeSegment]:
        """``advance`` without its checks, for callers that checked their inputs at their own boundary."""
        segments: list[StrokeSegment] = []
        remaining = float(dt_s)
        t = self.time_s
        for _ in range(1000):  # each pass ends a stroke or the step; bounded for safety
            if self.phase is None:
                if mode == "intermittent":  # the pause may end inside this step: start exactly then
                    wait = max(interval_s - self.parked_s, 0.0)
                    if wait > remaining:
                        self.parked_s += remaining
                        break
                    remaining -= wait
                    t += wait
                    self.parked_s += wait
                rate = self._start_rate(mode, interval_s, low_cpm, high_cpm, sensor_kg_m2, sensitivity)
                if rate is None:
                    self.parked_s += remaining
                    break
                self.phase, self.rate_cpm = 0.0, rate
                self.cycle_starts.append(t)
            if remaining <= 0.0:
                break
            if mode == "off":
                self.rate_cpm = low_cpm  # finish the stroke back to park at the low rate
            elif mode in ("low", "high"):
                self.rate_cpm = low_cpm if mode == "low" else high_cpm
            per_s = self.rate_cpm / 60.0
            boundary = 0.5 if self.phase < 0.5 else 1.0
            need = (boundary - self.phase) / per_s
            if need > remaining:
                new = self.phase + remaining * per_s
                segments.append(StrokeSegment(stroke_position(self.phase), stroke_position(new)))
                self.phase = new
                t += remaining
                remaining = 0.0
                break
            segments.append(
                StrokeSegment(
                    stroke_position(self.phase),
                    stroke_position(boundary),
                    "top" if boundary == 0.5 else "park",
                )
            )
            remaining -= need
            t += need
            if boundary == 0.5:
                self.phase = 0.5
            else:
                self.phase = None
                self.parked_s = 0.0
                self.cycles += 1
        self.time_s += float(dt_s)
        return segments
