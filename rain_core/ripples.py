"""Moved to ``rain_core.effects.ripples``; kept so earlier imports (``rain_core.ripples.WaveSolver``) still work."""

from rain_core.effects.ripples import *  # noqa: F403
from rain_core.effects.ripples import __all__ as _moved

__all__ = [*_moved]
