"""Compiled kernels of the spray's per-frame spawn (rain_core.jit): each replaces a chain of NumPy calls of the
emitter's fast path (``spawn.spawn_parcels_fast``) with one loop over a frame's parcels.

Their NumPy twins stay the fallback and the oracle: ``launch.launch_droplets_sorted`` / ``launch_mist``
(:func:`launch_parcels`), ``spawn._terminal_velocity``, ``launch.carrier_air_and_tau`` and
``flight.ground_time`` (:func:`fly`), ``body.body_hit_time_fast`` (:func:`body_hit`). The same operations in the
same order, so the results agree to rounding (libm's exp/log/sin/cos/pow against NumPy's, and Newton's
stopping test per parcel instead of over all of them: tests/effects/spray/test_kernels.py states the tolerances).
Random numbers are drawn by the caller, in the twin's order, and passed in. Units: m, s, m/s, mm for drop sizes.

The kernels by concern: ``flight``, ``body_test``, ``launches``, ``records``, ``wheel_state``; ``spawn_frame``
runs five of them in one call.
"""

from rain_core.effects.spray.kernels.body_test import body_hit  # noqa: F401
from rain_core.effects.spray.kernels.flight import fly  # noqa: F401
from rain_core.effects.spray.kernels.launches import launch  # noqa: F401
from rain_core.effects.spray.kernels.records import (  # noqa: F401
    add_wet_landings,
    due_landings,
    file_records,
    push_rows,
    quantile_90,
    settle,
    settle_horizons,
    tally,
)
from rain_core.effects.spray.kernels.spawn_frame import launch_to_records  # noqa: F401
from rain_core.effects.spray.kernels.wheel_state import wheel_kinematics, wheel_water  # noqa: F401
