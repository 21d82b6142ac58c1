"""Compiled kernels of the windshield's drop simulation (rain_core.jit): each replaces a chain of NumPy calls of
the fast path (``sim.WindshieldSim``) with one loop over the drop rows (``drop_rows``: one row a drop of the
(capacity, COLS) float64 array ``buf``; only rows [:n] are drops).

Their NumPy twins stay the fallback and the oracle: ``DropArray._flush_placed`` / ``WindshieldSim._placed``
(:func:`place_rows`), ``FastMotion._move`` (:func:`move_drops`) and ``_run`` (:func:`run_drops`),
``FastMerging._merge_moves`` with ``grid.PairFinder`` (:func:`merge_drops`), ``FastWiping._sweep``'s drops, film
and off-glass bead (:func:`sweep_blades`), ``WindshieldSim._arrive_fast`` (:func:`sample_arrivals`,
:func:`land_arrivals`), ``_give_to_drops`` (:func:`drops_in_cells`, :func:`give_to_drops`) and
``DropArray._append_at_rest`` (:func:`append_at_rest`). The same operations in the same order on the same values,
so the results are the twins' bit for bit (cube roots and the sums that NumPy adds pairwise stay in NumPy, done by
the caller on the kernels' outputs), but for the blade's angle to a drop:
libm's atan2 may differ from NumPy's by an ulp, which flips a drop's sweep only within an ulp of the blade's edge.
Random numbers are drawn by the caller, in the twins' order. Units: m, s, kg, m/s, rad.

The kernels by concern: ``motion``, ``merging``, ``wiping``, ``arrivals``, ``rows``, ``film``; ``common``
the glass's cells and the folded constants.
"""

from rain_core.effects.windshield.kernels.arrivals import (  # noqa: F401
    arrival_law,
    drops_in_cells,
    give_to_drops,
    land_arrivals,
    sample_arrivals,
)
from rain_core.effects.windshield.kernels.common import NEAR_CELLS, film_cell, inside  # noqa: F401
from rain_core.effects.windshield.kernels.film import (  # noqa: F401
    bead_points,
    evaporate_film,
    film_drying,
    sensor_masses,
)
from rain_core.effects.windshield.kernels.merging import merge_drops  # noqa: F401
from rain_core.effects.windshield.kernels.motion import move_drops, place_rows, run_drops  # noqa: F401
from rain_core.effects.windshield.kernels.rows import append_at_rest, compact_rows, shed_rows, sort_rows  # noqa: F401
from rain_core.effects.windshield.kernels.wiping import sweep_blades  # noqa: F401
