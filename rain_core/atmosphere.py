"""Moved to ``rain_core.effects.atmosphere`` (``model``, ``glow``, ``scattering``, ``effect``); kept so earlier
imports (``rain_core.atmosphere.sky_overcast``, ``visibility_m``, ``Atmosphere``) still work."""

from rain_core.effects.atmosphere import *  # noqa: F403
from rain_core.effects.atmosphere import AtmosphereEffect
from rain_core.effects.atmosphere import __all__ as _moved
from rain_core.effects.atmosphere.visibility import haze_for_visibility
from rain_core.effects.atmosphere.visibility import visibility_m as _scene_visibility_m

Atmosphere = AtmosphereEffect  # the earlier class name


def visibility_m(settings_or_beta, contrast: float | None = None):
    """``visibility_m(settings)``: the meteorological optical range (m) the scene has with those settings (rain +
    haze + clear air, rain_core.effects.atmosphere.visibility). ``visibility_m(beta_per_m[, contrast])``: the
    earlier form, −ln(contrast)/β (m) for an extinction β (1/m)."""
    if hasattr(settings_or_beta, "atmosphere"):
        return _scene_visibility_m(settings_or_beta)
    from rain_core.effects.atmosphere.model import CONTRAST_THRESHOLD
    from rain_core.effects.atmosphere.model import visibility_m as _beta_visibility_m

    return _beta_visibility_m(settings_or_beta, CONTRAST_THRESHOLD if contrast is None else contrast)


__all__ = [*_moved, "Atmosphere", "haze_for_visibility"]
