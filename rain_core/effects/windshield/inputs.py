"""``GlassInputs``: what the glass sees in one frame (rain, the car's motion, wind, roof, wiper settings).

This is the simulation's boundary (DESIGN §2): every field is checked once, when the inputs are made, and a bad
value raises ``ValueError`` naming the field, the value and the allowed range. The step then trusts them (no
checks in its loops). The settings' fields keep the ranges of the settings they come from
(``rain_core.settings``); the car's velocity and the wind, which come from the simulation rather than a
setting, are bounded by what any vehicle or gust in the project reaches, with a wide margin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rain_core import checks
from rain_core.effects.windshield.wipers import MODES
from rain_core.settings import field_info

# The ego car tops out at 200 km/h (vehicles.CAR_SPEC) and the wind at 40 m/s with gusts that at most double it;
# beyond these the sim refuses (1,000 km/h or a 10⁶ m/s wind would ask for impossible work, see issue 18).
MAX_CAR_SPEED_M_S = 100.0  # 360 km/h
MAX_WIND_M_S = 100.0
ROTATION_TOLERANCE = 1e-6  # |RᵀR − I| and |det R − 1| above this: not a rotation

# GlassInputs field → the setting whose range it keeps.
_SETTING_OF = {
    "rate_mm_h": "rain.rate_mm_h",
    "drop_scale": "windshield.drop_scale",
    "drop_budget": "windshield.drop_budget",
    "wiper_interval_s": "wipers.interval_s",
    "wiper_low_cpm": "wipers.low_cycles_per_min",
    "wiper_high_cpm": "wipers.high_cycles_per_min",
    "wiper_sensitivity": "wipers.auto_sensitivity",
    "blade_wear": "wipers.blade_wear",
}
_RANGES = {name: (field_info(path).range, field_info(path).unit, path) for name, path in _SETTING_OF.items()}
# The fields that come from the settings alone: a moving car makes new inputs every frame with the same ones.
_SETTINGS_FIELDS = tuple(name for name in _SETTING_OF if name != "rate_mm_h")
_PLAIN = (float, int)
# (the types and values of _SETTINGS_FIELDS last checked, as given; and as checked): the same plain numbers pass
# the same checks, so they are not checked again (what differs in value or type is).
_settings_memo: list = [None, None]


def _scalar(name: str, value) -> float:
    (lo, hi), unit, path = _RANGES[name]
    if isinstance(value, (np.floating, np.integer)):  # a NumPy scalar: as a Python number, checks.number's fast path
        value = value.item()
    return checks.number(f"GlassInputs.{name} ({path})", value, lo, hi, unit=unit)


def _settings(given: tuple) -> tuple:
    """``given``, the values of _SETTINGS_FIELDS in order, checked: as floats, drop_budget as an int."""
    key = (tuple(map(type, given)), given)  # types first: 1 and True, 1.0 and np.float64(1.0) differ
    if key == _settings_memo[0]:
        return _settings_memo[1]
    checked = [_scalar(name, value) for name, value in zip(_SETTINGS_FIELDS, given, strict=True)]
    budget = checked[_SETTINGS_FIELDS.index("drop_budget")]
    if budget != int(budget):
        raise ValueError(f"GlassInputs.drop_budget (windshield.drop_budget) must be an integer, got {budget!r}")
    checked[_SETTINGS_FIELDS.index("drop_budget")] = int(budget)
    checked = tuple(checked)
    if all(t in _PLAIN for t in key[0]):  # (an array's == is not a truth value: only plain numbers are kept)
        _settings_memo[:] = [key, checked]
    return checked


def _frozen(arr: np.ndarray) -> np.ndarray:
    """A read-only float64 copy of ``arr`` (the caller's array stays as it is)."""
    arr = arr.copy()  # C-contiguous, whatever arr was (a view of the car's 4×4, say)
    arr.flags.writeable = False
    return arr


def _vector(name: str, value, max_norm: float) -> np.ndarray:
    # Checked on Python floats: a frame makes one GlassInputs, and NumPy's per-call cost would dominate.
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"GlassInputs.{name} must be a 3-vector in m/s, got {checks.quote(value)}") from None
    if arr.shape != (3,):
        raise ValueError(f"GlassInputs.{name} must be one 3-vector (m/s), got shape {arr.shape}")
    x, y, z = arr.tolist()
    norm = math.sqrt(x * x + y * y + z * z)
    if not norm <= max_norm:  # also NaN and inf
        raise ValueError(
            f"GlassInputs.{name} must be finite with a length in [0, {max_norm:g}] m/s, got {checks.quote(value)}"
        )
    return _frozen(arr)


