"""Rainfall constants: the container's layers, the budget, the drop calendar, streak drawing, the occlusion march
and the splashes (the package docstring explains each). Units: m, s, m/s; D in mm; R in mm/h."""

from __future__ import annotations

import numpy as np

from rain_core import layout

# --- the container ---
PERIOD_M = layout.PERIOD_M  # m, the world repeats along z
TIME_PERIOD_S = 1024.0  # s, spawn times are stored modulo this on the GPU (every lifetime is far shorter)
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
FADE_FRACTION = 0.2  # membership ramps over this share of each half-size (sides) and of the height (top)
HEADROOM = 0.8  # expected live drops = this share of the budget (room for Poisson fluctuations)
BUDGET_FULL_AT_MM_H = 8.0  # mm/h from which the whole budget is used (heavy rain)
RATE_RAMP_S = 1.5  # s, time constant with which the effect's rate follows the set rate
RATE_OFF_MM_H = 0.002  # mm/h, below this (with the set rate 0) no more drops spawn
MIN_RECHECK_S = 0.05  # s, shortest delay before a due drop that is still inside is looked at again
CALENDAR_BUCKET_S = 1.0 / 32.0  # s; a check may come up to this late (it only delays the reuse of a slot)
CALENDAR_BUCKETS = 4096  # 128 s ahead; later checks are clamped to the end
TURBULENCE = 0.15  # per-drop horizontal velocity jitter, × wind speed (m/s)
OPEN_PROBES_FIRST, OPEN_PROBES = 4096, 512  # probe points per box for the open share (first frame, later)
OPEN_PROBE_EVERY = 8  # frames between probes
OPEN_PROBE_BLEND = 0.3  # weight of a new probe in the open share's running average

# --- streak drawing --- (keep the NumPy twin, ``streaks.streak_geometry``, in step with shaders/rainfall/streak.vert).
WIDTH_FLOOR_PX = 1.0  # px, narrowest streak; thinner drops get less opacity instead
ALPHA_MAX = 0.7  # a compensated streak gets brighter up to this opacity …
WIDTH_MAX_PX = 4.0  # … then wider up to this width; beyond, light is lost

# --- occlusion march ---
MARCH_STEP_M = 0.25  # m, horizontal spacing of the fine march (the height map's cell)
MARCH_MAX_SAMPLES = 128
REFINE_STEPS = 4  # bisections of the step in which a path meets a roof
FATE_CHUNK = 131072  # drops per batch of the fate tests (bounds the march's memory)
SKIP_BLOCK_M = 4.0  # m, cells of the max-pooled map used to skip paths far from any roof
FINE_BLOCK_M = 1.0  # m, cells of the second, finer pooled map
# m, how far above a drop its past path is checked for roofs. Wind inside a street canyon is far weaker than
# above the roofs, so a long ballistic rain shadow (small drops drift 2 m per m of fall in a 2 m/s wind) would put
# whole streets in the dry; a short reach keeps the dry strip under eaves, decks and canopies.
BACKWARD_MAX_M = 3.0
VEHICLE_WAKE_S = 0.05  # s, a drop that was inside a vehicle this recently is not spawned (see vehicle_fate)

# --- splashes ---
SPLASH_D_MIN_MM = 1.5  # mm, smaller drops make no visible splash
SPLASH_LIFE_S = (0.1, 0.3)  # s, lifetime of the smallest and largest splashing drop
SPLASH_CROWN_HEIGHT_PER_D = 7.0  # crown height / D (a 4 mm drop throws a ~3 cm crown)
SPLASH_LAYER = 1  # splashes fall on the ground inside this layer's box
SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX = 256, 65536
TYPE_PUDDLE_CROWN, TYPE_FILM_CROWN, TYPE_PROMPT = 0, 1, 2
