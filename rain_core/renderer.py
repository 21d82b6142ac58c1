"""Moved to ``rain_core.gfx``; kept so earlier imports (``rain_core.renderer.Renderer``, ``Frame``) still work."""

from rain_core.gfx.effect import STAGES, Effect
from rain_core.gfx.frame import Frame, PassStat, RenderContext, SharedResources
from rain_core.gfx.renderer import CLEAR_AIR_EXTINCTION_PER_M, Renderer

__all__ = ["CLEAR_AIR_EXTINCTION_PER_M", "STAGES", "Effect", "Frame", "PassStat", "RenderContext", "Renderer",
           "SharedResources"]