def _rotation(value) -> np.ndarray:
    try:
        rot = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(
            f"GlassInputs.car_rotation must be a (3, 3) rotation matrix, got {checks.quote(value)}"
        ) from None
    if rot.shape != (3, 3):
        raise ValueError(f"GlassInputs.car_rotation must be a (3, 3) rotation matrix, got shape {rot.shape}")
    r = rot.tolist()
    (a, b, c), (d, e, f), (g, h, k) = r
    # |RᵀR − I|: the columns (a, d, g), (b, e, h), (c, f, k), their norms and their (symmetric) dot products.
    off = max(abs(a * a + d * d + g * g - 1.0), abs(b * b + e * e + h * h - 1.0), abs(c * c + f * f + k * k - 1.0),
              abs(a * b + d * e + g * h), abs(a * c + d * f + g * k), abs(b * c + e * f + h * k))
    det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g)
    if not (off <= ROTATION_TOLERANCE and abs(det - 1.0) <= ROTATION_TOLERANCE):  # NaN fails too
        raise ValueError(
            "GlassInputs.car_rotation must be a finite rotation (orthonormal, det +1, within "
            f"{ROTATION_TOLERANCE:g}), got |RᵀR − I| = {off:.3g}, det = {det:.6g}"
        )
    return _frozen(rot)


@dataclass(frozen=True)
class GlassInputs:
    """What the glass sees this frame. rate_mm_h: rain rate (mm/h); car_velocity_m_s and wind_m_s: world (3,)
    m/s; car_rotation: (3, 3) car-local → world; sheltered: a roof over the glass stops the rain; drop_scale:
    arrivals × this; drop_budget: the most drops simulated one by one; wiper settings: mode, interval_s,
    low/high cycles per minute, auto sensitivity, blade wear.

    Checked when made (see the module docstring); frozen, so what was checked is what the step sees."""

    rate_mm_h: float = 0.0
    car_velocity_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    wind_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    car_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    sheltered: bool = False
    drop_scale: float = 1.0
    drop_budget: int = 6000
    wiper_mode: str = "off"
    wiper_interval_s: float = 4.0
    wiper_low_cpm: float = 45.0
    wiper_high_cpm: float = 70.0
    wiper_sensitivity: float = 1.0
    blade_wear: float = 0.2

    def __post_init__(self):
        put = object.__setattr__  # frozen: the checked values replace the given ones once, here
        put(self, "rate_mm_h", _scalar("rate_mm_h", self.rate_mm_h))
        checked = _settings(tuple(getattr(self, name) for name in _SETTINGS_FIELDS))
        for name, value in zip(_SETTINGS_FIELDS, checked, strict=True):
            put(self, name, value)
        put(self, "car_velocity_m_s", _vector("car_velocity_m_s", self.car_velocity_m_s, MAX_CAR_SPEED_M_S))
        put(self, "wind_m_s", _vector("wind_m_s", self.wind_m_s, MAX_WIND_M_S))
        put(self, "car_rotation", _rotation(self.car_rotation))
        if not isinstance(self.sheltered, (bool, np.bool_)):
            raise ValueError(f"GlassInputs.sheltered must be True or False, got {checks.quote(self.sheltered)}")
        put(self, "sheltered", bool(self.sheltered))
        if not isinstance(self.wiper_mode, str) or self.wiper_mode not in MODES:
            raise ValueError(
                f"GlassInputs.wiper_mode (wipers.mode) must be one of {MODES}, got {checks.quote(self.wiper_mode)}"
            )

    def moved(self, rate_mm_h, car_velocity_m_s, wind_m_s, car_rotation, sheltered) -> GlassInputs:
        """These inputs with another frame's rain, car motion, wind and roof, each checked as the constructor
        checks it; the settings' fields are these (checked when these were made). A moving car makes new inputs
        every frame with the same settings: this skips the dataclass's construction and the settings' check
        (about half the cost)."""
        if not isinstance(sheltered, (bool, np.bool_)):
            raise ValueError(f"GlassInputs.sheltered must be True or False, got {checks.quote(sheltered)}")
        new = object.__new__(GlassInputs)
        fields = new.__dict__  # (frozen: written past __setattr__, as __post_init__ does)
        fields.update(self.__dict__)
        fields["rate_mm_h"] = _scalar("rate_mm_h", rate_mm_h)
        fields["car_velocity_m_s"] = _vector("car_velocity_m_s", car_velocity_m_s, MAX_CAR_SPEED_M_S)
        fields["wind_m_s"] = _vector("wind_m_s", wind_m_s, MAX_WIND_M_S)
        fields["car_rotation"] = _rotation(car_rotation)
        fields["sheltered"] = bool(sheltered)
        return new

    @classmethod
    def for_speed(cls, speed_kmh: float, rate_mm_h: float, **kwargs) -> GlassInputs:
        """A car driving straight along −Z at speed_kmh (km/h) in rain of rate_mm_h (mm/h), no wind."""
        speed = checks.number("speed_kmh", speed_kmh, unit="km/h")
        return cls(rate_mm_h=rate_mm_h, car_velocity_m_s=np.array([0.0, 0.0, -speed / 3.6]), **kwargs)

    def relative_air_local(self) -> np.ndarray:
        """Air velocity relative to the car, in the car's local frame (m/s): +z is a headwind."""
        return self.car_rotation.T @ (self.wind_m_s - self.car_velocity_m_s)
