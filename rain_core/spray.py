"""Wheel splash and spray (DESIGN §3): every wheel throws the water it meets, by the Flintsch/Weir model.

The water model (float64 NumPy, the reference)
----------------------------------------------
Per wheel and frame: ground speed v (m/s), tyre width b (m) and the water film depth WFD under the contact
patch (the road's ``film_depth_mm``; a wet road without standing water still has a thin film). The water the
tyre meets per second is M_w = v·b·WFD·ρ_w (kg/s, Flintsch et al. 2012; ``physics.splash_water_flux``). It is
spent in order — like Weir et al. (1978) and Flintsch et al. — on

  ============  ===============================  =========================  ===========================
  mechanism     takes the film depth band (mm)    is thrown from (km/h)      goes
  ============  ===============================  =========================  ===========================
  capillary     0 … 0.1 (the film that clings     48 → 64 (ramp; below, it   spray (< 0.5 mm) off the
  adhesion      to the tread)                     drips back off the tyre)   rear and top of the tyre
  tread pickup  0.1 … 1.6 (the grooves' void)     15 → 30                    up and back off the tyre,
                                                                             splash; from 48 km/h an
                                                                             ever larger share (60 % at
                                                                             100 km/h) atomises to spray
  side waves    1.6 … 4.6 (squeezed out once      5 → 15                     splash (> 1 mm), low and
                the grooves are full)                                        sideways
  bow waves     everything deeper than 4.6        5 → 15                     splash, ahead of the tyre
  ============  ===============================  =========================  ===========================

until the water is exhausted. So the allocation always sums to M_w (:func:`allocate_water`); a mechanism
throws its share times its speed ramp, the rest stays on the road (``retained``). Above 64 km/h everything is
thrown and the thrown mass is exactly M_w: linear in v and in WFD. Measurable spray therefore starts at
48–64 km/h (the literature's range), splash from a puddle at walking pace.

Of the spray, ``MIST_SHARE`` of the mass is in drops small enough (~0.08 mm) to follow the air: the vehicle's
wake carries them as a mist trail (rooster tail) that hangs for seconds and hides the road for whoever follows.

Hydroplaning (:func:`hydroplaning_risk`): Horne's NASA formula puts the dynamic-hydroplaning speed of a tyre
at v_p = 6.36·√p km/h (p the inflation pressure in kPa), i.e. where the water wedge's dynamic pressure
½·ρ_w·v²·C_L (C_L ≈ 0.64) equals p. The share of the load the wedge carries is (v/v_p)²; grip starts to go at
half of it, and only where the film is deeper than the tread can drain (from 1 to 3 mm).

Flight (one closed form shared with the GPU: ``shaders/common/spray_flight.glsl``)
------------------------------------------------------------------------------
A droplet relaxes from its launch velocity v0 to the drift velocity u = wind − v_t(D)·ŷ (v_t from Gunn &
Kinzer) with a time constant τ:  x(t) = x0 + u·t + (v0 − u)·τ·(1 − e^(−t/τ)).  Real drops feel quadratic drag
(dv/dt = g − g·|v − w|(v − w)/v_t²); τ is chosen per drop so the distance it takes to slow from its launch
speed s0 = |v0 − u| to v_t matches quadratic drag: τ = v_t²·ln(s0/v_t) / (g·(s0 − v_t)) (→ v_t/g as s0 → v_t),
then stretched by up to 1.4 for fast launches (quadratic drag's long 1/t tail), a factor fitted so that
``python -m rain_core.bench spray`` finds the landing points within ~20 % of an RK4 quadratic-drag flight.

Each drop's fate is decided once, at spawn (the rainfall design): the time it meets the road (y = 0, or the
kerb-top beyond |x| = 7 m) or the thrower's body (a box with open wheel wells, moving with the vehicle) is its
lifetime; the shader draws it only while age < lifetime, so no drop ever passes below the road. Drops that land
in standing water are kept until they land, for the ripple solver (:meth:`SprayEmitter.landed_in_water`).

Particles
---------
What is drawn are *parcels*: each stands for many drops of one size thrown together, carries its mass (kg) and
so its extinction cross-section A = Q·(3/2)·m/(ρ_w·D) (Q = 2), and spreads as it flies. The number of parcels
alive is the budget; their masses add up to the mass the model throws (undone remainders carry over to the
next frame), so the picture does not depend on the budget except for its graininess. Two fixed ring buffers
(droplets, mist puffs) on the GPU receive only the newly spawned parcels each frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import moderngl
import numpy as np

from rain_core import layout, physics
from rain_core.gl import ColorView
from rain_core.renderer import Effect

# --- constants ----------------------------------------------------------------------------------------------

G = 9.81  # m/s²
RHO_W = physics.RHO_WATER  # kg/m³
KMH = 1.0 / 3.6  # m/s per km/h

MECHANISMS = ("capillary", "tread", "side", "bow")
# Film depth band each mechanism takes, in order (mm); bow waves take whatever is deeper.
CAPILLARY_MM = 0.1  # the film a wet tread carries round by adhesion
TREAD_MM = 1.5  # groove void per unit contact area: ~7 mm grooves × 0.25 void ratio, less what drains aside
SIDE_MM = 3.0  # what the tyre squeezes out sideways before a bow wave builds ahead of it
DEPTH_BANDS_MM = {"capillary": (0.0, CAPILLARY_MM), "tread": (CAPILLARY_MM, CAPILLARY_MM + TREAD_MM),
                  "side": (CAPILLARY_MM + TREAD_MM, CAPILLARY_MM + TREAD_MM + SIDE_MM),
                  "bow": (CAPILLARY_MM + TREAD_MM + SIDE_MM, math.inf)}
# Speed ramps (km/h): a mechanism throws none of its water below the first, all of it above the second.
RELEASE_KMH = {"capillary": (48.0, 64.0), "tread": (15.0, 30.0), "side": (5.0, 15.0), "bow": (5.0, 15.0)}
SPRAY_KMH = (48.0, 100.0)  # tread water atomises to spray over this ramp (jets break up finer with speed)
TREAD_SPRAY_SHARE = 0.6  # of the tread water, at full atomisation
MIST_SHARE = 0.05  # of the spray mass: drops < ~0.15 mm that the wake carries (drawn as mist puffs)
MIST_D_MM = 0.08  # mm, the mist's drop size (optics and settling speed)
EXTINCTION_EFFICIENCY = 2.0  # Q_ext of drops much larger than the wavelength
SPRAY_MAX_MM = 0.5  # spray drops are smaller than this
SPLASH_MIN_MM = 1.0  # splash drops larger than this

WET_FILM_MM = 0.2  # mm, film of a fully wet road without standing water (rain_core.road uses the same)
STANDING_WATER_MM = 2.0  # mm, deeper than the asphalt's macrotexture: a water surface that ripples

# Hydroplaning (Horne): v_p = HORNE_KMH_PER_SQRT_KPA·√p; tyre inflation per vehicle kind.
HORNE_KMH_PER_SQRT_KPA = 6.36
TYRE_PRESSURE_KPA = {"car": 230.0, "van": 400.0, "truck": 700.0}
HYDRO_LIFT_ONSET = 0.5  # share of the load on the water wedge where grip starts to go
HYDRO_DEPTH_MM = (1.0, 3.0)  # film depth over which the tread stops draining the contact patch

# Mist: the wake carries it forward at a share of the vehicle's speed, decaying with this time constant, and
# spreads it with an eddy diffusivity K = MIST_DIFFUSIVITY·|V|·height (m²/s).
WAKE_SHARE = (0.25, 0.45)
WAKE_TAU_S = 0.8
WAKE_LIFT = (0.02, 0.06)  # upward launch speed of the mist per unit speed, for a vehicle WAKE_LIFT_HEIGHT_M tall
WAKE_LIFT_HEIGHT_M = 2.0
MIST_DIFFUSIVITY = 0.01
MIST_LIFE_S = (2.5, 4.0)
MIST_SIGMA0_M = 0.25
SPRAY_AIR_SHARE = (0.1, 0.35)  # spray drops drift with this share of the vehicle's velocity (dragged air)
SPRAY_UPDRAUGHT = 0.6  # up to this share of their settling speed is held up by the wheel's wake
MIST_SIGMA_MAX = 0.5  # × the vehicle's height: a puff grows no taller than the wake that holds it

# Kinds of parcel (the shader's in_misc.x; +2 = fades out at the end of its life instead of hitting something).
KIND_DROPLET, KIND_MIST, KIND_FADE = 0, 1, 2
FATE_ROAD, FATE_BODY, FATE_AIR = 0, 1, 2

# Optics: half of the extinction is diffraction (a narrow forward lobe), the other half geometric: refraction
# (a forward Henyey–Greenstein lobe) and external reflection, F(i)/(4π) per unit geometric cross-section.
WATER_IOR = 1.333
G_DIFFRACTION = 0.95
G_REFRACTION = 0.8
GLINT_CHANCE = 0.03  # share of sparkle cells (about a pixel each) holding a glint; they carry 1/chance × the lobe

# Texture units (the briefing: 16–17 for the spray).
UNIT_DEPTH = 16

MAX_INTERVAL_S = 0.25  # s; a longer gap between frames emits only this much (no backlog bursts)
MIST_BUDGET_SHARE = 32  # mist ring = budget // this (at least MIN_MIST_CAPACITY): puffs are big and overlap
MIN_MIST_CAPACITY = 64

PARTICLE_DTYPE = np.dtype([
    ("p0", "<f4", 3), ("period", "<f4"),  # m (z relative to period·PERIOD_M); period index
    ("v0", "<f4", 3), ("tau", "<f4"),  # m/s launch velocity; s drag time constant (mist: spread rate)
    ("u", "<f4", 3), ("birth", "<f4"),  # m/s drift velocity; s since the effect's epoch
    ("life", "<f4"), ("sigma0", "<f4"), ("growth", "<f4"), ("area", "<f4"),  # s, m, m/s or m²/s, m²
    ("kind", "<f4"), ("d_mm", "<f4"), ("rand", "<f4"), ("glint", "<f4"),  # glint: mist puffs hold σ_max (m)
])
PARTICLE_FORMAT = "4f 4f 4f 4f 4f/i"
PARTICLE_ATTRIBUTES = ("in_p0", "in_v0", "in_u", "in_life", "in_misc")


# --- the water model ----------------------------------------------------------------------------------------

def _ramp(x, lo: float, hi: float) -> np.ndarray:
    return np.clip((np.asarray(x, dtype=np.float64) - lo) / (hi - lo), 0.0, 1.0)


def release_fraction(mechanism: str, speed_m_s) -> np.ndarray:
    """Share (0…1) of a mechanism's water that leaves the tyre at wheel speed |speed_m_s| (m/s)."""
    lo, hi = RELEASE_KMH[mechanism]
    return _ramp(np.abs(np.asarray(speed_m_s, dtype=np.float64)), lo * KMH, hi * KMH)


