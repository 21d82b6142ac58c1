"""The rainbow (issue 19): the primary and secondary bows on sunlit rain, from water's dispersion and Airy's
theory over the drop-size distribution (``optics``), on the rain the eye rays cross (``shower``).
The GL side (``RainbowEffect``) is imported lazily so the optics stay importable without GL."""

from rain_core.effects.rainbow.optics import (
    THETA_RANGE_DEG,
    airy_ai,
    bow_lut,
    bow_phase_rgb,
    cie_xyz_bar,
    drop_cross_section_sr,
    rainbow_angle_deg,
    rainbow_ray,
    rainbow_transmission,
    water_refractive_index,
)
from rain_core.effects.rainbow.shower import RainColumn, ShowerTracker

__all__ = ["THETA_RANGE_DEG", "RainColumn", "RainbowEffect", "ShowerTracker", "airy_ai", "bow_lut",
           "bow_phase_rgb", "cie_xyz_bar", "drop_cross_section_sr", "rainbow_angle_deg", "rainbow_ray",
           "rainbow_transmission", "water_refractive_index"]


def __getattr__(name: str):
    if name == "RainbowEffect":
        from rain_core.effects.rainbow import effect

        return effect.RainbowEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
