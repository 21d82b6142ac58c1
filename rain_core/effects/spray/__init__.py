"""Wheel splash and spray (DESIGN §3): every wheel throws the water it meets, by the Flintsch/Weir model.

Per wheel and frame the water the tyre meets, M_w = v·b·WFD·ρ_w, is spent in order on capillary adhesion, tread
pickup, side and bow waves (``water``); what is thrown leaves as *parcels* — each many drops of one size thrown
together, carrying its mass and so its extinction cross-section (``optics``) — whose flight is one closed form
shared with the GPU (``flight``). Each parcel's fate is decided once, at spawn: the time it meets the road, the
kerb-top or its thrower's body (``body``) is its lifetime, so no drop ever passes below the road. The parcels
alive are the budget; their masses add up to the mass the model throws, so the picture does not depend on the
budget except for its graininess. Fine spray becomes mist that the vehicle's wake carries (``launch``).

Modules
-------
``water`` (the water budget and Horne's hydroplaning risk), ``optics`` (phase function, extinction, the
constants the shaders share), ``flight`` (the closed-form flight, landing times by Newton's method and their
bisection reference, the RK4 quadratic-drag reference), ``body`` (vehicle bodies with open wheel wells; the
body test and its reference), ``wheels`` (the water model at every wheel of every vehicle in one pass, the
per-vehicle reference, and the launch geometry; the check of the vehicles' state), ``launch`` (how each bucket
of water leaves the wheel; the wake's mist), ``parcels`` (the GPU record layout, the ring buffers, the shader's
NumPy twin), ``emitter`` (``SprayEmitter``: the wheels' water into parcels, landings in standing water, the
line-of-sight optical depth) — all NumPy only, no GL — and ``probe`` (the GLSL twin evaluated by transform
feedback) and ``effect`` (``SprayEffect``), the GL side, imported on first use.

Fast path and reference (``python -m rain_core.bench spray``, tests/effects/spray/test_fast_path.py): per frame
the emitter spawns all wheels of all vehicles in one vectorised pass (counts per wheel and bucket from the
flux, then ``np.repeat`` into one row per parcel; one film lookup for every wheel and the last frame's
landings), writes only the new parcels into the rings (one slot range, two where it wraps: all the GPU upload
is), and spends no work on dead slots. ``SprayEmitter(reference=True)`` runs the float64 reference of each
step (per vehicle water model, masked launches, bisection landing times, the sampled body test): with the same
body test the two write the same parcels. Where Numba is installed (``rain_core.jit``) the fast path's chains
— wheels, accounts, launches, flight, body test, filing, landings — run as compiled loops (``kernels``), with
the NumPy code as their twin (tests/effects/spray/test_kernels.py). The frame is checked where it enters
(time, wind, vehicles' state: ValueError naming the field), and one step spawns at most about a ring's worth
whatever the input.

Shared data: ``SprayEffect.update`` publishes ``rc.shared.droplet_impacts`` ((N, 3) float64: x m, z m world,
downward momentum kg·m/s of the parcels that landed in standing water this frame), read by the ripples. The
film depth under the wheels comes from ``rain_core.water_film`` (evaluated in ``observe``, every frame, so the
hydroplaning risk is there while the effect is idle).
"""

from __future__ import annotations