def spray_share_of_tread(speed_m_s) -> np.ndarray:
    """Share (0…1) of the thrown tread water that atomises to spray (< 0.5 mm) at |speed_m_s| (m/s)."""
    return TREAD_SPRAY_SHARE * _ramp(np.abs(np.asarray(speed_m_s, dtype=np.float64)), SPRAY_KMH[0] * KMH,
                                     SPRAY_KMH[1] * KMH)


@dataclass
class WaterBudget:
    """Where one wheel's water goes, kg/s (arrays broadcast over the inputs).

    available: M_w. allocated: (..., 4) per mechanism (MECHANISMS order), sums to available. thrown: (..., 4),
    ≤ allocated. retained: what stays on the road. spray / mist / splash: the thrown mass as drops < 0.5 mm
    (mist included in spray), ~0.08 mm mist alone, > 1 mm splash. buckets: (..., 6) the emitter's parcel
    classes (``BUCKETS``), summing to the thrown mass."""

    available: np.ndarray
    allocated: np.ndarray
    thrown: np.ndarray
    buckets: np.ndarray

    @property
    def retained(self) -> np.ndarray:
        return self.available - self.thrown.sum(axis=-1)

    @property
    def spray(self) -> np.ndarray:
        b = self.buckets
        return b[..., 0] + b[..., 1] + b[..., 5]

    @property
    def mist(self) -> np.ndarray:
        return self.buckets[..., 5]

    @property
    def splash(self) -> np.ndarray:
        b = self.buckets
        return b[..., 2] + b[..., 3] + b[..., 4]


BUCKETS = ("capillary_spray", "tread_spray", "tread_splash", "side_splash", "bow_splash", "mist")


def allocate_water(speed_m_s, tire_width_m, film_depth_m) -> WaterBudget:
    """Spend M_w = v·b·WFD·ρ_w (kg/s) on capillary adhesion, tread pickup, side and bow waves, in that order.

    speed_m_s: wheel ground speed (m/s; the sign, reversing, is ignored); tire_width_m: b (m); film_depth_m:
    WFD (m). Vectorised (inputs broadcast). See the module docstring for the bands and ramps."""
    v = np.abs(np.asarray(speed_m_s, dtype=np.float64))
    b = np.asarray(tire_width_m, dtype=np.float64)
    h = np.asarray(film_depth_m, dtype=np.float64)
    available = np.asarray(physics.splash_water_flux(v, b, h), dtype=np.float64)
    h_mm = h * 1e3
    shape = np.broadcast(v, b, h).shape
    allocated = np.zeros(shape + (4,))
    thrown = np.zeros(shape + (4,))
    flux_per_mm = v * b * RHO_W * 1e-3  # kg/s per mm of film
    for k, name in enumerate(MECHANISMS):
        lo, hi = DEPTH_BANDS_MM[name]
        allocated[..., k] = flux_per_mm * np.clip(h_mm - lo, 0.0, hi - lo)
        thrown[..., k] = allocated[..., k] * release_fraction(name, v)
    # The bands tile [0, ∞), so the allocation is M_w; rounding aside, make the sum exact.
    total = allocated.sum(axis=-1)
    scale = np.divide(available, total, out=np.ones_like(total), where=total > 0)
    allocated *= scale[..., None]
    thrown *= scale[..., None]
    tread_spray = thrown[..., 1] * spray_share_of_tread(v)
    buckets = np.stack([thrown[..., 0] * (1.0 - MIST_SHARE), tread_spray * (1.0 - MIST_SHARE),
                        thrown[..., 1] - tread_spray, thrown[..., 2], thrown[..., 3],
                        (thrown[..., 0] + tread_spray) * MIST_SHARE], axis=-1)
    return WaterBudget(available, allocated, thrown, buckets)


def hydroplaning_speed_m_s(tyre_pressure_kpa) -> np.ndarray:
    """Horne's dynamic hydroplaning speed (m/s) for an inflation pressure in kPa: 6.36·√p km/h."""
    return HORNE_KMH_PER_SQRT_KPA * np.sqrt(np.asarray(tyre_pressure_kpa, dtype=np.float64)) * KMH


def hydroplaning_risk(speed_m_s, film_depth_m, tyre_pressure_kpa=TYRE_PRESSURE_KPA["car"]) -> np.ndarray:
    """0 (full grip) … 1 (the tyre rides on water): the wedge's share of the load (v/v_p)² past
    HYDRO_LIFT_ONSET, times how far the film (m) exceeds what the tread drains (1 → 3 mm). Vectorised."""
    v = np.abs(np.asarray(speed_m_s, dtype=np.float64))
    lift = (v / hydroplaning_speed_m_s(tyre_pressure_kpa)) ** 2
    speed_part = np.clip((lift - HYDRO_LIFT_ONSET) / (1.0 - HYDRO_LIFT_ONSET), 0.0, 1.0)
    depth_part = _ramp(np.asarray(film_depth_m, dtype=np.float64) * 1e3, *HYDRO_DEPTH_MM)
    return speed_part * depth_part


# --- optics -------------------------------------------------------------------------------------------------

def henyey_greenstein(mu, g: float) -> np.ndarray:
    """Henyey–Greenstein phase function (1/sr) at mu = cos(scattering angle) (1 = straight on)."""
    mu = np.asarray(mu, dtype=np.float64)
    d = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))


def fresnel_reflection(cos_i, n: float = WATER_IOR) -> np.ndarray:
    """Unpolarised Fresnel reflectance of water seen from air at incidence cos_i."""
    ci = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    st2 = (1.0 - ci * ci) / (n * n)
    ct = np.sqrt(np.maximum(1.0 - st2, 0.0))
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return 0.5 * (rs * rs + rp * rp)


def reflection_lobe(mu) -> np.ndarray:
    """External reflection off a sphere, per unit geometric cross-section and steradian: F(i)/(4π), with the
    incidence i = (π − θ)/2 for scattering angle θ (mu = cos θ)."""
    cos_i = np.sqrt(np.clip((1.0 - np.asarray(mu, dtype=np.float64)) / 2.0, 0.0, 1.0))
    return fresnel_reflection(cos_i) / (4.0 * math.pi)


def _reflection_share() -> float:
    mu = np.linspace(-1.0, 1.0, 20001)
    f = reflection_lobe(mu)
    return float(2.0 * math.pi * np.sum((f[1:] + f[:-1]) / 2.0 * np.diff(mu)))


REFLECTION_SHARE = _reflection_share()  # ≈ 0.066: the reflected share of the geometric cross-section


def phase_function(mu, glint: float = 1.0) -> np.ndarray:
    """Phase function (1/sr, integrates to 1 over the sphere for glint = 1) of water drops ≫ λ, per unit
    extinction: ½ diffraction + ½ (refraction + reflection); ``glint`` scales the reflection lobe (sparkle)."""
    return 0.5 * henyey_greenstein(mu, G_DIFFRACTION) + 0.5 * (
        (1.0 - REFLECTION_SHARE) * henyey_greenstein(mu, G_REFRACTION) + glint * reflection_lobe(mu))


