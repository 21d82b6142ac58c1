"""Moved to ``rain_core.effects.atmosphere`` (``model``, ``glow``, ``scattering``, ``effect``); kept so earlier
imports (``rain_core.atmosphere.sky_overcast``, ``visibility_m``, ``Atmosphere``) still work."""

from rain_core.effects.atmosphere import *  # noqa: F403
from rain_core.effects.atmosphere import AtmosphereEffect
from rain_core.effects.atmosphere import __all__ as _moved

Atmosphere = AtmosphereEffect  # the earlier class name

__all__ = [*_moved, "Atmosphere"]
