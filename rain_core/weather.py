"""Weather over time: the road's wet film and two flood levels filling in rain and drying after it, and wind.

Levels (each normalised to [0, 1], DESIGN §3): ``wetness`` — the water film that darkens the asphalt;
``cracks`` — the first flood level, water standing in cracks and ruts; ``puddles`` — the second flood level.

Model (piecewise linear, so every step is integrated exactly)
-------------------------------------------------------------
* Rain counts when R ≥ ``R_WET_MIN_MM_H`` (0.05 mm/h; fainter drizzle evaporates on contact). Then each level
  rises at its fill rate (per second) and stops at 1; the drying clock (``time_since_rain_s``) stays at 0.
* Fill rates are Lagarde's control table (DESIGN §3), made continuous in R: the light / moderate / heavy rows
  are anchored at 0.5 / 2 / 8 mm/h (the geometric centres of those bands on the six-band scale, also the
  presets' rates), interpolated linearly in log R between anchors, falling to 0 at 0.05 mm/h and held at the
  heavy row above 8 mm/h.
* Without rain, each level drains at its drying rate (film 0.2/s, cracks 0.1/s, puddles 0.05/s) and stops at 0,
  but only once the drying clock has passed its onset: film at ``drying_delay_s``, cracks one
  ``drying_stage_gap_s`` later, puddles two later — the film dries first, cracks next, puddles last.
* A step at constant R is a sum of exact segments (the drying step is split where each onset falls), so one
  10 s step equals a hundred 0.1 s steps to rounding, and no dt can leave [0, 1].
* Lagarde's rates are game-time rates (a road wets in seconds). ``time_scale`` multiplies the dt the levels see:
  < 1 for slower, more realistic wetting, > 1 to hurry a demo, 0 to freeze them. Wind is not scaled.
* A level can be pinned (``pin``) from the UI: it then reports the pinned value and stays there; ``unpin``
  lets it evolve again from that value.

Wind: mean speed (m/s), direction (rad, the heading the wind blows *toward*, measured in the ground plane from
−Z towards +X) and gustiness in [0, 1]. Gusts are a seeded sum of sinusoids evaluated at absolute time, so they
are smooth, reproducible and independent of how time was stepped. The wind velocity is horizontal (+Y up).
Each sinusoid's time is reduced modulo its own period first (``fmod`` is exact), so the wind stays finite at any
finite time (ω·t would overflow to inf, and sin(inf) is NaN, past ~1e307 s).

Bounds: one step is at most ``MAX_STEP_S`` (1e9 s, ~32 years; the levels are exact for any dt, and the bound
keeps the summed time finite); every argument is checked at the boundary (a number, finite, in its range).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import checks, physics

LEVELS = ("wetness", "cracks", "puddles")
R_WET_MIN_MM_H = 0.05  # mm/h, below this no level rises and the road dries

# Lagarde's table: anchors (mm/h) for the light, moderate and heavy rows, and each level's rates per second.
ANCHOR_RATES_MM_H = (0.5, 2.0, 8.0)
FILL_PER_S = {
    "wetness": (0.6, 0.75, 1.0),
    "cracks": (0.2, 0.5, 0.85),
    "puddles": (0.1, 0.3, 0.7),
}
DRY_PER_S = {"wetness": 0.2, "cracks": 0.1, "puddles": 0.05}

GUST_COMPONENTS = 6  # sinusoids per gust signal
GUST_FREQ_HZ = (0.03, 0.6)  # range of gust frequencies, log-uniform
GUST_DIRECTION_SWING_RAD = 0.35  # largest direction swing at gustiness 1
MAX_STEP_S = 1e9  # s, longest single step


def fill_rates_per_s(rate_mm_h) -> np.ndarray:
    """Fill rates of (wetness, cracks, puddles) in 1/s at rain rate R (mm/h, [0, 500]); shape R.shape + (3,).

    Linear in log R through (0.05 → 0), (0.5 → light), (2 → moderate), (8 → heavy), constant above 8 mm/h.
    """
    r = physics._check_rate(rate_mm_h)
    xs = np.log(np.array((R_WET_MIN_MM_H,) + ANCHOR_RATES_MM_H))
    logr = np.log(np.maximum(r, R_WET_MIN_MM_H))
    return np.stack([np.interp(logr, xs, (0.0,) + FILL_PER_S[name]) for name in LEVELS], axis=-1)


@dataclass(frozen=True)
class WindState:
    """Wind at one instant. speed_m_s, direction_rad, gustiness: the mean settings; velocity_m_s: the
    gust-modulated velocity (x, y, z) in m/s, world frame (+Y up, y = 0); gust_speed_m_s: its length."""

    speed_m_s: float = 0.0
    direction_rad: float = 0.0
    gustiness: float = 0.0
    velocity_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gust_speed_m_s: float = 0.0


@dataclass(frozen=True)
class WeatherState:
    """The weather handed to the effects each frame (immutable; copy freely).

    time_s: simulated time in s (unscaled); rate_mm_h: current rain rate in mm/h; category: its six-band name;
    wetness, cracks, puddles: levels in [0, 1] (pinned ones report the pinned value); time_since_rain_s: weather
    time since rain last counted (scaled by time_scale; 0 while raining, inf if it never rained);
    extinction_per_km: rain extinction β in km⁻¹; wind: WindState; pinned: names of the pinned levels.
    """

    time_s: float = 0.0
    rate_mm_h: float = 0.0
    category: str = "none"
    wetness: float = 0.0
    cracks: float = 0.0
    puddles: float = 0.0
    time_since_rain_s: float = math.inf
    extinction_per_km: float = 0.0
    wind: WindState = WindState()
    pinned: tuple[str, ...] = ()


def _check_nonneg(name: str, value, unit: str, hi: float = math.inf) -> float:
    return checks.number(name, value, 0.0, hi, unit)


class _GustSignal:
    """A smooth, zero-mean signal in [−1, 1]: a seeded sum of sinusoids with amplitudes ∝ f^−1/2 (more energy
    in slow gusts), normalised by the sum of amplitudes so it can never leave [−1, 1]."""

    def __init__(self, rng: np.random.Generator):
        lo, hi = np.log(GUST_FREQ_HZ[0]), np.log(GUST_FREQ_HZ[1])
        self.omega = 2 * np.pi * np.exp(rng.uniform(lo, hi, GUST_COMPONENTS))
        self.phase = rng.uniform(0.0, 2 * np.pi, GUST_COMPONENTS)
        amp = self.omega**-0.5
        self.amp = amp / amp.sum()
        self.period = 2 * np.pi / self.omega

    def __call__(self, t: float) -> float:
        # fmod(t, period) is exact, so this equals sin(ω·t + φ) to rounding, and stays finite for huge t.
        return float(np.dot(self.amp, np.sin(self.omega * np.fmod(t, self.period) + self.phase)))


class _GustPair:
    """Two gust signals evaluated at one time in one pass: a single fmod, product, sum and sine over both signals'
    sinusoids (each element sees the same operations as in the signal's own call, so the same bits), then each
    signal's dot product. The wind asks both every frame, and each NumPy call costs far more than its arithmetic."""

    def __init__(self, first: _GustSignal, second: _GustSignal):
        self.period = np.concatenate([first.period, second.period])
        self.omega = np.concatenate([first.omega, second.omega])
        self.phase = np.concatenate([first.phase, second.phase])
        self._amps = (first.amp, second.amp)
        self._buf = np.empty(len(self.period))  # the sines, written in place (sliced per call: copies keep no views)
        self._n = len(first.period)

    def __call__(self, t: float) -> tuple[float, float]:
        """(first, second) signal at time t (s, finite)."""
        x = self._buf
        np.fmod(t, self.period, out=x)
        np.multiply(self.omega, x, out=x)
        np.add(x, self.phase, out=x)
        np.sin(x, out=x)
        a0, a1 = self._amps
        n = self._n
        return float(np.dot(a0, x[:n])), float(np.dot(a1, x[n:]))


class Weather:
    """Wetting, drying and wind over time. Starts dry at time 0; advance it with ``step(dt_s, rate_mm_h)``.

    seed: seeds the gust signals; time_scale: multiplies the dt the levels see (≥ 0); drying_delay_s: weather
    seconds after rain before the film starts drying; drying_stage_gap_s: extra delay before cracks, and again
    before puddles; wind_speed_m_s, wind_direction_rad, gustiness ([0, 1]): see ``set_wind``.
    """

    def __init__(self, seed: int = 0, time_scale: float = 1.0, drying_delay_s: float = 10.0,
                 drying_stage_gap_s: float = 5.0, wind_speed_m_s: float = 0.0, wind_direction_rad: float = 0.0,
                 gustiness: float = 0.0):
        if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
            raise ValueError(f"seed must be an int >= 0, got {seed!r}")
        self.seed = int(seed)
        rng = np.random.default_rng(self.seed)
        self._gust_speed = _GustSignal(rng)
        self._gust_direction = _GustSignal(rng)
        self._gusts = _GustPair(self._gust_speed, self._gust_direction)
        self._applied: tuple | None = None  # the settings' values apply_settings last set (None: changed since)
        self.time_scale = time_scale
        self.drying_delay_s = drying_delay_s
        self.drying_stage_gap_s = drying_stage_gap_s
        self.paused = False  # True: the levels hold still (settings' auto_weather off); wind keeps blowing
        self._levels = dict.fromkeys(LEVELS, 0.0)
        self._pinned: set[str] = set()
        self._pinned_names: tuple[str, ...] = ()  # the pinned levels in LEVELS' order (what the state reports)
        self._time_s = 0.0
        self._rate = 0.0
        self._of_rate: tuple | None = None  # (rate, fill rates, category, extinction): they depend on it alone
        self._since_rain = math.inf
        self.set_wind(wind_speed_m_s, wind_direction_rad, gustiness)

    # --- parameters (validated on assignment) ---

    @property
    def time_scale(self) -> float:
        """Multiplier on the dt the levels see (≥ 0, at most 1e4)."""
        return self._time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        self._time_scale = _check_nonneg("time_scale", value, "×", 1e4)
        self._applied = None

    @property
    def drying_delay_s(self) -> float:
        """Weather seconds after rain stops before the film starts drying."""
        return self._drying_delay_s

    @drying_delay_s.setter
    def drying_delay_s(self, value: float) -> None:
        self._drying_delay_s = _check_nonneg("drying_delay_s", value, "s")
        self._applied = None

    @property
    def drying_stage_gap_s(self) -> float:
        """Weather seconds between the film's, the cracks' and the puddles' drying onsets."""
        return self._drying_stage_gap_s

    @drying_stage_gap_s.setter
    def drying_stage_gap_s(self, value: float) -> None:
        self._drying_stage_gap_s = _check_nonneg("drying_stage_gap_s", value, "s")
        self._applied = None

    def drying_onsets_s(self) -> dict[str, float]:
        """Weather time since rain (s) at which each level starts drying."""
        return {name: self._drying_delay_s + i * self._drying_stage_gap_s for i, name in enumerate(LEVELS)}

    def set_wind(self, speed_m_s: float, direction_rad: float, gustiness: float) -> None:
        """Mean wind speed in m/s (≥ 0, ≤ 100), heading in rad it blows toward (from −Z towards +X; any finite
        value), gustiness in [0, 1] (0 steady; 1 gusts swing the speed by up to ±100 %)."""
        speed = _check_nonneg("wind_speed_m_s", speed_m_s, "m/s", 100.0)
        direction = checks.number("wind_direction_rad", direction_rad, unit="rad")
        gust = _check_nonneg("gustiness", gustiness, "", 1.0)
        self._wind_speed, self._wind_direction, self._gustiness = speed, direction, gust
        self._applied = None

    # --- pinning ---

    @staticmethod
    def _check_level(level: str) -> None:
        if level not in LEVELS:
            raise ValueError(f"level must be one of {', '.join(LEVELS)}, got {level!r}")

    def pin(self, level: str, value: float) -> None:
        """Hold ``level`` (wetness, cracks or puddles) at ``value`` in [0, 1] until ``unpin``."""
        self._check_level(level)
        self._levels[level] = _check_nonneg(level, value, "", 1.0)
        self._pinned.add(level)
        self._pinned_changed()

    def unpin(self, level: str) -> None:
        """Let ``level`` evolve again, starting from the value it was pinned at."""
        self._check_level(level)
        self._pinned.discard(level)
        self._pinned_changed()

    def _pinned_changed(self) -> None:
        self._pinned_names = tuple(name for name in LEVELS if name in self._pinned)
        self._applied = None

    @property
    def pinned(self) -> dict[str, float]:
        """The pinned levels and their values."""
        return {name: self._levels[name] for name in LEVELS if name in self._pinned}

    def reset(self, wetness: float = 0.0, cracks: float = 0.0, puddles: float = 0.0,
              time_since_rain_s: float = math.inf) -> None:
        """Set the (unpinned) levels, each in [0, 1], and the drying clock in s (inf: it has not rained)."""
        values = {"wetness": wetness, "cracks": cracks, "puddles": puddles}
        checked = {k: _check_nonneg(k, v, "", 1.0) for k, v in values.items()}
        if time_since_rain_s != math.inf:
            time_since_rain_s = _check_nonneg("time_since_rain_s", time_since_rain_s, "s")
        for k, v in checked.items():
            if k not in self._pinned:
                self._levels[k] = v
        self._since_rain = float(time_since_rain_s)

    # --- evolution ---

    def step(self, dt_s: float, rate_mm_h: float) -> WeatherState:
        """Advance by dt_s seconds ([0, MAX_STEP_S]) at a constant rain rate in mm/h ([0, 500]); returns the state."""
        dt = _check_nonneg("dt_s", dt_s, "s", MAX_STEP_S)
        rate = _check_nonneg("rate_mm_h", rate_mm_h, "mm/h", physics.R_MAX_MM_H)
        self._time_s += dt
        self._rate = rate
        if self.paused:
            return self.state
        dw = dt * self._time_scale  # weather time
        pinned = self._pinned
        if rate >= R_WET_MIN_MM_H:
            fill = self._rate_terms(rate)[1]
            for i, name in enumerate(LEVELS):
                if name not in pinned:
                    self._levels[name] = min(1.0, self._levels[name] + float(fill[i]) * dw)
            self._since_rain = 0.0
        else:
            t0 = self._since_rain
            t1 = t0 + dw
            for name, onset in self.drying_onsets_s().items():
                if name in pinned:
                    continue
                # The part of [t0, t1] after this level's onset (all of dw when the clock is already at inf).
                drying = dw if t0 >= onset else max(0.0, t1 - onset)
                self._levels[name] = max(0.0, self._levels[name] - DRY_PER_S[name] * drying)
            self._since_rain = t1
        return self.state

    def _rate_terms(self, rate: float) -> tuple:
        """(rate, fill_rates_per_s, rain category, extinction per km) at ``rate`` (mm/h, already checked): the
        rate changes only when the user moves it, so the last one's are kept (each costs NumPy calls)."""
        terms = self._of_rate
        if terms is None or terms[0] != rate:
            terms = self._of_rate = (rate, fill_rates_per_s(rate), physics.rain_category(rate),
                                     physics.rain_extinction_per_km(rate))
        return terms

    def wind_at(self, time_s: float) -> WindState:
        """The wind at absolute time time_s (s, any finite value): mean settings plus the seeded gusts."""
        if type(time_s) is not float:  # step passes its own float; a caller's value is checked once here
            time_s = checks.number("time_s", time_s, unit="s")
        elif not math.isfinite(time_s):
            raise ValueError(f"time_s must be a finite time in s, got {time_s!r}")
        g = self._gustiness
        gust_speed, gust_direction = self._gusts(time_s)
        speed = self._wind_speed * (1.0 + g * gust_speed)
        heading = self._wind_direction + g * GUST_DIRECTION_SWING_RAD * gust_direction
        velocity = (speed * math.sin(heading), 0.0, -speed * math.cos(heading))
        return WindState(self._wind_speed, self._wind_direction, g, velocity, speed)

    @property
    def time_s(self) -> float:
        """Simulated time in s (the sum of the dt passed to step, unscaled)."""
        return self._time_s

    @property
    def state(self) -> WeatherState:
        """The current WeatherState."""
        _, _, category, extinction = self._rate_terms(self._rate)
        return WeatherState(
            time_s=self._time_s,
            rate_mm_h=self._rate,
            category=category,
            wetness=self._levels["wetness"],
            cracks=self._levels["cracks"],
            puddles=self._levels["puddles"],
            time_since_rain_s=self._since_rain,
            extinction_per_km=extinction,
            wind=self.wind_at(self._time_s),
            pinned=self._pinned_names,
        )

    # --- settings ---

    @classmethod
    def from_settings(cls, settings) -> Weather:
        """A Weather configured from a rain_core.settings.Settings (seeded by settings.wind.seed)."""
        weather = cls(seed=settings.wind.seed)
        weather.apply_settings(settings)
        return weather

    def apply_settings(self, settings) -> None:
        """Take time scale, drying delays, pause (rain.auto_weather off), pins and wind from validated settings.

        The rain rate itself is passed to ``step`` each frame (settings.rain.rate_mm_h).
        """
        rain, wind = settings.rain, settings.wind
        # Asked every frame, and the settings rarely change: nothing to set while they hold what was last applied
        # and nothing else has changed these parameters since (every setter, pin and unpin clears _applied).
        applied = (rain.time_scale, rain.drying_delay_s, rain.drying_stage_gap_s, rain.wetness, rain.cracks,
                   rain.puddles, wind.speed_m_s, wind.direction_deg, wind.gustiness)
        if applied == self._applied:
            self.paused = not rain.auto_weather
            return
        self.time_scale = rain.time_scale
        self.drying_delay_s = rain.drying_delay_s
        self.drying_stage_gap_s = rain.drying_stage_gap_s
        self.paused = not rain.auto_weather
        for name in LEVELS:
            value = getattr(rain, name)
            if value is None:
                self.unpin(name)
            else:
                self.pin(name, value)
        self.set_wind(wind.speed_m_s, math.radians(wind.direction_deg), wind.gustiness)
        self._applied = applied
