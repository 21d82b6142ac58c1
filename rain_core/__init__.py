"""Rainroad core: rain effects, their simulations and a headless renderer (no window, no ImGui).

``from rain_core import Session, Weather`` is the scripting API (rain_core.session); it is imported on first use,
so ``import rain_core`` stays light and GL-free.
"""

__version__ = "0.1.0"

_LAZY = {"Session": "rain_core.session", "Weather": "rain_core.session", "Capture": "rain_core.session",
         "load_dataset": "rain_core.session"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'rain_core' has no attribute {name!r}")


def __dir__():
    return sorted([*globals(), *_LAZY])