def extinction_area_m2(mass_kg, d_mm) -> np.ndarray:
    """Extinction cross-section (m²) of mass_kg of water in drops of diameter d_mm (mm): Q·(3/2)·m/(ρ_w·D)."""
    return EXTINCTION_EFFICIENCY * 1.5 * np.asarray(mass_kg, dtype=np.float64) / (
        RHO_W * np.asarray(d_mm, dtype=np.float64) * 1e-3)


# --- flight -------------------------------------------------------------------------------------------------

DRAG_TAIL_FIT = 1.4  # fitted: drops 0.2–5 mm launched at 5–30 m/s, 10–45° up (python -m rain_core.bench spray)


def drag_time_constant(d_mm, launch_speed_m_s) -> np.ndarray:
    """Time constant τ (s) of the linear-drag flight model for drops of d_mm (mm) launched at launch_speed_m_s
    (m/s) relative to their drift velocity: quadratic drag's distance from s0 down to v_t, v_t²·ln(s0/v_t) /
    (g·(s0 − v_t)), divided by (s0 − v_t) — stretched for fast launches by up to DRAG_TAIL_FIT."""
    vt = np.maximum(np.asarray(physics.terminal_velocity(np.asarray(d_mm, dtype=np.float64)), dtype=np.float64),
                    1e-3)
    s0 = np.asarray(launch_speed_m_s, dtype=np.float64)
    ratio = np.maximum(s0 / vt, 1.0)
    fast = ratio > 1.0 + 1e-6
    safe = np.where(fast, ratio, 2.0)
    tau_fast = vt * np.log(safe) / (G * (safe - 1.0))
    # Linear drag gives up the excess speed exponentially, quadratic drag like 1/t (a long tail): stretch τ
    # by up to DRAG_TAIL_FIT for fast launches (1 at terminal speed, so τ stays continuous there).
    stretch = 1.0 + (DRAG_TAIL_FIT - 1.0) * (1.0 - 1.0 / ratio**2)
    return np.where(fast, tau_fast * stretch, vt / G)


def _expm1_tau(t, tau):
    """τ·(1 − e^(−t/τ)), accurate for small t/τ."""
    return -tau * np.expm1(-t / tau)


def flight_position(p0, v0, u, tau, t) -> np.ndarray:
    """Position (m) at age t (s): x0 + u·t + (v0 − u)·τ·(1 − e^(−t/τ)). p0, v0, u (..., 3); tau, t (...)."""
    p0, v0, u = (np.asarray(a, dtype=np.float64) for a in (p0, v0, u))
    tau = np.asarray(tau, dtype=np.float64)[..., None]
    t = np.asarray(t, dtype=np.float64)[..., None]
    return p0 + u * t + (v0 - u) * _expm1_tau(t, tau)


def flight_velocity(v0, u, tau, t) -> np.ndarray:
    """Velocity (m/s) at age t (s): u + (v0 − u)·e^(−t/τ)."""
    v0, u = np.asarray(v0, dtype=np.float64), np.asarray(u, dtype=np.float64)
    decay = np.exp(-np.asarray(t, dtype=np.float64) / np.asarray(tau, dtype=np.float64))[..., None]
    return u + (v0 - u) * decay


def _height(y0, w0, uy, tau, t):
    return y0 + uy * t + (w0 - uy) * _expm1_tau(t, tau)


def time_to_height(y0, w0, uy, tau, level) -> np.ndarray:
    """First time (s) at which the height y0 + u_y·t + (w0 − u_y)·τ·(1 − e^(−t/τ)) comes down to ``level``
    (arrays, m and m/s; u_y < 0). 0 where the start is already at or below it. Bisection after the apex."""
    y0, w0, uy, tau, level = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in
                                                   (y0, w0, uy, tau, level)))
    uy = np.minimum(uy, -1e-6)
    # Apex: dy/dt = 0 at t* = τ·ln((w0 − u_y)/(−u_y)) when launched upwards; the height falls after it.
    apex = np.where(w0 > 0.0, tau * np.log(np.maximum((w0 - uy) / -uy, 1.0)), 0.0)
    lo = apex.copy()
    hi = apex + np.maximum(tau, 1e-3)
    for _ in range(60):
        above = _height(y0, w0, uy, tau, hi) > level
        if not above.any():
            break
        hi = np.where(above, hi * 2.0 + 0.01, hi)
    for _ in range(56):
        mid = 0.5 * (lo + hi)
        above = _height(y0, w0, uy, tau, mid) > level
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return np.where(y0 <= level, 0.0, lo)


def ground_time(p0, v0, u, tau) -> np.ndarray:
    """Age (s) at which a drop meets the ground: the road (y = 0), or the kerb-top (KERB_HEIGHT_M) where it is
    beyond the kerb (|x| ≥ ROAD_HALF_WIDTH_M). A drop crossing the kerb line below the kerb-top is stopped at
    the time it was last at kerb-top height (so it never passes below either surface)."""
    p0, v0, u = (np.asarray(a, dtype=np.float64) for a in (p0, v0, u))
    tau = np.asarray(tau, dtype=np.float64)
    t_road = time_to_height(p0[..., 1], v0[..., 1], u[..., 1], tau, 0.0)
    t_kerb = time_to_height(p0[..., 1], v0[..., 1], u[..., 1], tau, layout.KERB_HEIGHT_M)
    x_kerb = flight_position(p0, v0, u, tau, t_kerb)[..., 0]
    x_road = flight_position(p0, v0, u, tau, t_road)[..., 0]
    beyond_kerb = np.abs(x_kerb) >= layout.ROAD_HALF_WIDTH_M
    beyond_road = np.abs(x_road) >= layout.ROAD_HALF_WIDTH_M
    return np.where(beyond_kerb | beyond_road, t_kerb, t_road)


def quadratic_drag_reference(p0, v0, d_mm, wind=(0.0, 0.0, 0.0), dt_s: float = 2e-4, t_max_s: float = 10.0):
    """Float64 RK4 flight with quadratic drag, dv/dt = g − g·|v − w|(v − w)/v_t², until y = 0.

    p0, v0: (3,) m, m/s; d_mm: drop diameter (mm); wind (3,) m/s. Returns (landing point (3,) m, time s),
    the landing interpolated linearly inside the last step. The accuracy reference for the closed form."""
    vt = float(physics.terminal_velocity(d_mm))
    k = G / (vt * vt)
    w = np.asarray(wind, dtype=np.float64)
    gvec = np.array([0.0, -G, 0.0])

    def acc(v):
        rel = v - w
        return gvec - k * np.linalg.norm(rel) * rel

    x = np.asarray(p0, dtype=np.float64).copy()
    v = np.asarray(v0, dtype=np.float64).copy()
    t = 0.0
    while t < t_max_s:
        k1v, k1x = acc(v), v
        k2v, k2x = acc(v + 0.5 * dt_s * k1v), v + 0.5 * dt_s * k1v
        k3v, k3x = acc(v + 0.5 * dt_s * k2v), v + 0.5 * dt_s * k2v
        k4v, k4x = acc(v + dt_s * k3v), v + dt_s * k3v
        x1 = x + dt_s / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
        v1 = v + dt_s / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
        if x1[1] <= 0.0:
            a = x[1] / (x[1] - x1[1])
            return x + a * (x1 - x), t + a * dt_s
        x, v, t = x1, v1, t + dt_s
    return x, t


# --- vehicle bodies -----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class BodyBox:
    """A vehicle body for the spray's collision test, local frame (forward −Z, right +X, up +Y), m: the box
    |x| < half_width, floor_y < y < height, |z| < half_length, with open wheel wells around the axles at
    z = ±half_wheelbase (|Δz| < well_half_length, y < well_top, |x| > well_inner_x)."""

    half_width: float
    half_length: float
    floor_y: float
    height: float
    half_wheelbase: float
    well_half_length: float
    well_top: float
    well_inner_x: float

    @staticmethod
    def of(spec) -> BodyBox:
        r = spec.wheel_radius_m
        floor = 0.5 * r if spec.kind == "car" else r  # ground clearance: cars low, vans and lorries high
        return BodyBox(spec.width_m / 2.0, spec.length_m / 2.0, floor, spec.height_m, spec.wheelbase_m / 2.0,
                       r + 0.1, 2.0 * r + 0.05, spec.track_m / 2.0 - spec.tire_width_m / 2.0 - 0.05)

    def contains(self, local) -> np.ndarray:
        """Whether local points (..., 3) m lie inside the body (wheel wells excluded)."""
        x, y, z = np.abs(local[..., 0]), local[..., 1], local[..., 2]
        box = (x < self.half_width) & (y > self.floor_y) & (y < self.height) & (np.abs(z) < self.half_length)
        in_well_z = np.abs(np.abs(z) - self.half_wheelbase) < self.well_half_length
        well = in_well_z & (y < self.well_top) & (x > self.well_inner_x)
        return box & ~well


