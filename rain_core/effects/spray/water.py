"""The Flintsch/Weir water budget of one tyre, and Horne's hydroplaning risk (float64 NumPy, the reference).

Per wheel and frame: ground speed v (m/s), tyre width b (m) and the water film depth WFD under the contact
patch (``rain_core.water_film.film_depth_mm``; a wet road without standing water still has a thin film). The
water the tyre meets per second is M_w = v·b·WFD·ρ_w (kg/s, Flintsch et al. 2012; ``physics.splash_water_flux``).
It is spent in order — like Weir et al. (1978) and Flintsch et al. — on

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import checks, physics

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
SPRAY_MAX_MM = 0.5  # spray drops are smaller than this
SPLASH_MIN_MM = 1.0  # splash drops larger than this

STANDING_WATER_MM = 2.0  # mm, deeper than the asphalt's macrotexture: a water surface that ripples

# Hydroplaning (Horne): v_p = HORNE_KMH_PER_SQRT_KPA·√p; tyre inflation per vehicle kind.
HORNE_KMH_PER_SQRT_KPA = 6.36
TYRE_PRESSURE_KPA = {"car": 230.0, "van": 400.0, "truck": 700.0}
HYDRO_LIFT_ONSET = 0.5  # share of the load on the water wedge where grip starts to go
HYDRO_DEPTH_MM = (1.0, 3.0)  # film depth over which the tread stops draining the contact patch


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
    WFD (m). Vectorised (inputs broadcast). See the module docstring for the bands and ramps. The inputs are
    checked (``physics.splash_water_flux``: ValueError naming the argument); the emitter, which checks its
    own inputs once per frame, calls :func:`allocate_water_unchecked`."""
    v = np.abs(np.asarray(speed_m_s, dtype=np.float64))
    b = np.asarray(tire_width_m, dtype=np.float64)
    h = np.asarray(film_depth_m, dtype=np.float64)
    available = np.asarray(physics.splash_water_flux(v, b, h), dtype=np.float64)
    return allocate_water_unchecked(v, b, h, available)


_BAND_LO_MM = np.array([DEPTH_BANDS_MM[m][0] for m in MECHANISMS])
_BAND_MM = np.array([DEPTH_BANDS_MM[m][1] - DEPTH_BANDS_MM[m][0] for m in MECHANISMS])
_RAMP_LO = np.array([RELEASE_KMH[m][0] for m in MECHANISMS]) * KMH
_RAMP_SPAN = np.array([RELEASE_KMH[m][1] - RELEASE_KMH[m][0] for m in MECHANISMS]) * KMH
_SPRAY_LO, _SPRAY_SPAN = SPRAY_KMH[0] * KMH, SPRAY_KMH[1] * KMH - SPRAY_KMH[0] * KMH  # _ramp's lo and hi − lo


