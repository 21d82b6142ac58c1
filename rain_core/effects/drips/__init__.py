"""Dripping edges (issue 19): water the low roofs catch (the bridge deck, the canopy, awnings) drips from their
edges during the rain and, while they drain, after it (``edges``: where, ``flow``: how much and how it falls).
The GL side (``DripsEffect``) is imported lazily so the rest stays importable without GL."""

from rain_core.effects.drips.edges import DripSites, find_drip_sites
from rain_core.effects.drips.flow import (
    DROP_D_MM,
    RoofReservoirs,
    drop_diameters_mm,
    fall_m,
    fall_speed_m_s,
    fall_time_s,
    landings,
    site_periods_s,
)

__all__ = ["DROP_D_MM", "DripSites", "DripsEffect", "RoofReservoirs", "drop_diameters_mm", "fall_m",
           "fall_speed_m_s", "fall_time_s", "find_drip_sites", "landings", "site_periods_s"]


def __getattr__(name: str):
    if name == "DripsEffect":
        from rain_core.effects.drips import effect

        return effect.DripsEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