def body_hit_time(p0, v0, u, tau, t_max, body_origin, body_velocity, right, forward, boxes: list[BodyBox],
                  box_index, samples: int = 20, refine: int = 12) -> np.ndarray:
    """First age (s, ≤ t_max) at which each drop is inside its thrower's body, else t_max.

    The body moves at body_velocity (m/s) from body_origin (m, the vehicle's ground point at the drop's birth)
    without turning (right/forward: its unit axes). Per drop: p0, v0, u (n, 3), tau, t_max (n,),
    body_origin, body_velocity, right, forward (n, 3); box_index (n,) into ``boxes``. The flight is sampled
    at ``samples`` ages (denser early) and the first entry refined by bisection; the returned age is the last
    one found outside, so the drop is drawn only up to the body's surface."""
    n = len(tau)
    if n == 0:
        return np.zeros(0)
    frac = (np.arange(1, samples + 1) / samples) ** 2
    ts = t_max[:, None] * frac[None, :]  # (n, S)

    def inside(t):  # t (n, k) → (n, k) bool
        pos = flight_position(p0[:, None, :], v0[:, None, :], u[:, None, :], tau[:, None], t)
        rel = pos - (body_origin[:, None, :] + body_velocity[:, None, :] * t[..., None])
        local = np.stack([np.einsum("nkc,nc->nk", rel, right), rel[..., 1],
                          -np.einsum("nkc,nc->nk", rel, forward)], axis=-1)
        out = np.zeros(t.shape, dtype=bool)
        for i, box in enumerate(boxes):
            sel = box_index == i
            if sel.any():
                out[sel] = box.contains(local[sel])
        return out

    hit = inside(ts)
    any_hit = hit.any(axis=1)
    result = np.asarray(t_max, dtype=np.float64).copy()
    if not any_hit.any():
        return result
    first = np.argmax(hit, axis=1)
    rows = np.nonzero(any_hit)[0]
    hi = ts[rows, first[rows]]
    lo = np.where(first[rows] > 0, ts[rows, np.maximum(first[rows] - 1, 0)], 0.0)
    sub = (p0[rows], v0[rows], u[rows], tau[rows], body_origin[rows], body_velocity[rows], right[rows],
           forward[rows], box_index[rows])

    def inside_rows(t):
        pos = flight_position(sub[0], sub[1], sub[2], sub[3], t)
        rel = pos - (sub[4] + sub[5] * t[:, None])
        local = np.stack([np.einsum("nc,nc->n", rel, sub[6]), rel[:, 1], -np.einsum("nc,nc->n", rel, sub[7])],
                         axis=-1)
        out = np.zeros(len(t), dtype=bool)
        for i, box in enumerate(boxes):
            sel = sub[8] == i
            if sel.any():
                out[sel] = box.contains(local[sel])
        return out

    for _ in range(refine):
        mid = 0.5 * (lo + hi)
        ins = inside_rows(mid)
        hi = np.where(ins, mid, hi)
        lo = np.where(ins, lo, mid)
    result[rows] = lo
    return result


# --- wheels -------------------------------------------------------------------------------------------------

def road_film_depth_fn(frame):
    """The film depth (mm) under points x, z (m) for this frame: the road's ``film_depth_mm`` (standing water
    in cracks and puddles from the weather's flood levels and settings.road's puddle map, and the wet film
    of the weather's wetness, none under roofs). Without the road module: the wet film alone (WET_FILM_MM at
    wetness 1) on the asphalt. Returns a callable (x, z) → mm."""
    weather = getattr(frame, "weather", None)
    wetness = float(getattr(weather, "wetness", 0.0) or 0.0)
    cracks = float(getattr(weather, "cracks", 0.0) or 0.0)
    puddles = float(getattr(weather, "puddles", 0.0) or 0.0)
    road_settings = getattr(getattr(frame, "settings", None), "road", None)
    amount = float(getattr(road_settings, "puddle_amount", 0.5))
    seed = int(getattr(road_settings, "puddle_seed", 0))
    world = getattr(frame, "world", None)
    road_fn = _road_film_function()

    def depth(x, z):
        x, z = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64))
        if road_fn is not None:
            return np.asarray(road_fn(x, z, cracks, puddles, puddle_amount=amount, seed=seed, world=world,
                                      wetness=wetness), dtype=np.float64)
        return np.where(np.abs(x) <= layout.ROAD_HALF_WIDTH_M, WET_FILM_MM * wetness, 0.0)

    return depth


def _road_film_function():
    """rain_core.road.film_depth_mm(x, z, cracks, puddles, puddle_amount, seed, world, wetness) → mm, if the
    road module is there (it is the one model of the film the road draws), else None."""
    try:
        from rain_core.road import film_depth_mm
    except ImportError:
        return None
    return film_depth_mm


@dataclass
class WheelWater:
    """One vehicle's four wheels this frame (FL, FR, RL, RR). contacts (4, 3) m; speed_m_s (4,) signed;
    width_m (4,) m of tread meeting the water (a lorry's twin rear tyres count twice); film_depth_mm (4,);
    budget: WaterBudget over the 4 wheels (kg/s); hydroplaning_risk (4,) in [0, 1]."""

    vehicle: object
    contacts: np.ndarray
    speed_m_s: np.ndarray
    width_m: np.ndarray
    film_depth_mm: np.ndarray
    budget: WaterBudget
    hydroplaning_risk: np.ndarray


def wheel_water(vehicle, depth_fn) -> WheelWater:
    """The water model at a vehicle's wheels; depth_fn(x, z) → film depth (mm) at world points (m)."""
    contacts = np.asarray(vehicle.wheel_contacts(), dtype=np.float64)
    speeds = np.asarray(vehicle.wheel_speeds(), dtype=np.float64)
    widths = np.asarray(vehicle.wheel_widths(), dtype=np.float64).copy()
    if getattr(vehicle.spec, "kind", "car") == "truck":
        widths[2:] *= 2.0  # a lorry's rear axle runs twin tyres
    depth_mm = np.maximum(np.asarray(depth_fn(contacts[:, 0], contacts[:, 2]), dtype=np.float64), 0.0)
    budget = allocate_water(speeds, widths, depth_mm * 1e-3)
    pressure = TYRE_PRESSURE_KPA.get(getattr(vehicle.spec, "kind", "car"), TYRE_PRESSURE_KPA["car"])
    risk = hydroplaning_risk(speeds, depth_mm * 1e-3, pressure)
    return WheelWater(vehicle, contacts, speeds, widths, depth_mm, budget, risk)


# --- the emitter (CPU side, no GL) --------------------------------------------------------------------------

@dataclass
class _Ring:
    """A fixed ring of parcels (GPU layout) with their birth/death times (float64, effect clock)."""

    capacity: int
    data: np.ndarray = field(init=False)
    death: np.ndarray = field(init=False)
    birth: np.ndarray = field(init=False)
    head: int = 0

    def __post_init__(self):
        self.data = np.zeros(self.capacity, PARTICLE_DTYPE)
        self.data["life"] = -1.0  # never drawn
        self.death = np.full(self.capacity, -np.inf)
        self.birth = np.full(self.capacity, np.inf)

    def push(self, records: np.ndarray, birth: np.ndarray, death: np.ndarray) -> list[tuple[int, int]]:
        """Write the newest records over the oldest; returns the (start, count) slot ranges written."""
        n = len(records)
        if n == 0 or self.capacity == 0:
            return []
        if n > self.capacity:
            records, birth, death = records[-self.capacity:], birth[-self.capacity:], death[-self.capacity:]
            n = self.capacity
        ranges = []
        start, done = self.head, 0
        while done < n:
            count = min(n - done, self.capacity - start)
            self.data[start:start + count] = records[done:done + count]
            self.birth[start:start + count] = birth[done:done + count]
            self.death[start:start + count] = death[done:done + count]
            ranges.append((start, count))
            done += count
            start = (start + count) % self.capacity
        self.head = start
        return ranges

    def alive(self, now: float) -> int:
        return int(np.count_nonzero((self.birth <= now) & (self.death > now)))

    def last_death(self) -> float:
        return float(self.death.max()) if self.capacity else -math.inf


@dataclass
class SpawnStats:
    """Totals since the emitter started (kg, counts) and of the last frame."""

    thrown_kg: float = 0.0  # ∫ thrown mass dt (after strength), what the parcels must carry
    emitted_kg: float = 0.0  # Σ parcel masses spawned
    available_kg: float = 0.0  # ∫ M_w dt
    parcels: int = 0
    mist_puffs: int = 0
    fates: np.ndarray = field(default_factory=lambda: np.zeros(3))  # kg by fate: road, body, air
    last_parcels: int = 0
    last_mist: int = 0