def allocate_water_unchecked(speed_m_s, tire_width_m, film_depth_m, available=None) -> WaterBudget:
    """:func:`allocate_water` for inputs already known finite and in range (no checks: the per-frame path), all
    four mechanisms in one pass. ``available``: M_w if already computed (kg/s), else v·b·WFD·ρ_w here."""
    v = np.abs(np.asarray(speed_m_s, dtype=np.float64))
    b = np.asarray(tire_width_m, dtype=np.float64)
    h = np.asarray(film_depth_m, dtype=np.float64)
    flux_per_mm = v * b * (physics.RHO_WATER * 1e-3)  # kg/s per mm of film
    h_mm = h * 1e3
    if available is None:
        available = flux_per_mm * h_mm  # M_w = v·b·WFD·ρ_w
    if not flux_per_mm.shape == h_mm.shape == v.shape:  # (the emitter's arrays are all (W,) already)
        flux_per_mm, h_mm, v = np.broadcast_arrays(flux_per_mm, h_mm, v)
    # Each mechanism takes its band of the depth, and throws the share its speed ramp releases.
    allocated = flux_per_mm[..., None] * np.minimum(np.maximum(h_mm[..., None] - _BAND_LO_MM, 0.0), _BAND_MM)
    release = np.minimum(np.maximum((v[..., None] - _RAMP_LO) / _RAMP_SPAN, 0.0), 1.0)
    thrown = allocated * release
    # The bands tile [0, ∞), so the allocation is M_w; rounding aside, make the sum exact.
    total = allocated.sum(axis=-1)
    scale = np.divide(available, total, out=np.ones_like(total), where=total > 0)
    allocated *= scale[..., None]
    thrown *= scale[..., None]
    # spray_share_of_tread(v) (v ≥ 0 here) with np.clip's values from two ufuncs.
    share = TREAD_SPRAY_SHARE * np.minimum(np.maximum((v - _SPRAY_LO) / _SPRAY_SPAN, 0.0), 1.0)
    tread_spray = thrown[..., 1] * share
    buckets = np.empty(thrown.shape[:-1] + (6,))
    np.multiply(thrown[..., 0], 1.0 - MIST_SHARE, out=buckets[..., 0])
    np.multiply(tread_spray, 1.0 - MIST_SHARE, out=buckets[..., 1])
    np.subtract(thrown[..., 1], tread_spray, out=buckets[..., 2])
    buckets[..., 3:5] = thrown[..., 2:4]
    np.multiply(thrown[..., 0] + tread_spray, MIST_SHARE, out=buckets[..., 5])
    return WaterBudget(np.asarray(available, dtype=np.float64), allocated, thrown, buckets)


def hydroplaning_speed_m_s(tyre_pressure_kpa) -> np.ndarray:
    """Horne's dynamic hydroplaning speed (m/s) for an inflation pressure in kPa: 6.36·√p km/h."""
    return HORNE_KMH_PER_SQRT_KPA * np.sqrt(np.asarray(tyre_pressure_kpa, dtype=np.float64)) * KMH


def hydroplaning_risk(speed_m_s, film_depth_m, tyre_pressure_kpa=TYRE_PRESSURE_KPA["car"]) -> np.ndarray:
    """0 (full grip) … 1 (the tyre rides on water): the wedge's share of the load (v/v_p)² past
    HYDRO_LIFT_ONSET, times how far the film (m) exceeds what the tread drains (1 → 3 mm). Vectorised.

    speed_m_s finite (m/s, either sign), film_depth_m finite ≥ 0 (m), tyre_pressure_kpa finite > 0 (kPa);
    anything else is a ValueError naming the argument."""
    v = checks.array("speed_m_s", speed_m_s, -math.inf, math.inf, "m/s")
    h = checks.array("film_depth_m", film_depth_m, 0.0, math.inf, "m")
    p = checks.array("tyre_pressure_kpa", tyre_pressure_kpa, 0.0, math.inf, "kPa", lo_open=True)
    return hydroplaning_risk_unchecked(v, h, p)


def hydroplaning_risk_unchecked(speed_m_s, film_depth_m, tyre_pressure_kpa, planing_speed_m_s=None) -> np.ndarray:
    """:func:`hydroplaning_risk` without the argument checks (the emitter's per-frame path; its inputs are
    checked once at the frame's boundary). ``planing_speed_m_s``: ``hydroplaning_speed_m_s(tyre_pressure_kpa)``
    (m/s) if the caller keeps it (the pressures of a fleet do not change)."""
    v = np.abs(np.asarray(speed_m_s, dtype=np.float64))
    if planing_speed_m_s is None:
        planing_speed_m_s = hydroplaning_speed_m_s(tyre_pressure_kpa)
    lift = (v / planing_speed_m_s) ** 2
    # np.clip's (and _ramp's) values from two ufuncs, without the wrapper.
    speed_part = np.minimum(np.maximum((lift - HYDRO_LIFT_ONSET) / (1.0 - HYDRO_LIFT_ONSET), 0.0), 1.0)
    lo, hi = HYDRO_DEPTH_MM
    depth_mm = np.asarray(film_depth_m, dtype=np.float64) * 1e3
    depth_part = np.minimum(np.maximum((depth_mm - lo) / (hi - lo), 0.0), 1.0)
    return speed_part * depth_part
