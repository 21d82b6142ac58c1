"""Where the rain is along an eye ray, for the rainbow: the rain around the viewer while it rains, and after it
stops the departing shower, a slab that recedes at the shower's speed (GL-free).

A bow needs sunlit drops in front of the viewer. While it rains they fill every ray from the eye to the first
surface or the cloud base. When the rain stops here it goes on further away: the shower that passed moves off
(``shower_speed_m_s``) and stays ``shower_width_m`` deep, so the bow lingers on it, fainter as the surfaces of
the street hide the nearer part of the slab, then only against the sky, then gone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MAX_DISTANCE_M = 20_000.0  # beyond this no departing shower is drawn (the air's own extinction hides it)


@dataclass(frozen=True)
class RainColumn:
    """Rain at ``rate_mm_h`` (mm/h) between ``near_m`` and ``far_m`` (m) along every eye ray."""

    rate_mm_h: float
    near_m: float
    far_m: float


class ShowerTracker:
    """Follows the rain rate over time (``observe`` every frame) and gives the rain column of a moment."""

    def __init__(self):
        self.last_rain_s: float | None = None  # s, the last time it rained here
        self.last_rate_mm_h = 0.0

    def observe(self, time_s: float, rate_mm_h: float) -> None:
        """Record the rate (mm/h) at time_s (s). Time running backwards (a restarted scene) forgets the past."""
        if self.last_rain_s is not None and time_s < self.last_rain_s:
            self.last_rain_s, self.last_rate_mm_h = None, 0.0
        if rate_mm_h > 0.0:
            self.last_rain_s, self.last_rate_mm_h = time_s, rate_mm_h

    def column(self, time_s: float, rate_mm_h: float, speed_m_s: float, width_m: float) -> RainColumn | None:
        """The rain the eye rays cross at time_s: all of them from the eye while it rains (rate_mm_h > 0); after
        the rain, the departing shower [v·(t − t_stop), + width] (m); None once it is beyond MAX_DISTANCE_M or
        it never rained."""
        if rate_mm_h > 0.0:
            return RainColumn(rate_mm_h, 0.0, math.inf)
        if self.last_rain_s is None:
            return None
        near = speed_m_s * max(time_s - self.last_rain_s, 0.0)
        if near >= MAX_DISTANCE_M:
            return None
        return RainColumn(self.last_rate_mm_h, near, near + width_m)
