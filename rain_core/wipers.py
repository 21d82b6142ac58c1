"""Moved to rain_core.effects.windshield.wipers; kept so earlier imports (``rain_core.wipers``) still work."""

from rain_core.effects.windshield.wipers import (
    AUTO_HIGH_FACTOR,
    AUTO_THRESHOLD_KG_M2,
    MODES,
    SENSOR_CENTRE_FRACTION,
    SENSOR_SIZE_M,
    Blade,
    StrokeSegment,
    WiperController,
    stroke_position,
    tandem_blades,
)

__all__ = [
    "AUTO_HIGH_FACTOR",
    "AUTO_THRESHOLD_KG_M2",
    "MODES",
    "SENSOR_CENTRE_FRACTION",
    "SENSOR_SIZE_M",
    "Blade",
    "StrokeSegment",
    "WiperController",
    "stroke_position",
    "tandem_blades",
]