from rain_core.effects.spray.body import (
    BodyBox,
    body_hit_time,
    body_hit_time_fast,
)
from rain_core.effects.spray.emitter import (
    MAX_BUDGET,
    MAX_INTERVAL_S,
    MAX_STRENGTH,
    MIN_MIST_CAPACITY,
    MIST_BUDGET_SHARE,
    SpawnStats,
    SprayEmitter,
    line_of_sight_optical_depth,
)
from rain_core.effects.spray.flight import (
    DRAG_TAIL_FIT,
    drag_time_constant,
    flight_position,
    flight_velocity,
    ground_time,
    quadratic_drag_reference,
    time_to_height,
    time_to_height_newton,
)
from rain_core.effects.spray.launch import (
    MIST_DIFFUSIVITY,
    MIST_LIFE_S,
    MIST_SIGMA0_M,
    MIST_SIGMA_MAX,
    SPRAY_AIR_SHARE,
    SPRAY_UPDRAUGHT,
    WAKE_LIFT,
    WAKE_LIFT_HEIGHT_M,
    WAKE_SHARE,
    WAKE_TAU_S,
)
from rain_core.effects.spray.optics import (
    EXTINCTION_EFFICIENCY,
    G_DIFFRACTION,
    G_REFRACTION,
    GLINT_CHANCE,
    REFLECTION_SHARE,
    WATER_IOR,
    extinction_area_m2,
    fresnel_reflection,
    henyey_greenstein,
    phase_function,
    reflection_lobe,
    shader_defines,
)
from rain_core.effects.spray.parcels import (
    FATE_AIR,
    FATE_BODY,
    FATE_ROAD,
    KIND_DROPLET,
    KIND_FADE,
    KIND_MIST,
    PARTICLE_ATTRIBUTES,
    PARTICLE_DTYPE,
    PARTICLE_FORMAT,
    parcel_state,
)
from rain_core.effects.spray.water import (
    BUCKETS,
    CAPILLARY_MM,
    DEPTH_BANDS_MM,
    HORNE_KMH_PER_SQRT_KPA,
    HYDRO_DEPTH_MM,
    HYDRO_LIFT_ONSET,
    KMH,
    MECHANISMS,
    MIST_D_MM,
    MIST_SHARE,
    RELEASE_KMH,
    SIDE_MM,
    SPLASH_MIN_MM,
    SPRAY_KMH,
    SPRAY_MAX_MM,
    STANDING_WATER_MM,
    TREAD_MM,
    TREAD_SPRAY_SHARE,
    TYRE_PRESSURE_KPA,
    WaterBudget,
    allocate_water,
    allocate_water_unchecked,
    hydroplaning_risk,
    hydroplaning_risk_unchecked,
    hydroplaning_speed_m_s,
    release_fraction,
    spray_share_of_tread,
)
from rain_core.effects.spray.wheels import (
    MAX_FILM_DEPTH_MM,
    MAX_VEHICLE_SPEED_M_S,
    WheelGeometry,
    WheelWater,
    check_vehicles,
    gather_wheels,
    road_film_depth_fn,
    wheel_water,
)

__all__ = [
    "BUCKETS", "BodyBox", "CAPILLARY_MM", "DEPTH_BANDS_MM", "DRAG_TAIL_FIT", "EXTINCTION_EFFICIENCY", "FATE_AIR",
    "FATE_BODY", "FATE_ROAD", "GLINT_CHANCE", "G_DIFFRACTION", "G_REFRACTION", "HORNE_KMH_PER_SQRT_KPA",
    "HYDRO_DEPTH_MM", "HYDRO_LIFT_ONSET", "KIND_DROPLET", "KIND_FADE", "KIND_MIST", "KMH", "MAX_BUDGET",
    "MAX_FILM_DEPTH_MM", "MAX_INTERVAL_S", "MAX_STRENGTH", "MAX_VEHICLE_SPEED_M_S", "MECHANISMS",
    "MIN_MIST_CAPACITY", "MIST_BUDGET_SHARE", "MIST_DIFFUSIVITY", "MIST_D_MM", "MIST_LIFE_S", "MIST_SHARE",
    "MIST_SIGMA0_M", "MIST_SIGMA_MAX", "PARTICLE_ATTRIBUTES", "PARTICLE_DTYPE", "PARTICLE_FORMAT",
    "REFLECTION_SHARE", "RELEASE_KMH", "SIDE_MM", "SPLASH_MIN_MM", "SPRAY_AIR_SHARE", "SPRAY_KMH", "SPRAY_MAX_MM",
    "SPRAY_UPDRAUGHT", "STANDING_WATER_MM", "SpawnStats", "SprayEffect", "SprayEmitter", "TREAD_MM",
    "TREAD_SPRAY_SHARE", "TYRE_PRESSURE_KPA", "WAKE_LIFT", "WAKE_LIFT_HEIGHT_M", "WAKE_SHARE", "WAKE_TAU_S",
    "WATER_IOR", "WaterBudget", "WheelGeometry", "WheelWater", "allocate_water", "allocate_water_unchecked",
    "body_hit_time", "body_hit_time_fast", "check_vehicles", "drag_time_constant", "extinction_area_m2",
    "flight_position", "flight_velocity", "fresnel_reflection", "gather_wheels", "glsl_probe", "ground_time",
    "henyey_greenstein", "hydroplaning_risk", "hydroplaning_risk_unchecked", "hydroplaning_speed_m_s",
    "line_of_sight_optical_depth", "parcel_state", "phase_function", "probe_program", "quadratic_drag_reference",
    "reflection_lobe", "release_fraction", "road_film_depth_fn", "shader_defines", "spray_share_of_tread",
    "time_to_height", "time_to_height_newton", "wheel_water",
]


def __getattr__(name: str):
    """The GL side (``SprayEffect``, ``glsl_probe``, ``probe_program``) is imported on first use, so the simulation
    modules import (and run) without moderngl."""
    if name == "SprayEffect":
        from rain_core.effects.spray.effect import SprayEffect

        return SprayEffect
    if name in ("glsl_probe", "probe_program"):
        from rain_core.effects.spray import probe

        return getattr(probe, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
