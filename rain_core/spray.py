"""Moved to ``rain_core.effects.spray``; kept so earlier imports still work."""

from rain_core.effects.spray import *  # noqa: F403
from rain_core.effects.spray import SprayEffect
from rain_core.effects.spray import __all__ as _moved

Spray = SprayEffect  # the earlier class name

__all__ = [*_moved, "Spray"]