class SprayEmitter:
    """Turns the wheels' water into parcels in two rings (droplets, mist) — all the CPU side of the effect.

    seed: the generator for every random choice (same seed + same frames → the same parcels). budget: droplet
    parcels alive at most (the mist ring gets budget // 8). film_depth_fn(x, z) → mm overrides the road's film
    (tests use analytic fields); then the weather's wetness film is still added on the asphalt.
    """

    def __init__(self, seed: int = 0, budget: int = 12_000, film_depth_fn=None):
        self.rng = np.random.default_rng(seed)
        self.film_depth_fn = film_depth_fn
        self.strength = 1.0
        self.epoch: float | None = None
        self._last_time: float | None = None
        self._acc: dict[int, np.ndarray] = {}  # id(vehicle) → (4, 6) kg not yet emitted
        self._life_q90 = [1.0, MIST_LIFE_S[1]]  # s, running 90th percentile of parcel lives per ring
        self._pending = np.zeros((0, 4))  # landings still in flight: (time, x, z, momentum)
        self._landed = np.zeros((0, 3))
        self.wheels: list[WheelWater] = []
        self._wheels_time: float | None = None
        self.stats = SpawnStats()
        self.set_budget(budget)

    # --- configuration ------------------------------------------------------------------------------------
    def set_budget(self, budget: int) -> None:
        """Resize the rings (clears them) when the budget (droplet parcels) changes."""
        budget = int(budget)
        if getattr(self, "budget", None) == budget:
            return
        self.budget = budget
        mist = max(MIN_MIST_CAPACITY, budget // MIST_BUDGET_SHARE) if budget > 0 else 0
        self.rings = [_Ring(budget), _Ring(mist)]
        self.dirty: list[list[tuple[int, int]]] = [[(0, budget)] if budget else [], [(0, mist)] if mist else []]

    def clear(self) -> None:
        """Forget every parcel in flight (the effect was switched off)."""
        budget, self.budget = self.budget, -1
        self.set_budget(budget)
        self._pending = np.zeros((0, 4))
        self._last_time = None

    # --- per frame ----------------------------------------------------------------------------------------
    def depth_function(self, frame):
        """(x, z) → film depth in mm for this frame (the override, plus the wet film, or the road's)."""
        if self.film_depth_fn is None:
            return road_film_depth_fn(frame)
        wetness = float(getattr(getattr(frame, "weather", None), "wetness", 0.0) or 0.0)
        fn = self.film_depth_fn

        def depth(x, z):
            x, z = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(z, np.float64))
            film = np.where(np.abs(x) <= layout.ROAD_HALF_WIDTH_M, WET_FILM_MM * wetness, 0.0)
            return np.maximum(np.asarray(fn(x, z), dtype=np.float64), film)

        return depth

    def observe(self, frame) -> list[WheelWater]:
        """Evaluate the water model at every vehicle's wheels (cached per frame time)."""
        if self._wheels_time != frame.time_s or len(self.wheels) != len(frame.vehicles):
            fn = self.depth_function(frame)
            self.wheels = [wheel_water(v, fn) for v in frame.vehicles]
            self._wheels_time = frame.time_s
        return self.wheels

    def throwing(self) -> bool:
        """Whether any wheel of the last observed frame throws water."""
        return any(float(w.budget.thrown.sum()) > 0.0 for w in self.wheels)

    def alive_until(self) -> float:
        """Effect-clock time (s since epoch) when the last parcel in flight dies."""
        return max((r.last_death() for r in self.rings), default=-math.inf)

    def clock(self, time_s: float) -> float:
        """Frame time (s) → the effect clock (s since the first frame), what the shader's u_clock holds."""
        return time_s - (self.epoch if self.epoch is not None else time_s)

    def alive_counts(self, time_s: float) -> tuple[int, int]:
        now = self.clock(time_s)
        return self.rings[0].alive(now), self.rings[1].alive(now)

    def landed_in_water(self) -> list[tuple[float, float, float]]:
        """Parcels that landed in standing water (film ≥ STANDING_WATER_MM) during the last emitted frame:
        (x m, z m world, downward momentum kg·m/s), for the ripple solver's impulses."""
        return [(float(x), float(z), float(p)) for x, z, p in self._landed]

    def emit(self, frame) -> None:
        """Spawn the parcels thrown since the last call (at most MAX_INTERVAL_S of them) into the rings."""
        t = float(frame.time_s)
        if self.epoch is None:
            self.epoch = t
        if self._last_time is None or t < self._last_time:
            self._last_time = t
        elapsed = min(t - self._last_time, MAX_INTERVAL_S)
        self._last_time = t
        now = self.clock(t)
        self._landed = np.zeros((0, 3))
        wheels = self.observe(frame)
        live_ids = {id(w.vehicle) for w in wheels}
        self._acc = {k: a for k, a in self._acc.items() if k in live_ids}
        self.stats.last_parcels = self.stats.last_mist = 0
        if elapsed > 0.0 and self.budget > 0 and wheels:
            self._spawn(frame, wheels, elapsed, now)
        self._pop_landings(now)

    def _pop_landings(self, now: float) -> None:
        if len(self._pending):
            done = self._pending[:, 0] <= now
            self._landed = np.concatenate([self._landed, self._pending[done, 1:]])
            self._pending = self._pending[~done]

    # --- spawning -----------------------------------------------------------------------------------------
    def _spawn(self, frame, wheels: list[WheelWater], elapsed: float, now: float) -> None:
        rng = self.rng
        rates = np.stack([w.budget.buckets for w in wheels]) * self.strength  # (V, 4, 6) kg/s
        self.stats.available_kg += float(sum(w.budget.available.sum() for w in wheels)) * elapsed
        self.stats.thrown_kg += float(rates.sum()) * elapsed
        acc = np.stack([self._acc.get(id(w.vehicle), np.zeros((4, len(BUCKETS)))) for w in wheels])
        acc = acc + rates * elapsed
        counts = np.zeros(acc.shape, dtype=np.int64)
        for ring, buckets in ((0, slice(0, 5)), (1, slice(5, 6))):
            mass = acc[..., buckets]
            total = float(mass.sum())
            if total <= 0.0 or self.rings[ring].capacity == 0:
                continue
            rate = self.rings[ring].capacity / max(self._life_q90[ring], 0.05)  # parcels per second
            expected = rate * elapsed * mass / total
            whole = np.floor(expected)
            counts[..., buckets] = (whole + (rng.random(expected.shape) < expected - whole)).astype(np.int64)
        emitted = counts > 0
        parcel_mass = np.where(emitted, acc / np.maximum(counts, 1), 0.0)
        acc = np.where(emitted, 0.0, acc)
        for w, a in zip(wheels, acc, strict=True):
            self._acc[id(w.vehicle)] = a
        if not emitted.any():
            return
        # One row per parcel: which vehicle, wheel and bucket, and its mass.
        vi, wi, bi = np.nonzero(counts)
        reps = counts[vi, wi, bi]
        vi, wi, bi = np.repeat(vi, reps), np.repeat(wi, reps), np.repeat(bi, reps)
        mass = parcel_mass[vi, wi, bi]
        self.stats.emitted_kg += float(mass.sum())
        geo = _WheelGeometry(wheels)
        age_now = elapsed * rng.random(len(vi))  # how long before now each parcel left the tyre
        birth = now - age_now
        mist = bi == 5
        for ring, sel in ((0, ~mist), (1, mist)):
            if sel.any():
                self._spawn_ring(frame, ring, geo, vi[sel], wi[sel], bi[sel], mass[sel], birth[sel],
                                 age_now[sel], now)

    def _spawn_ring(self, frame, ring: int, geo, vi, wi, bi, mass, birth, age_now, now) -> None:
        rng = self.rng
        n = len(vi)
        w = vi * 4 + wi  # flat wheel index
        wind = np.asarray(getattr(getattr(getattr(frame, "weather", None), "wind", None), "velocity_m_s",
                                  (0.0, 0.0, 0.0)), dtype=np.float64)
        launch = _launch_mist if ring == 1 else _launch_droplets
        p0, v0, d_mm, sigma0, growth_k, air, updraught = launch(rng, geo, w, bi, age_now)
        sigma_max = MIST_SIGMA_MAX * geo.height[vi]
        vt = np.asarray(physics.terminal_velocity(d_mm), dtype=np.float64)
        u = wind + air
        u[:, 1] -= vt * (1.0 - updraught)
        if ring == 1:
            tau = np.full(n, WAKE_TAU_S)
        else:
            tau = drag_time_constant(d_mm, np.linalg.norm(v0 - u, axis=1))
        t_ground = ground_time(p0, v0, u, tau)
        fate = np.full(n, FATE_ROAD)
        if ring == 0:
            veh_origin = geo.position[vi] - geo.velocity[vi] * age_now[:, None]
            t_body = body_hit_time(p0, v0, u, tau, t_ground, veh_origin, geo.velocity[vi], geo.right[vi],
                                   geo.forward[vi], geo.boxes, geo.box_index[vi])
            fate = np.where(t_body < t_ground, FATE_BODY, FATE_ROAD)
            life = np.minimum(t_body, t_ground)
            growth = growth_k * np.linalg.norm(v0 - u, axis=1)
        else:
            cap = rng.uniform(*MIST_LIFE_S, n)
            fate = np.where(cap < t_ground, FATE_AIR, FATE_ROAD)
            life = np.minimum(cap, t_ground)
            growth = growth_k
        # Drawn up to 1 ms before the surface so float32 never shows it past the road or the body.
        life = np.maximum(life - 1e-3, 0.0)
        q90 = float(np.quantile(life, 0.9))
        self._life_q90[ring] = 0.9 * self._life_q90[ring] + 0.1 * max(q90, 0.05)
        # The ring is refilled every q90 seconds (that is how the emission rate was set): a parcel living longer
        # would be overwritten in flight, so it fades out at that age instead.
        horizon = max(self._life_q90[ring], 0.05)
        cut = life > horizon
        fate = np.where(cut, FATE_AIR, fate)
        life = np.minimum(life, horizon)
        for f in range(3):
            self.stats.fates[f] += float(mass[fate == f].sum())
        # Landings in standing water, for the ripples.
        road = fate == FATE_ROAD
        if road.any() and ring == 0:
            land_p = flight_position(p0[road], v0[road], u[road], tau[road], life[road])
            depth = np.asarray(self._depth_fn_cache(frame)(land_p[:, 0], land_p[:, 2]), dtype=np.float64)
            wet = depth >= STANDING_WATER_MM
            if wet.any():
                vel = flight_velocity(v0[road][wet], u[road][wet], tau[road][wet], life[road][wet])
                momentum = mass[road][wet] * np.maximum(-vel[:, 1], 0.0)
                rows = np.column_stack([birth[road][wet] + life[road][wet], land_p[wet][:, 0], land_p[wet][:, 2],
                                        momentum])
                self._pending = np.concatenate([self._pending, rows])
        area = extinction_area_m2(mass, d_mm)
        keep = birth + life > now  # parcels that already died within this frame are not drawn
        rec = np.zeros(int(keep.sum()), PARTICLE_DTYPE)
        if len(rec):
            period = np.floor(p0[keep, 2] / layout.PERIOD_M)
            p = p0[keep].copy()
            p[:, 2] -= period * layout.PERIOD_M
            rec["p0"], rec["period"] = p, period
            rec["v0"], rec["tau"] = v0[keep], tau[keep]
            rec["u"], rec["birth"] = u[keep], birth[keep]
            rec["life"], rec["sigma0"], rec["growth"], rec["area"] = life[keep], sigma0[keep], growth[keep], \
                area[keep]
            kind = np.full(len(rec), KIND_MIST if ring == 1 else KIND_DROPLET, np.float32)
            kind += np.where(fate[keep] == FATE_AIR, KIND_FADE, 0)
            rec["kind"], rec["d_mm"] = kind, d_mm[keep]
            rec["rand"] = rng.random(len(rec))
            splash = d_mm[keep] >= SPLASH_MIN_MM
            rec["glint"] = sigma_max[keep] if ring == 1 else np.where(splash, 1.0, 0.5)
            ranges = self.rings[ring].push(rec, birth[keep], (birth + life)[keep])
            self.dirty[ring].extend(ranges)
        if ring == 0:
            self.stats.parcels += n
            self.stats.last_parcels += n
        else:
            self.stats.mist_puffs += n
            self.stats.last_mist += n

    def _depth_fn_cache(self, frame):
        key = (frame.time_s, id(frame))
        if getattr(self, "_depth_key", None) != key:
            self._depth_key = key
            self._depth_fn = self.depth_function(frame)
        return self._depth_fn

    def take_dirty(self) -> list[list[tuple[int, int]]]:
        """The slot ranges written since the last call, per ring (the GPU upload list)."""
        dirty, self.dirty = self.dirty, [[], []]
        return dirty


