"""``GlassInputs``: what the glass sees in one frame (rain, the car's motion, wind, roof, wiper settings)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class GlassInputs:
    """What the glass sees this frame. rate_mm_h: rain rate (mm/h); car_velocity_m_s and wind_m_s: world (3,)
    m/s; car_rotation: (3, 3) car-local → world; sheltered: a roof over the glass stops the rain; drop_scale:
    arrivals × this; wiper settings: mode, interval_s, low/high cycles per minute, auto sensitivity, blade
    wear."""

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

    @classmethod
    def for_speed(cls, speed_kmh: float, rate_mm_h: float, **kwargs) -> GlassInputs:
        """A car driving straight along −Z at speed_kmh (km/h) in rain of rate_mm_h (mm/h), no wind."""
        return cls(rate_mm_h=rate_mm_h, car_velocity_m_s=np.array([0.0, 0.0, -speed_kmh / 3.6]), **kwargs)

    def relative_air_local(self) -> np.ndarray:
        """Air velocity relative to the car, in the car's local frame (m/s): +z is a headwind."""
        rel = np.asarray(self.wind_m_s, float) - np.asarray(self.car_velocity_m_s, float)
        return np.asarray(self.car_rotation, float).T @ rel
