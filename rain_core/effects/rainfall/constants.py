"""Rainfall constants: the container's layers, the budget, the stateless drops, streak drawing
and the splashes (the package docstring explains each). Units: m, s, m/s; D in mm; R in mm/h."""

from __future__ import annotations

import numpy as np

from rain_core import layout

# --- the container ---
PERIOD_M = layout.PERIOD_M  # m, the world repeats along z
GROUND_Y_M = 0.0  # m, drops end at the road plane (kerbs and sidewalks hide the last 15 cm by depth test)
BOX_BOTTOM_Y_M = -0.5  # m, the boxes reach just below the ground
LAYER_SCALES = (0.125, 0.25, 0.5, 1.0)  # half-size of each layer relative to the outer one
PROFILE_EXPONENT = 2.0  # the summed density ∝ half-size^−p (see the package docstring)


def _profile(scales, p: float) -> tuple[float, ...]:
    """ν_k such that Σ_{j ≥ k} ν_j ∝ scale_k^−p, with ν of the outer layer 1."""
    total = np.asarray(scales, dtype=np.float64) ** -p
    nu = total - np.append(total[1:], 0.0)
    return tuple(float(v) for v in nu / nu[-1])


LAYER_PROFILE = _profile(LAYER_SCALES, PROFILE_EXPONENT)  # ν_k
FORWARD_OFFSET = 0.8  # box centre this many half-sizes ahead: the back face fades out just behind the eye
TOP_SLOPE = 0.8  # box top = eye height + TOP_SLOPE × half-size + TOP_PAD_M
TOP_PAD_M = 1.0
# m: a box's height is fixed (it is the vertical period of its drops, which must not change while the camera
# moves): from BOX_BOTTOM_Y_M to the top of the box for an eye this high (the chase camera is at 2.6 m). A
# higher eye slides the box up (its bottom then fades in).
EYE_ALLOWANCE_M = 3.0
FADE_FRACTION = 0.2  # membership ramps over this share of each half-size (sides) and of the height (top)
BUDGET_FULL_AT_MM_H = 8.0  # mm/h from which the whole budget is used (heavy rain)
RATE_RAMP_S = 1.5  # s, time constant with which the effect's rate follows the set rate
RATE_OFF_MM_H = 0.002  # mm/h, below this (with the set rate 0) the rain is off
TURBULENCE = 0.15  # per-drop horizontal velocity jitter, × wind (standard deviation of the factor)
TURBULENCE_STEPS = 3  # the wind factor is 1 + j·TURBULENCE/2 with an integer j in [−3, 3] (std 2): exact mod a box

# --- stateless drops (the package docstring, "Drops without state") ---
TIME_PERIOD_S = 16384  # s (2^14): the GPU gets t mod this as whole seconds + a fraction, and the epoch
TABLE_BITS = 12  # the drop table has 2^12 quantile bins of the instance size distribution per layer
TABLE_SIZE = 1 << TABLE_BITS
INSTANCE_RATE_MM_H = 28.0  # mm/h: instance diameters follow Marshall–Palmer's shape at this rate (see rates)
MAX_VEHICLES = 8  # vehicles (nearest first) whose bodies cull drops in the shader
SPLASH_PERIOD_S = 0.3125  # s, each splash slot has one impact per period (≥ the longest splash life)

# --- streak drawing --- (keep the NumPy twin, ``streaks.streak_geometry``, in step with
# shaders/rainfall/streak_record.vert).
WIDTH_FLOOR_PX = 1.0  # px, narrowest streak; thinner drops get less opacity instead
# A drawn instance stands for many real drops (its weight), spread through the volume around it. Their light is
# spread first: a streak above SPREAD_ALPHA gets longer along its motion (up to STRETCH_MAX × its footprint: the
# drops it stands for seen as a line of rain), then wider (up to WIDTH_MAX_PX), and only then brighter (up to
# ALPHA_MAX); beyond all three, light is lost. SPREAD_ALPHA is about the opacity of one real streak at 1/60 s
# (π/4·D/(v·T + D) ≈ 0.02–0.05 for 2–4 mm drops), so a compensated streak reads as a faint line of rain, not a
# bright flake (widening first made far streaks square flecks, like snow).
SPREAD_ALPHA = 0.05
STRETCH_MAX = 3.0
ALPHA_MAX = 0.7
WIDTH_MAX_PX = 4.0

# --- splashes ---
SPLASH_D_MIN_MM = 1.5  # mm, smaller drops make no visible splash
SPLASH_LIFE_S = (0.1, 0.3)  # s, lifetime of the smallest and largest splashing drop
SPLASH_CROWN_HEIGHT_PER_D = 7.0  # crown height / D (a 4 mm drop throws a ~3 cm crown)
SPLASH_LAYER = 1  # splashes fall on the ground inside this layer's box
SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX = 256, 65536
TYPE_PUDDLE_CROWN, TYPE_FILM_CROWN, TYPE_PROMPT = 0, 1, 2