def parcel_state(records: np.ndarray, clock_s: float, shift_periods: float = 0.0):
    """Centres (n, 3) m (world z, or wrapped when ``shift_periods`` is the renderer's shift_z/PERIOD_M),
    horizontal and vertical Gaussian sizes σ_h, σ_v (n,) m and an alive mask of ring records at the effect
    clock ``clock_s`` (s), computed as spray.vert does (float64)."""
    rec = records
    age = clock_s - rec["birth"].astype(np.float64)
    alive = (age >= 0.0) & (age < rec["life"])
    age = np.where(alive, age, 0.0)
    tau = np.where(alive, rec["tau"], 1.0).astype(np.float64)  # slots never written hold τ = 0
    pos = flight_position(rec["p0"], rec["v0"], rec["u"], tau, age)
    pos[:, 2] += (rec["period"] - shift_periods) * layout.PERIOD_M
    mist = (np.mod(rec["kind"], 2.0) > 0.5)
    sigma = np.where(mist, rec["sigma0"] + np.sqrt(rec["growth"] * age),
                     rec["sigma0"] + rec["growth"] * _expm1_tau(age, tau) + 0.02 * age)
    sigma_v = np.where(mist, np.minimum(sigma, rec["glint"]), sigma)
    return pos, sigma, sigma_v, alive


def line_of_sight_optical_depth(emitter: SprayEmitter, time_s: float, eye, target) -> float:
    """Optical depth of the spray along the segment eye → target (world m) at frame time ``time_s``: the sum
    over parcels between the two points of A/(2π·σ_h·σ_v)·exp(−d_h²/(2σ_h²) − d_v²/(2σ_v²)), d_h and d_v the
    horizontal and vertical parts of the parcel's distance from the line: the line integral of a Gaussian puff
    along a near-horizontal ray. exp(−τ) is the share of the target's light that gets through — the
    visibility loss of whoever follows."""
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    axis = target - eye
    length = float(np.linalg.norm(axis))
    axis /= max(length, 1e-9)
    total = 0.0
    for ring in emitter.rings:
        if ring.capacity == 0:
            continue
        pos, sigma_h, sigma_v, alive = parcel_state(ring.data, emitter.clock(time_s))
        rel = pos - eye
        along = rel @ axis
        keep = alive & (along > 0.0) & (along < length)
        perp = rel[keep] - along[keep, None] * axis
        dv2 = perp[:, 1] ** 2
        dh2 = np.sum(perp**2, axis=1) - dv2
        sh, sv = sigma_h[keep], sigma_v[keep]
        total += float(np.sum(ring.data["area"][keep] / (2.0 * math.pi * sh * sv)
                              * np.exp(-0.5 * (dh2 / sh**2 + dv2 / sv**2))))
    return total


class _WheelGeometry:
    """Per-vehicle and per-wheel arrays gathered for vectorised launches."""

    def __init__(self, wheels: list[WheelWater]):
        vehicles = [w.vehicle for w in wheels]
        self.position = np.array([v.position for v in vehicles], dtype=np.float64)
        self.velocity = np.array([v.velocity() for v in vehicles], dtype=np.float64)
        self.forward = np.array([v.forward() for v in vehicles], dtype=np.float64)
        self.right = np.array([v.right() for v in vehicles], dtype=np.float64)
        self.height = np.array([v.spec.height_m for v in vehicles])
        self.half_length = np.array([v.spec.length_m / 2.0 for v in vehicles])
        specs = []
        self.box_index = np.zeros(len(vehicles), dtype=np.int64)
        for i, v in enumerate(vehicles):
            if v.spec not in specs:
                specs.append(v.spec)
            self.box_index[i] = specs.index(v.spec)
        self.boxes = [BodyBox.of(s) for s in specs]
        self.contacts = np.concatenate([w.contacts for w in wheels])  # (W, 3)
        self.speed = np.abs(np.concatenate([w.speed_m_s for w in wheels]))
        sign = np.concatenate([np.where(w.speed_m_s < 0, -1.0, 1.0) for w in wheels])
        self.travel = np.repeat(self.forward, 4, axis=0) * sign[:, None]  # direction the wheel rolls
        self.outward = np.repeat(self.right, 4, axis=0) * np.tile([-1.0, 1.0, -1.0, 1.0], len(wheels))[:, None]
        self.radius = np.repeat([v.spec.wheel_radius_m for v in vehicles], 4)
        self.width = np.concatenate([w.width_m for w in wheels])
        self.wheel_velocity = np.repeat(self.velocity, 4, axis=0)


_UP = np.array([0.0, 1.0, 0.0])


def _lognormal(rng, median: float, sigma: float, lo: float, hi: float, n: int) -> np.ndarray:
    return np.clip(median * np.exp(sigma * rng.standard_normal(n)), lo, hi)


