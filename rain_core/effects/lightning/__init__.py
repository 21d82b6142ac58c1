"""Lightning (issue 19): a seeded thunderstorm schedule with published stroke statistics (``schedule``), the
branching channel (``bolt``), and the flash lighting the street and the sky (``LightningEffect``, imported lazily
so the schedule stays importable without GL)."""

from rain_core.effects.lightning.bolt import bolt_segments
from rain_core.effects.lightning.schedule import (
    CONVECTIVE_RATE_MM_H,
    PEAK_CD,
    SPEED_OF_SOUND_M_S,
    Flash,
    FlashSchedule,
    auto_flashes_per_min,
    mean_intensity_cd,
)

__all__ = ["CONVECTIVE_RATE_MM_H", "PEAK_CD", "SPEED_OF_SOUND_M_S", "Flash", "FlashSchedule", "LightningEffect",
           "auto_flashes_per_min", "bolt_segments", "mean_intensity_cd"]


def __getattr__(name: str):
    if name == "LightningEffect":
        from rain_core.effects.lightning import effect

        return effect.LightningEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
