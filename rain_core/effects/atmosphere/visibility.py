"""The visibility a scene's settings give, and the haze that gives a visibility asked for (GL-free).

Visibility is the meteorological optical range (MOR, WMO): the distance at which a black object's contrast
against the horizon falls to 5 %, V = −ln(0.05)/β ≈ 3/β, β the total extinction of the air: clear air, the rain at
its rate (× the atmosphere's fog_scale) and the haze (atmosphere.haze_per_km). The same β the atmosphere effect
renders with (``model.extinction_per_m``), so what is asked is what is drawn.
"""

from __future__ import annotations

import math

from rain_core.effects.atmosphere.model import CONTRAST_THRESHOLD, extinction_per_m, rain_extinction_per_m
from rain_core.physics import CLEAR_AIR_EXTINCTION_PER_M

MOR_LN = -math.log(CONTRAST_THRESHOLD)  # ≈ 2.996


def visibility_m(settings) -> float:
    """The meteorological optical range (m, 5 % contrast) of the scene with ``settings`` (rain_core.settings.
    Settings): clear air + rain + haze; with the atmosphere effect off, the clear air alone (the rain is then
    not drawn as a medium)."""
    atm = settings.atmosphere
    rate = settings.rain.rate_mm_h
    beta = extinction_per_m(rate, atm.fog_scale, atm.haze_per_km) if atm.enabled else CLEAR_AIR_EXTINCTION_PER_M
    return MOR_LN / beta


def haze_for_visibility(visibility: float, rate_mm_h: float, fog_scale: float = 1.0) -> tuple[float, float]:
    """(haze_per_km, shortfall): the haze extinction (1/km) that, with the clear air and the rain at rate_mm_h
    (mm/h, × fog_scale), gives a total visibility of ``visibility`` (m); shortfall > 0 (m) when the rain alone
    already sees less far than asked (the haze is then 0 and the visibility is the rain's)."""
    if not (visibility > 0.0):
        raise ValueError(f"visibility must be > 0 m, got {visibility!r}")
    if math.isinf(visibility):
        return 0.0, 0.0
    wanted = MOR_LN / visibility
    have = CLEAR_AIR_EXTINCTION_PER_M + fog_scale * float(rain_extinction_per_m(rate_mm_h))
    if have > wanted:
        return 0.0, visibility - MOR_LN / have
    return (wanted - have) * 1000.0, 0.0
