"""The numbers of the windshield model (see ``rain_core.effects.windshield`` for the physics they stand in),
and the spherical-cap geometry of a drop on the glass. Units: SI (m, kg, s) unless a name says otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.physics import RHO_WATER

# --- physical constants (water and air densities and g: rain_core.physics) ---------------------------------
NU_AIR = 1.5e-5  # m²/s, kinematic viscosity of air
MU_W = 1.0e-3  # Pa·s, water
GAMMA_W = 0.072  # N/m, surface tension of water

# --- drop model --------------------------------------------------------------------------------------------
CONTACT_ANGLE_DEG = 50.0  # clean automotive glass, 40–60°
_HALF = math.radians(CONTACT_ANGLE_DEG) / 2.0
HEIGHT_PER_RADIUS = math.tan(_HALF)  # cap height / contact radius
VOLUME_PER_RADIUS3 = math.pi * HEIGHT_PER_RADIUS * (3.0 + HEIGHT_PER_RADIUS**2) / 6.0  # cap volume / a³
_THETA = math.radians(CONTACT_ANGLE_DEG)
SPHERE_PER_RADIUS = 1.0 / math.sin(_THETA)  # radius of the cap's sphere / contact radius a
FRONTAL_PER_RADIUS2 = SPHERE_PER_RADIUS**2 * (_THETA - math.sin(_THETA) * math.cos(_THETA))  # segment area / a²
# Contact-angle hysteresis cos θr − cos θa. 0.25 makes drops of contact radius ≳ 3 mm (≈ 20 µL, a 3.4 mm
# raindrop's volume) slide down a 60°-raked glass — single raindrops stick, merged ones run.
HYSTERESIS = 0.25
KINETIC_PIN = 0.8  # sliding resistance / static pinning: drops stick-slip rather than glide
# Viscous resistance of a sliding drop, F = c·μ·a·v, dominated by the wedge at its contact line: c ≈
# 6·ln(a/ℓ)/θ ≈ 100 (Cox–Voinov, ℓ ~ 1 nm). Down a 60° glass a 4 mm drop then slides at ~0.15 m/s and a
# 6 mm one at ~0.7 m/s.
VISCOUS_C = 100.0
# Drag coefficient of a sessile cap in shear flow (more than a free sphere's ~0.5). With the boundary layer
# below, a drop at mid-glass starts to climb at ~110 km/h (2 mm contact radius), ~85 km/h (3 mm) and
# ~65 km/h (5 mm): small drops stay put at any speed, large ones stream up.
DRAG_CD = 1.2
BL_RUN_UP_M = 0.2  # boundary-layer run from the stagnation line at the cowl to the glass's lower edge
FLOW_AT_BOTTOM = 0.3  # air speed over the glass / headwind: low near the cowl (stagnation) …
FLOW_AT_TOP = 1.0  # … accelerating to the free stream at the roof
FLOW_SPREAD = 0.35  # outward flow towards the A-pillars at the glass's side edges, / the upward flow
CROSSWIND_GAIN = 0.6  # sideways air speed over the glass / crosswind

D_OBJECT_MM = 0.5  # arrivals smaller than this (after splashing) join the film: sub-pixel at 1080p
M_OBJECT_MIN = RHO_WATER * math.pi / 6.0 * (D_OBJECT_MM * 1e-3) ** 3  # kg
SPLASH_SPEED_M_S = (3.0, 25.0)  # normal impact speed where splashing starts / reaches SPLASH_MAX
SPLASH_MAX = 0.7  # most of a drop that can splash into satellite mist
TRAIL_SPACING_RADII = 3.0  # a running drop drops a droplet every this many of its radii
TRAIL_FRACTION = 0.02  # of the drop's mass, per trail droplet
TRAIL_PARENT_MIN = 25.0 * M_OBJECT_MIN  # drops lighter than this leave no droplets (only the wet line)
TRAIL_FILM_M = 0.3e-6  # thickness of the wet line a running drop leaves (m)
V_STOP_M_S = 1e-3

# --- film --------------------------------------------------------------------------------------------------
FILM_CELLS = 64  # the CPU film grid is FILM_CELLS × FILM_CELLS over the glass's UV square
BEAD_THRESHOLD_M = 8e-6  # a film thicker than this (m, cell mean) beads up into a drop
BEAD_KEEP = 0.25  # the film left in a cell that beaded, × the threshold
# Evaporation of thin water, kg/m²/s at rest, × (1 + U/EVAP_AIR_M_S) with U the air speed over the glass:
# a 0.1 µm wiper streak dries in ~10 s parked and in ~1 s at motorway speed.
FILM_EVAP_KG_M2_S = 1e-5
EVAP_AIR_M_S = 2.0
# Diffusion-limited evaporation of a sessile drop, dm/dt = −k·a (k = 4·D_v·Δc in humid rain air): hours.
DROP_EVAP_KG_M_S = 1.7e-7

# --- the water the wipers push -----------------------------------------------------------------------------
BEAD_BINS = 24  # radial bins of the water a blade pushes
RESIDUE_M = 0.1e-6  # film left behind a new, wet blade (m); × (1 + 4·wear)
# Water a blade can push per metre of its length before it leaks past the rubber: a bead ~2 mm across.
BEAD_CAPACITY_KG_M = 3e-3
END_LEAVE_FRACTION = 0.35  # of the bead, left as a row of drops where a stroke ends; the rest sheds
BLADE_HALF_WIDTH_M = 0.006  # the rubber's reach either side of its line

MAX_SUBSTEP_S = 1.0 / 30.0  # the simulation sub-steps a frame at most this long (frames: checks.MAX_FRAME_DT_S)

# --- work bounds per sub-step (issue 18): whatever the valid input, a step does bounded work --------------------
# Arrivals drawn one by one; more (only far beyond real rain: 500 mm/h at 200 km/h into a gale, ×4 drops) land as
# mist of the same mean mass, spread over the film. 8 mm/h at 120 km/h brings ~1,800 per sub-step.
MAX_ARRIVALS_PER_SUBSTEP = 32_768
# The merge test's spatial hash: grid cells covered by the swept boxes of large or fast drops, and candidate
# pairs. Over the first, the drops with the longest steps are tested where they end (their sweep is not
# tested); over the second, the remaining drops wait for the next sub-step. Ordinary rain needs ~1/100 of these.
MERGE_CELLS_MAX = 1 << 16
MERGE_PAIRS_MAX = 1 << 18


def norm2(v: np.ndarray) -> np.ndarray:
    """Lengths of (n, 2) vectors (np.linalg.norm is ~20× slower on this shape)."""
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1])


def drop_radius(mass_kg) -> np.ndarray:
    """Contact radius (m) of a drop of the given mass (kg) sitting on the glass as a spherical cap."""
    return np.cbrt(np.asarray(mass_kg, dtype=np.float64) / (RHO_WATER * VOLUME_PER_RADIUS3))


def drop_mass(radius_m) -> np.ndarray:
    """Mass (kg) of a cap of contact radius ``radius_m`` (m)."""
    return RHO_WATER * VOLUME_PER_RADIUS3 * np.asarray(radius_m, dtype=np.float64) ** 3


def uniform_index(u: np.ndarray, count: np.ndarray) -> np.ndarray:
    """A random index in [0, count) from each uniform ``u`` in [0, 1): floor(u·count) (below count for any u < 1;
    the min guards it). One uniform a pick: a bulk draw, where ``Generator.integers`` with an array of bounds costs
    ~70 ns each (kernels.give_to_drops makes the same picks in its loop)."""
    return np.minimum((u * count).astype(np.int64), count - 1)