# Per droplet bucket: drop diameter (median mm, log-σ, min, max), parcel start size (m), spread per m/s.
# Side and bow waves leave as sheets that break into large drops, so they carry the largest sizes.
_DROPLET_SIZES = {0: (0.25, 0.35, 0.1, SPRAY_MAX_MM), 1: (0.25, 0.35, 0.1, SPRAY_MAX_MM),
                  2: (1.5, 0.3, SPLASH_MIN_MM, 3.0), 3: (3.0, 0.35, 1.5, 5.0), 4: (3.0, 0.35, 1.5, 5.0)}
# A spray parcel is a small cloud; a splash parcel a few large drops. Each parcel stands for many drops that
# leave the tyre spread over several centimetres; at 2–3 cm the parcels drew as separate white "bricks" smeared
# over the exposure, at 5–8 cm they merge into a cloud. The optical depth is the parcel's extinction area over
# its footprint, so the size does not change how much the spray hides.
_DROPLET_SIGMA0_M = {0: 0.075, 1: 0.075, 2: 0.05, 3: 0.06, 4: 0.06}
# Growth of the parcel (m) per metre it travels relative to the air: the spread of its drops' speeds.
_DROPLET_SPREAD = {0: 0.05, 1: 0.05, 2: 0.04, 3: 0.04, 4: 0.04}


def _launch_droplets(rng, geo: _WheelGeometry, w, bucket, age_now):
    """Start points (m), ground velocities (m/s), drop sizes (mm), parcel sizes (m) and spread rates of the
    droplet parcels leaving wheels ``w`` (flat index) from buckets 0–4 (see ``BUCKETS``)."""
    n = len(w)
    c = geo.contacts[w] - geo.wheel_velocity[w] * age_now[:, None]  # where the contact patch was at birth
    f, o = geo.travel[w], geo.outward[w]
    back = -f
    r, b, v = geo.radius[w], geo.width[w], geo.speed[w]
    vel = geo.wheel_velocity[w]
    centre = c + _UP * r[:, None]
    p0 = np.zeros((n, 3))
    v0 = np.zeros((n, 3))
    d_mm = np.zeros(n)
    sigma0 = np.zeros(n)
    across = (rng.random(n) - 0.5) * b  # where on the tread width
    air = np.zeros((n, 3))  # m/s, air velocity the parcel drifts with (besides the wind)
    updraught = np.zeros(n)  # share of the settling speed the wheel's wake holds up
    for k in range(5):
        sel = bucket == k
        m = int(sel.sum())
        if m == 0:
            continue
        d_mm[sel] = _lognormal(rng, *_DROPLET_SIZES[k], m)
        sigma0[sel] = _DROPLET_SIGMA0_M[k] * rng.uniform(0.8, 1.25, m)
        vs, rs = v[sel][:, None], r[sel][:, None]
        fs, os_, bs = f[sel], o[sel], back[sel]
        if k in (0, 1):
            # Spray: the film flung off the tyre (capillary water off its rear and top, the atomised share of
            # the groove water lower down) breaks into drops too small to keep their launch speed (τ ~ 10 ms):
            # they are caught by the air the wheel and body drag along, and leave the wheel well with it.
            lo, hi = (0.8, 1.8) if k == 0 else (0.2, 1.0)
            p0[sel] = (c[sel] + bs * (rs * rng.uniform(1.0, 1.3, (m, 1))) + _UP * (rs * rng.uniform(lo, hi, (m, 1)))
                       + os_ * (b[sel, None] * rng.uniform(0.4, 1.0, (m, 1))))  # pumped out past the tread
            share = rng.uniform(*SPRAY_AIR_SHARE, (m, 1))
            v0[sel] = vel[sel] * share + vs * (_UP * rng.uniform(0.0, 0.05, (m, 1))
                                               + os_ * rng.uniform(0.0, 0.08, (m, 1)))
            air[sel] = vel[sel] * share  # the dragged air keeps carrying them until they settle
            updraught[sel] = rng.uniform(0.0, SPRAY_UPDRAUGHT, m)
        elif k == 2:
            # Tread pickup: off the tyre at angle α from the bottom towards the rear, at up to the tread's speed
            # relative to the car (v), i.e. up and back; with some sideways spread off the groove edges.
            alpha = np.radians(5.0 + 45.0 * rng.random(m) ** 1.6)[:, None]
            speed = vs * rng.uniform(0.6, 1.0, (m, 1))
            rel = speed * (np.cos(alpha) * bs + np.sin(alpha) * _UP)
            lateral = vs * rng.normal(0.1, 0.12, (m, 1))
            p0[sel] = centre[sel] + rs * (np.sin(alpha) * bs - np.cos(alpha) * _UP) + os_ * across[sel, None]
            v0[sel] = vel[sel] + rel + os_ * lateral
        elif k == 3:
            # Side waves: squeezed out at the front edges of the contact patch, low and sideways.
            p0[sel] = c[sel] + fs * (0.3 * rs) + os_ * (b[sel, None] / 2.0) + _UP * 0.005
            # Most of the water goes low (the sheet's base), little to its top edge.
            v0[sel] = vs * (fs * rng.uniform(0.2, 0.5, (m, 1)) + os_ * rng.uniform(0.3, 0.7, (m, 1))
                            + _UP * (0.04 + 0.3 * rng.random((m, 1)) ** 2))
        else:
            # Bow waves: pushed ahead of the tyre, thrown forward and aside.
            p0[sel] = c[sel] + fs * (0.9 * rs) + os_ * across[sel, None] + _UP * 0.01
            v0[sel] = vs * (fs * rng.uniform(0.8, 1.15, (m, 1)) + os_ * rng.uniform(-0.1, 0.5, (m, 1))
                            + _UP * (0.08 + 0.35 * rng.random((m, 1)) ** 2))
    growth = np.array([_DROPLET_SPREAD[k] for k in range(5)])[bucket]
    return p0, v0, d_mm, sigma0, growth, air, updraught


def _launch_mist(rng, geo: _WheelGeometry, w, bucket, age_now):
    """Mist puffs: released behind the wheel into the wake, which carries them forward at a share of the
    vehicle's speed; spread rate 2K (m²/s) from the wake's eddy diffusivity."""
    n = len(w)
    vi = w // 4
    c = geo.contacts[w] - geo.wheel_velocity[w] * age_now[:, None]
    f, o = geo.travel[w], geo.outward[w]
    r, v = geo.radius[w][:, None], geo.speed[w][:, None]
    vel = geo.wheel_velocity[w]
    # The fine spray of every wheel is drawn into the wake: puffs start just behind the body, in line with the
    # wheel (the air beside the body streams along it; behind it, it recirculates).
    axle_to_tail = geo.half_length[vi] - np.einsum("nc,nc->n", c - geo.position[vi], -geo.forward[vi])
    behind = np.maximum(axle_to_tail, 0.0)[:, None] + rng.uniform(0.0, 0.8, (n, 1))
    p0 = (c - f * behind + _UP * (r * rng.uniform(0.4, 1.4, (n, 1)))
          + o * rng.uniform(-0.2, 0.2, (n, 1)))
    # The wake's recirculation lifts the mist to about the vehicle's height: upward speed ∝ v·height.
    lift = v * rng.uniform(*WAKE_LIFT, (n, 1)) * (geo.height[vi] / WAKE_LIFT_HEIGHT_M)[:, None]
    v0 = vel * rng.uniform(*WAKE_SHARE, (n, 1)) + _UP * lift + o * (v * rng.uniform(0.0, 0.06, (n, 1)))
    d_mm = np.full(n, MIST_D_MM)
    sigma0 = MIST_SIGMA0_M * rng.uniform(0.8, 1.3, n)
    diffusivity = MIST_DIFFUSIVITY * np.linalg.norm(geo.velocity[vi], axis=1) * geo.height[vi]
    return p0, v0, d_mm, sigma0, 2.0 * diffusivity, np.zeros((n, 3)), np.zeros(n)


# --- the effect (GL) ----------------------------------------------------------------------------------------

def shader_defines() -> dict[str, str]:
    """The model constants the shaders share with this module (one source of truth)."""
    return {"SPRAY_G_DIFFRACTION": repr(G_DIFFRACTION), "SPRAY_G_REFRACTION": repr(G_REFRACTION),
            "SPRAY_REFLECTION_SHARE": repr(REFLECTION_SHARE), "SPRAY_WATER_IOR": repr(WATER_IOR),
            "SPRAY_GLINT_CHANCE": repr(GLINT_CHANCE), "SPRAY_PERIOD_M": repr(float(layout.PERIOD_M))}


def probe_program(shaders):
    """The transform-feedback probe of the GLSL twin (shaders/spray_probe.vert): inputs in_p0 (xyz m),
    in_v0 (xyz m/s, w τ s), in_u (xyz m/s, w age s), in_mu; outputs out_pos, out_vel, out_phase."""
    return shaders.program("spray/probe.vert", varyings=("out_pos", "out_vel", "out_phase"),
                           defines=shader_defines())


