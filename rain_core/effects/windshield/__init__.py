"""The driver's windshield (DESIGN §3 "Windshield", issue 8): drops that gather, slide with the airflow, merge
and trail, a water film, wipers that push water, and the refraction of the street through it all.

One module per concept; everything but ``effect`` is NumPy only (no GL), so the simulation runs, tests and
times without a GL context:

``constants``  the model's numbers and a drop's cap geometry (``drop_radius``, ``drop_mass``)
``glass``      ``GlassGeometry``: the glass surface, its coordinates (s, t) / UV, gravity along it
``airflow``    the air over the glass and the drag on a drop (``airflow_onset_speed_m_s``)
``inputs``     ``GlassInputs``: what the glass sees in a frame
``grid``       the spatial hash that finds merge candidates (``grid_pairs``; the fast ``PairFinder``)
``wipers``     blade geometry, the stroke motion and the mode controller
``reference``  ``WindshieldSimReference``: the float64 NumPy reference — the water bookkeeping, arrivals and
               the step, with its parts ``dynamics`` (motion, trails, shedding), ``merging``, ``film`` (drying,
               beading), ``wiping``
``sim``        ``WindshieldSim``: the fast path the effect runs (the same model and state, far fewer NumPy calls,
               work bounded per step; compared with the reference in tests/effects/windshield/test_fast_path.py)
``kernels``    the fast path's compiled loops (Numba, rain_core.jit; the NumPy code stays their twin and fallback;
               the same glass bit for bit: tests/effects/windshield/test_kernels.py)
``splats``     the instance rows the effect draws from the simulation's state
``effect``     ``WindshieldEffect``: the GL side (water textures, the glass)

Bad input is refused where ``GlassInputs`` are made (ValueError naming the field and its range); the step
trusts them.
"""

from rain_core.effects.windshield.airflow import airflow_onset_speed_m_s
from rain_core.effects.windshield.constants import FILM_CELLS, drop_mass, drop_radius
from rain_core.effects.windshield.glass import GlassGeometry
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.reference import WindshieldSimReference
from rain_core.effects.windshield.sim import WindshieldSim
from rain_core.effects.windshield.wipers import Blade, StrokeSegment, WiperController, tandem_blades

__all__ = [
    "FILM_CELLS",
    "Blade",
    "GlassGeometry",
    "GlassInputs",
    "StrokeSegment",
    "WindshieldEffect",
    "WindshieldSim",
    "WindshieldSimReference",
    "WiperController",
    "airflow_onset_speed_m_s",
    "drop_mass",
    "drop_radius",
    "tandem_blades",
]


def __getattr__(name: str):
    # The GL effect is imported on first use, so importing the simulation needs no moderngl.
    if name == "WindshieldEffect":
        from rain_core.effects.windshield.effect import WindshieldEffect

        return WindshieldEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
