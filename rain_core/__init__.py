"""Rainroad core: rain effects, their simulations and a headless renderer (no window, no ImGui)."""

__version__ = "0.1.0"