def glsl_probe(ctx: moderngl.Context, shaders, p0, v0, tau, u, age, mu):
    """Evaluate the GLSL twin for n parcels: (positions (n, 3) m, velocities (n, 3) m/s, phase (n,) 1/sr) at
    ages ``age`` (s) and scattering cosines ``mu``, computed in float32 on the GPU."""
    prog = probe_program(shaders)
    n = len(age)
    data = np.zeros((n, 13), np.float32)
    data[:, 0:3], data[:, 4:7], data[:, 7] = p0, v0, tau
    data[:, 8:11], data[:, 11], data[:, 12] = u, age, mu
    vbo = ctx.buffer(data.tobytes())
    out = ctx.buffer(reserve=n * 7 * 4)
    fbo = ctx.simple_framebuffer((1, 1))  # a draw needs a complete framebuffer even with rasteriser discard
    fbo.use()
    vao = ctx.vertex_array(prog, [(vbo, "4f 4f 4f 1f", "in_p0", "in_v0", "in_u", "in_mu")])
    vao.transform(out, mode=moderngl.POINTS, vertices=n)
    res = np.frombuffer(out.read(), np.float32).reshape(n, 7).astype(np.float64)
    for obj in (vao, vbo, out, fbo):
        obj.release()
    return res[:, :3], res[:, 3:6], res[:, 6]


def _set(program, name: str, value) -> None:
    if name in program:
        program[name].value = value


class Spray(Effect):
    """Wheel splash and spray for every vehicle (module docstring), drawn in the ``transparent`` stage.

    ``Spray(ctx, shaders=None, settings=None, seed=0, film_depth_fn=None)``: settings are read per frame from
    ``frame.settings.spray`` (enabled, strength, budget) and ``camera.exposure_s`` (streak length);
    film_depth_fn(x, z) → mm replaces the road's film (the weather's wet film is still added).

    After each frame: ``wheels`` (WheelWater per vehicle, ego first), :meth:`hydroplaning_risk`,
    :meth:`landed_in_water` (for the ripples), ``emitter.stats``. The HDR depth is read on texture unit 16.
    """

    name = "spray"
    stages = ("transparent",)

    def __init__(self, ctx: moderngl.Context, shaders=None, settings=None, seed: int = 0, film_depth_fn=None):
        self.ctx = ctx
        self._shaders = shaders
        budget = settings.spray.budget if settings is not None else 12_000
        self.emitter = SprayEmitter(seed=seed, budget=budget, film_depth_fn=film_depth_fn)
        self._buffers: list[moderngl.Buffer | None] = [None, None]
        self._vaos: list[moderngl.VertexArray | None] = [None, None]
        self._capacity = [-1, -1]
        self._program = None
        self._color_fbo = ColorView(ctx)  # the HDR colour without its depth (the pass samples that depth)
        self._depth_sampler = ctx.sampler(compare_func="", filter=(moderngl.NEAREST, moderngl.NEAREST),
                                          repeat_x=False, repeat_y=False)
        self._frame = None

    # --- queries for the app and the lead -----------------------------------------------------------------
    @property
    def wheels(self) -> list[WheelWater]:
        return self.emitter.wheels

    def hydroplaning_risk(self, vehicle=None) -> np.ndarray:
        """(4,) risk per wheel (0…1) of ``vehicle`` (default: the first, the ego) in the last frame."""
        for w in self.emitter.wheels:
            if vehicle is None or w.vehicle is vehicle:
                return w.hydroplaning_risk.copy()
        return np.zeros(4)

    @property
    def ego_hydroplaning_risk(self) -> float:
        """Largest per-wheel risk of the ego car in the last frame (0…1), for the panel's indicator."""
        return float(self.hydroplaning_risk().max())

    def landed_in_water(self) -> list[tuple[float, float, float]]:
        """(x m, z m, downward momentum kg·m/s) of the parcels that landed in standing water this frame."""
        return self.emitter.landed_in_water()

    # --- Effect -------------------------------------------------------------------------------------------
    @staticmethod
    def _section(frame):
        from rain_core.settings import SpraySection

        settings = getattr(frame, "settings", None)
        return settings.spray if settings is not None else SpraySection()

    def active(self, frame) -> bool:
        """Runs while wheels throw water or parcels are still in flight (and the effect is on with a budget).
        The water model (and so the hydroplaning risk) is evaluated every frame regardless."""
        sec = self._section(frame)
        self.emitter.observe(frame)
        if not (sec.enabled and sec.budget > 0 and sec.strength > 0.0):
            if self.emitter.alive_until() > -math.inf:
                self.emitter.clear()
            self.emitter._last_time = None
            return False
        return self.emitter.throwing() or self.emitter.alive_until() > self.emitter.clock(frame.time_s)

    def update(self, frame, rc) -> None:
        sec = self._section(frame)
        self.emitter.set_budget(sec.budget)
        self.emitter.strength = sec.strength
        self.emitter.emit(frame)
        self._upload()
        self._frame = frame
        # Where the spray lands in standing water, the ripple effect (if running) presses dents.
        rc.resources["droplet_impacts"] = self.landed_in_water()

    def _upload(self) -> None:
        dirty = self.emitter.take_dirty()
        for ring in range(2):
            data = self.emitter.rings[ring].data
            cap = self.emitter.rings[ring].capacity
            if self._capacity[ring] != cap:
                for obj in (self._vaos[ring], self._buffers[ring]):
                    if obj is not None:
                        obj.release()
                self._vaos[ring] = self._buffers[ring] = None
                if cap:
                    self._buffers[ring] = self.ctx.buffer(data.tobytes())
                self._capacity[ring] = cap
                continue
            buf = self._buffers[ring]
            for start, count in dirty[ring]:
                buf.write(data[start:start + count].tobytes(), offset=start * PARTICLE_DTYPE.itemsize)

    def _prog(self, rc) -> moderngl.Program:
        if self._program is None:
            lib = self._shaders or rc.shaders
            self._program = lib.program("spray/spray.vert", "spray/spray.frag", defines=shader_defines())
        return self._program

    def _vao(self, ring: int, prog) -> moderngl.VertexArray | None:
        if self._vaos[ring] is None and self._buffers[ring] is not None:
            self._vaos[ring] = self.ctx.vertex_array(
                prog, [(self._buffers[ring], PARTICLE_FORMAT, *PARTICLE_ATTRIBUTES)])
        return self._vaos[ring]

    def _hdr_color_fbo(self, rc) -> moderngl.Framebuffer:
        # The pass reads the scene's depth, so it writes through a framebuffer without that depth attached.
        return self._color_fbo.fbo(rc.hdr.color)

    def render(self, stage: str, rc) -> None:
        if stage != "transparent":
            return
        frame = rc.frame
        now = self.emitter.clock(frame.time_s)
        if self.emitter.alive_until() <= now:
            return
        ctx = self.ctx
        prog = self._prog(rc)
        rc.set_frame_uniforms(prog)
        camera = frame.camera
        right, up, fwd = camera.basis()
        cam_vel = np.asarray(frame.ego.velocity(), dtype=np.float64) if frame.ego is not None else np.zeros(3)
        exposure_s = float(getattr(getattr(frame.settings, "camera", None), "exposure_s", 0.02))
        values = {
            "u_clock": float(now), "u_shift_periods": float(round(rc.shift_z / layout.PERIOD_M)),
            "u_camera_vel": tuple(float(x) for x in cam_vel), "u_exposure_s": exposure_s,
            "u_cam_forward": tuple(float(x) for x in fwd), "u_depth": UNIT_DEPTH,
            "u_viewport": (float(rc.size[0]), float(rc.size[1])),
            "u_near": float(camera.near_m), "u_far": float(camera.far_m),
            "u_pixel_angle": 2.0 * math.tan(math.radians(camera.fov_y_deg) / 2.0) / rc.size[1],
        }
        for key, value in values.items():
            _set(prog, key, value)
        self._depth_sampler.use(UNIT_DEPTH)
        rc.hdr.depth.use(UNIT_DEPTH)
        self._hdr_color_fbo(rc).use()
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA, moderngl.ZERO, moderngl.ONE)
        for ring in (1, 0):  # mist behind, droplets over it (no sorting: both are soft and mostly thin)
            vao = self._vao(ring, prog)
            if vao is not None and self.emitter.rings[ring].last_death() > now:
                vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=self.emitter.rings[ring].capacity)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)  # as the scene pass left it
        self._depth_sampler.clear(UNIT_DEPTH)
        rc.hdr.fbo.use()

    def release(self) -> None:
        for obj in (*self._vaos, *self._buffers):
            if obj is not None:
                obj.release()
        self._vaos = [None, None]
        self._buffers = [None, None]
        self._capacity = [-1, -1]
        self._color_fbo.release()
        self._depth_sampler.release()


def make_spray(ctx: moderngl.Context, settings=None) -> Spray:
    """The spray effect for ``Scene``'s effect list (settings are read per frame)."""
    return Spray(ctx, settings=settings)
