"""Rainfall (DESIGN §3 "Near and far rain", "Rainfall container"; issue 6): streak particles in a container that
follows the camera, whose fate is settled when they spawn, drawn as motion-blurred drops, plus impact splashes.

Units: m, s, m/s; drop diameter D in mm, rain rate R in mm/h. World frame +Y up, the car drives along −Z.

Container (nested boxes, denser near the viewer)
------------------------------------------------
Four axis-aligned boxes ("layers") with horizontal half-sizes ``container_m/2 × (⅛, ¼, ½, 1)``, each centred 0.8
half-sizes ahead of the camera along its horizontal view direction (so the camera sits a tenth of the box from
its back face, where the fade ends and the view begins), from just below the ground to ``TOP_SLOPE × half-size``
above the eye (about the top of the view frustum at the far face). A box holds the view frustum's slab poorly
(~40 % of the drops are in view, the rest are the reservoir that falls or drifts into it), but it can be
refilled exactly when it moves (below). Each layer holds a Poisson process of drops with a uniform density
n_k = κ·ν_k; ν is chosen so that the summed density falls as 1/distance² (``PROFILE_EXPONENT``): every layer
gets about as many drops as the next smaller one twice, so the streaks near the eye — the ones a viewer reads as
rain — are many and faint rather than few and saturated, while the far ones, sub-pixel and short, are sparser
and carry more weight each. Membership fades linearly over the outer 20 % of each box; a drop's weight divides
by the faded summed density, so the weighted density is exact everywhere inside the outer box — except in the
outer box's own fade, where the streaks fade into the far rain (the atmosphere effect's extinction).

Keeping the container filled (no per-frame work on every drop)
-------------------------------------------------------------
Drops live in world space. Between two frames the drops of one size move by u·dt (wind, fall speed v(D)) and
the box moves with the camera. The region that is new to the box — inside it now, outside the previous box
advected with the drops — is a union of slabs on the box's leading faces (the top face while drops fall in, the
front face while the car drives, the upwind face in wind, every face when the box resizes). Those slabs are
sampled exactly (Poisson counts, D from Marshall–Palmer, a drop kept when it lies in its own D-dependent slab
and in no earlier one). On the first frame the whole box is new. So the set of drops inside each box is at all
times a sample of the world's stationary rain, whatever the camera does (turning, reversing, stopping).

A drop leaves by hitting something (its lifetime, settled at spawn) or by leaving its box. The CPU keeps a
calendar of when each drop is due for a check (its hit time, or when it would leave its box at the current
relative velocity); only the due drops are looked at (the ones that left are freed and cleared on the GPU,
the others rescheduled). The GPU computes every position from the spawn point, velocity and age, and culls what
lies outside its box. CPU work per frame is proportional to the spawn rate, not to the particle count.

Budget, thinning and compensation
---------------------------------
Physical drop densities are ~700–4000 drops/m³ (``physics.number_density_per_m3``), millions in a container. The
drawn count is ``HEADROOM × budget × min(1, N(R)/N(BUDGET_FULL_AT_MM_H))``: it follows the physical density
until the budget is full at heavy rain (8 mm/h), so light rain has fewer streaks than heavy rain, as it should.
Each drawn drop stands for w = N_eff(R)/n_draw(x) real drops (≥ 1; N_eff = density_scale·N) and is drawn
with w times the light of one drop: first **brighter** (opacity up to ``ALPHA_MAX``), then **wider** (up to
``WIDTH_MAX_PX``); only beyond that is light lost (``python -m rain_core.bench rainfall`` measures how much).
The weight is stored per drop when it spawns, so a change of rate changes the picture only as drops are
replaced — no pop. The rate the effect uses also approaches the set rate with a ``RATE_RAMP_S`` time constant.

Occlusion: a top-down roof height map, not ray casts against trimesh
-------------------------------------------------------------------
``world.occluder_height(x, z)`` is the occluder mesh (bridge deck, embankment, canopy, roofs, awnings) rendered
once into a 0.25 m top-down height map. A drop's straight path (slanted by wind) is marched through that map,
from ``BACKWARD_MAX_M`` above the drop down to the ground: the first point below a roof ends the drop's life
there; a hit before the spawn point means the drop would have come through a roof (under it, or in the strip of
rain shadow under an eave) and it is not spawned. A map lookup is a few array operations for thousands of
drops, where a trimesh ray cast costs microseconds per ray and needs its acceleration structure; two max-pooled
copies of the map (4 m and 1 m blocks) narrow each path to the stretch that can meet a roof, so a drop over the
open road costs a handful of lookups. (Sampling every 0.25 m, a slanted path can clip the corner of a roof
unseen: ~0.2 % of the drops near buildings.) The share of each box that rain can reach is tracked with probe
drops, so the budget goes to the open air, not into buildings.

Vehicles move, so they are tested analytically: the ego car and the traffic as convex pieces (the body below the
belt line, and the greenhouse with its raked windshield) moving at their velocity at spawn time; a drop whose
path relative to a vehicle enters it ends there (roof, hood, windshield, sides). A drop inside a vehicle, or that
would have left one less than ``VEHICLE_WAKE_S`` ago, is not spawned; a longer ballistic wake would be wrong,
since small drops ride the airflow around the body. A vehicle that brakes or turns after a drop spawned can
meet drops its fate did not foresee (they fall through it for the rest of their short lives).

What the camera sees
--------------------
A streak is the drop's path relative to the camera during the exposure (``camera.exposure_s``): from
p(t) to p(t − T) + v_cam·T, so rain tilts towards the windshield by atan(v_car/v(D)) and follows the car's actual
velocity (taken at the camera point of the ego car, including its yaw rate; finite differences for the free
camera). Width = the drop's projected diameter (Beard & Chuang's flattened shape for D > 1 mm) with a 1 px floor;
opacity = (weight × projected drop area) / (streak area), since a drop covers each pixel of its streak for only
a fraction of the exposure. Colour (``shaders/rainfall/drop.glsl``): a drop is a tiny fish-eye that
shows ~94 % of the radiance of a ~165° view behind it (Garg & Nayar), plus the sun, street lamps and headlights
scattered by the drop (two-term Henyey–Greenstein phase function, the same as the atmosphere effect), so drops
in a headlight beam glow. Streaks blend over the HDR frame with the scene's depth test, without depth writes
or sorting.

Splashes
--------
Not tied to drops (DESIGN §3): impact points are drawn at random on the open ground near the camera at the rate
of visible impacts, ∫_{D ≥ 1.5 mm} N(D)·v(D) dD per m² per s (smaller drops make no visible splash), thinned
with a fixed ratio until ``splash`` capacity is full at heavy rain — hardly any in light rain. On a puddle a
crown (height ∝ D, a few cm for the largest drops), on a wet film a smaller crown, on a dry surface a prompt
splash (droplets only); they live 100–300 ms, never under a roof or a vehicle.

Cost and skipping
-----------------
R = 0 with no drops left in the air → ``active`` is False: no update, no pass. Switched off (or a zero budget),
``observe`` forgets every drop, so switching back on refills the container at once. Per frame the GPU draws the
environment map (64×32 texels, each the mean of 64 sky directions), then one instanced quad per drop slot: a
slot outside the view or its box is culled in the vertex shader before any lighting; only the lights that reach
the container are looped over. Texture units: ``units.RAINFALL_STATE`` (drop state), ``units.RAINFALL_ENV``
(environment).

Modules
-------
``constants`` (the numbers above), ``shape`` (Beard & Chuang drop shapes), ``rates`` (budget share and splash
flux), ``boxes`` (the container), ``occluders`` (the roof map and its march), ``vehicle_fate`` (vehicles as convex
pieces), ``pool`` (drop slots and their calendar), ``sim`` (``RainfallSim``: spawning, retiring, splashes),
``measure`` (weighted counts for tests and the benchmark), ``streaks`` (the NumPy twin of the streak shader) —
all NumPy only, no GL — and ``effect`` (``RainfallEffect``, the GL side, imported on first use).
"""

from __future__ import annotations

from rain_core.effects.rainfall.boxes import Boxes, full_region, layer_boxes
from rain_core.effects.rainfall.measure import drop_weights, weighted_count
from rain_core.effects.rainfall.pool import DropPool
from rain_core.effects.rainfall.rates import drawn_share
from rain_core.effects.rainfall.sim import RainfallSim, RainInput, RainUpdate
from rain_core.effects.rainfall.streaks import StreakCamera, streak_geometry

# The constants live in ``constants``, the fate tests in ``occluders`` and ``vehicle_fate``.
__all__ = ["Boxes", "DropPool", "RainInput", "RainUpdate", "RainfallEffect", "RainfallSim", "StreakCamera",
           "drawn_share", "drop_weights", "full_region", "layer_boxes", "streak_geometry", "weighted_count"]


def __getattr__(name: str):
    """``RainfallEffect`` is imported on first use, so the simulation modules import (and run) without moderngl."""
    if name == "RainfallEffect":
        from rain_core.effects.rainfall.effect import RainfallEffect

        return RainfallEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
