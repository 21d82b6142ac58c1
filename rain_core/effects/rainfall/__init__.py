"""Rainfall (DESIGN §3 "Near and far rain", "Rainfall container"; issues 6 and 13): streaks of drops in a container
that follows the camera, drawn as motion-blurred drops, plus impact splashes. The drops have no state: each
one's position is a closed-form function of its index and the time, computed in the vertex shader, so the CPU's
work per frame is a handful of uniforms whatever the budget (issue 13: a 1M budget cost 25–110 ms of CPU per
frame when the CPU spawned and retired drops).

Units: m, s, m/s; drop diameter D in mm, rain rate R in mm/h. World frame +Y up, the car drives along −Z.

Container (nested boxes, denser near the viewer)
------------------------------------------------
Four axis-aligned boxes ("layers") with horizontal half-sizes ``container_m/2 × (⅛, ¼, ½, 1)``, each centred 0.8
half-sizes ahead of the camera along its horizontal view direction, from just below the ground to
``TOP_SLOPE × half-size + TOP_PAD_M`` above an eye ``EYE_ALLOWANCE_M`` high: the height is fixed, since it is the
drops' vertical period (a higher eye slides the box up; its bottom then fades in). Layer k holds a share of the
budget such that the instance density ρ_k ∝ ν_k, with ν chosen so that the summed density falls as
1/distance² (``PROFILE_EXPONENT``): near streaks — the ones a viewer reads as rain — are many and faint, far
ones sparser and carry more weight each. Membership fades linearly over the outer 20 % of each box; a drop's
weight divides by the faded summed density, so the weighted density is exact everywhere inside the outer box.

Drops without state (``drops``; shaders/rainfall/drops.glsl, whose float64 twin is ``RainfallSim.drops``)
--------------------------------------------------------------------------------------------------------
Instance i gets from its index a diameter (a bin of the drop table: the Weyl sequence of i, so every index
range holds an even spread of sizes) and a phase. Its fall speed is the measured terminal velocity, quantised
(< 1 %) so that it passes through its box a whole number m_i of times per ``TIME_PERIOD_S``: the pass count and
the fraction of the current pass are then exact from t mod 2^14 s (whole seconds and a fraction) and the epoch,
in float32, at any t. Each pass ("cycle") draws from hash(i, cycle) the spawn point, the keep decision and the
turbulence step, so the pattern never repeats. Horizontally a drop moves with (1 + j·TURBULENCE/2) times the
wind's integral ∫w dt (accumulated in float64 on the CPU; j an integer in [−3, 3]), so drops follow gusts; its
position wraps periodically into its layer's box — the box is one period of a world-anchored tiling, so it holds
a stationary uniform sample wherever the camera goes, and the CPU sends only offsets reduced modulo the box.

Budget, thinning and compensation (``rates``)
---------------------------------------------
The instance sizes follow Marshall–Palmer's shape at ``INSTANCE_RATE_MM_H`` (q(D)); the rain's N_eff(D) is
reached by thinning, not by changing the instances (so a rate change never moves a drop): with
r(D) = N_eff(D)/q(D), an instance is drawn when its cycle's keep hash < min(1, r/c), and then stands for
max(r, c)/ρ real drops — the expected weighted density is ∫q·r = N_eff exactly, for any budget. c is set so
that the drawn count follows the physical count, as before (``drawn_share``: light rain has fewer streaks),
until the budget is full at heavy rain (``BUDGET_FULL_AT_MM_H``, ~77 % of the instances drawn), and never so
that a drawn drop stands for less than one real drop. The effect's rate follows the set rate with a
``RATE_RAMP_S`` time constant (and the air empties with the same constant when the rain stops). Each drawn drop
carries its weight's light: first longer along its motion (from ``SPREAD_ALPHA``, up to ``STRETCH_MAX`` × its
footprint), then wider (up to ``WIDTH_MAX_PX``), then brighter (opacity up to ``ALPHA_MAX``);
``python -m rain_core.bench rainfall`` measures the light lost beyond and the density error.

Occlusion in the vertex shader
------------------------------
``world.occluder_height(x, z)`` — the occluder mesh (bridge deck, embankment, canopy, roofs, awnings) rendered
once into a 0.25 m top-down height map, 2 m beyond |x| = 48 m — is uploaded once as two textures; a drop below
the roof over its column is not drawn (a vertical test: the short slanted rain shadow under eaves in wind is
not modelled). Vehicles move, so the ego car and the nearest traffic (``MAX_VEHICLES``) are a uniform array:
per vehicle two convex pieces (a local box cut by the raked windshield and rear window), a drop inside is not
drawn. Drops below the ground are not drawn either.

What the camera sees
--------------------
A streak is the drop's path relative to the camera during the exposure (``camera.exposure_s``): from p(t) to
p(t) − (u − v_cam)·T, so rain tilts towards the windshield by atan(v_car/v(D)) and follows the car's actual
velocity (taken at the camera point of the ego car, including its yaw rate; finite differences for the free
camera). Width = the drop's projected diameter (Beard & Chuang's flattened shape for D > 1 mm) with a 1 px floor.
Opacity is the drop's coverage (``optics.streak_coverage``): a pixel on the path is covered A·(τ/T)/(pixel area)
on average over the exposure, A the projected area (× the weight), so α = A / (w·(ℓ + h)) with ℓ the streak's
length and h the drop's own chord along its motion (area / true width) — for a sub-pixel drop the footprint is
its path, not a pixel-long stub. A drawn instance stands for many real drops spread around it: its light is
spread first (above ``SPREAD_ALPHA``, about the opacity of one real streak at 1/60 s): longer along its motion
up to ``STRETCH_MAX`` × its footprint, then wider up to ``WIDTH_MAX_PX``, and only then brightened up to
``ALPHA_MAX`` — a faint line of rain rather than a bright flake. Colour (``shaders/rainfall/drop.glsl``,
``env.frag``, ``optics``): a drop is a tiny fish-eye (Garg & Nayar 2004, 2007) — refraction through it (its ~165°
field of view, mostly what lies just behind it), specular reflection and one internal reflection, each with its
Fresnel weight, summed over the environment the camera sees (the sky through the rain layer, as the sky pass draws
it, and the lit ground) — plus the sun, street lamps and headlights scattered by the drop (two-term
Henyey–Greenstein, the atmosphere effect's), so drops in a headlight beam glow. By day a drop is several times
brighter than the façades it covers and a little darker than the sky; seen horizontally it is ~0.7 × the
atmosphere's far-rain airlight (0.4–0.5 × before issue 14). Streaks blend over the HDR frame with the scene's depth
test, without depth writes.

Splashes
--------
Splash slot j has one impact per ``SPLASH_PERIOD_S`` at a phase of its own; hash(j, period) gives the place
(world-anchored in the splash layer's box), the drop (∝ N(D)·v(D) above 1.5 mm: smaller drops make no visible
splash) and whether it is drawn: the drawn share follows the rate of visible impacts, thinned with a fixed
ratio until the slots are full at heavy rain — hardly any in light rain. On a puddle (the road's height map
below the puddle level) a crown (height ∝ D), on a wet film a smaller crown, on a dry surface a prompt splash;
they live 100–300 ms, never under a roof or inside a vehicle.

Cost and skipping
-----------------
R = 0 after the ramp → ``active`` is False: no update, no pass. Switched off (or a zero budget), ``observe``
forgets the history, so switching back on starts at the set rate. Per frame the CPU computes the boxes, the
ramp, the thinning and ~60 uniforms; the GPU draws the environment map (64×32 texels), then the streaks in
two passes: a transform-feedback pass (``streak_record.vert``, one vertex per instance, nothing rasterised)
finds each drop, culls it before any lighting when thinned out, outside the view or occluded, lights it and
writes its streak record (56 bytes: ends, half extents, colour; GPU memory, never uploaded); one instanced quad
per record (``streak.vert``) draws it. A drop's work thus runs once, not at each of its quad's 4 corners. Then
one billboard per splash slot. Nothing is uploaded per frame but uniforms (what changes every
frame, the lights that reach the boxes included, in one uniform block, ``rain_block.RainFrame``, shared by
both programs). Texture units: ``units.RAINFALL_DROPS`` (drop table), ``RAINFALL_ENV`` (environment),
``RAINFALL_OCCLUDER`` and ``RAINFALL_OCCLUDER_COARSE`` (roof maps), ``RAINFALL_ROAD_HEIGHT`` (puddles, for the
splash kinds).

Modules
-------
``constants`` (the numbers above), ``shape`` (Beard & Chuang drop shapes), ``drops`` (hash, drop table, time
split), ``rates`` (budget share, thinning, splash flux), ``boxes`` (the container), ``vehicle_fate`` (vehicles as
convex pieces), ``sim`` (``RainfallSim``: the per-frame uniforms, and the twin of every drop and splash),
``measure`` (weighted counts for tests and the benchmark), ``streaks`` (the NumPy twin of the streak shader),
``optics`` (the drop's optics: the env.frag quadrature and its twin, the streak coverage), ``box_uniforms`` and
``rain_block`` (the per-frame uniforms and block packed from floats) —
all NumPy only, no GL — and ``effect`` (``RainfallEffect``, the GL side, imported on first use) with
``streak_pass`` (``StreakPass``: the streaks' record and quad passes and the records' buffer).
"""

from __future__ import annotations

from rain_core.effects.rainfall.boxes import Boxes, full_region, layer_boxes
from rain_core.effects.rainfall.measure import drop_weights, weighted_count
from rain_core.effects.rainfall.rates import drawn_share
from rain_core.effects.rainfall.sim import RainfallSim, RainInput, RainUpdate
from rain_core.effects.rainfall.streaks import StreakCamera, streak_geometry

# The constants live in ``constants``, the hash and the drop table in ``drops``, vehicles in ``vehicle_fate``.
__all__ = ["Boxes", "RainInput", "RainUpdate", "RainfallEffect", "RainfallSim", "StreakCamera", "drawn_share",
           "drop_weights", "full_region", "layer_boxes", "streak_geometry", "weighted_count"]


def __getattr__(name: str):
    """``RainfallEffect`` is imported on first use, so the simulation modules import (and run) without moderngl."""
    if name == "RainfallEffect":
        from rain_core.effects.rainfall.effect import RainfallEffect

        return RainfallEffect
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
