"""Moved to rain_core.effects.rainfall (one module per concept; the GL effect in effect.py). Kept so the names
tests, benchmarks, sheets and users imported from ``rain_core.rainfall`` stay importable. (``DropPool`` is gone:
the drops have no state since issue 13.)"""

from rain_core.effects.rainfall.boxes import Boxes, full_region, layer_boxes
from rain_core.effects.rainfall.constants import SPLASH_D_MIN_MM, SPLASH_LIFE_S, TYPE_PROMPT
from rain_core.effects.rainfall.effect import RainfallEffect
from rain_core.effects.rainfall.measure import drop_weights, weighted_count
from rain_core.effects.rainfall.rates import drawn_share
from rain_core.effects.rainfall.sim import RainfallSim, RainInput, RainUpdate
from rain_core.effects.rainfall.streaks import StreakCamera, streak_geometry
from rain_core.effects.rainfall.vehicle_fate import vehicle_pieces

__all__ = ["SPLASH_D_MIN_MM", "SPLASH_LIFE_S", "TYPE_PROMPT", "Boxes", "RainInput", "RainUpdate", "RainfallEffect",
           "RainfallSim", "StreakCamera", "drawn_share", "drop_weights", "full_region", "layer_boxes",
           "streak_geometry", "vehicle_pieces", "weighted_count"]
