"""Moved to rain_core.effects.windshield; kept so earlier imports (``rain_core.windshield.WindshieldSim``, …)
still work."""

from rain_core.effects.windshield.airflow import airflow_onset_speed_m_s
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BEAD_CAPACITY_KG_M,
    BEAD_THRESHOLD_M,
    CONTACT_ANGLE_DEG,
    FILM_CELLS,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    M_OBJECT_MIN,
    MAX_SUBSTEP_S,
    RESIDUE_M,
    VOLUME_PER_RADIUS3,
    drop_mass,
    drop_radius,
)
from rain_core.effects.windshield.effect import WindshieldEffect
from rain_core.effects.windshield.glass import GlassGeometry
from rain_core.effects.windshield.grid import grid_pairs as _grid_pairs
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.reference import WindshieldSimReference
from rain_core.effects.windshield.sim import WindshieldSim
from rain_core.physics import RHO_WATER as RHO_W

__all__ = [
    "BEAD_BINS",
    "BEAD_CAPACITY_KG_M",
    "BEAD_THRESHOLD_M",
    "CONTACT_ANGLE_DEG",
    "FILM_CELLS",
    "GAMMA_W",
    "HEIGHT_PER_RADIUS",
    "HYSTERESIS",
    "MAX_SUBSTEP_S",
    "M_OBJECT_MIN",
    "RESIDUE_M",
    "RHO_W",
    "VOLUME_PER_RADIUS3",
    "GlassGeometry",
    "GlassInputs",
    "WindshieldEffect",
    "WindshieldSim",
    "WindshieldSimReference",
    "_grid_pairs",
    "airflow_onset_speed_m_s",
    "drop_mass",
    "drop_radius",
]
