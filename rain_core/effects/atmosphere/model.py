"""The atmosphere model in NumPy (float64): extinction, visibility, rain-grey airlight, the phase function and the
state of one frame — the truth the shaders (``shaders/common/atmosphere.glsl``) are tested against. No GL.

Extinction
    β = β_clear + fog_scale·β_rain(R) + haze, with β_rain = 0.312·R^0.67 km⁻¹ (Weber et al. 2015;
    ``physics.rain_extinction_per_km``) and β_clear a clear day (3.912 / 40 km). The scene shader sees every
    surface through T = exp(−β·d) plus airlight A·(1 − T) (Koschmieder). That covers every view the scene shader
    draws: the puddle reflections are drawn by it from the mirrored camera, so their d is the whole reflected path;
    the windshield refracts a copy of this fogged frame. The contrast of a dark object against the horizon sky
    therefore falls as exp(−β·d): the meteorological optical range (5 % contrast, WMO) is V = −ln 0.05 / β ≈
    3.0 / β; the older 2 % threshold gives 3.912 / β.

Airlight
    A(v) = A_iso + (β_m / β)·E_sun·p(v·s): the isotropic part is the mean radiance of the surroundings — the
    horizon sky, greyed by the rain (``rain_overcast``), plus at night the lamp-lit street — and the sun's share
    is single scattering by the medium's part β_m of β (rain + haze; the analytic sky already holds the clear
    air) with a forward-peaked phase function p (two-term Henyey–Greenstein), so the sun side glows.

Sky
    The analytic sky is seen through the rain/haze layer (``LAYER_M`` thick) with β_m only: T = exp(−β_m·H / v_y),
    so the horizon goes to A(v) — far buildings fade into exactly the sky behind them, with no seam.

Rain-grey
    ``rain_overcast(R)`` = R / (R + 1.5 mm/h) in [0, 1): 0 in dry weather, 0.57 at 2 mm/h, 0.87 at 10 mm/h — a
    smooth transition, not a switch. The Scene passes it to ``lighting_for_hour(hour, overcast)`` (dimmer, greyer
    sun and sky; the exposure follows); ``sky_overcast`` applies the user's manual value or "auto". The effect
    also desaturates its airlight by the same amount, so the fog greys with the sky.

Near and far rain
    The rainfall effect draws the drops within its camera-following container (~30–50 m) as streaks; this model
    is all rain as a medium. Both read the same ``frame.weather.rate_mm_h``, so raising R thickens both at once.
    The fog starts at d = 0 (no cut at the container's edge, so there is no seam there); the price is that drops
    inside the container extinguish light twice, once as streaks and once as fog: β·r ≈ 6 % at 10 mm/h and 13 %
    at 50 mm/h for r = 40 m — under the 20 % spread between the published β(R) fits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from rain_core import checks, physics
from rain_core.physics import CLEAR_AIR_EXTINCTION_PER_M

LAYER_M = 1000.0  # m, thickness of the rain/haze layer the sky is seen through (keep = ATMOSPHERE_LAYER_M)
# Phase function of rain: two-term Henyey–Greenstein. The forward lobe (g = 0.7, geometric optics of mm drops
# without the diffraction spike) is what makes halos; the back lobe's weight is set so that p(180°) = 1/18.8 sr,
# the lidar ratio of liquid water drops (O'Connor et al. 2004) — it lets a driver see the rain in the own beams.
PHASE_G = 0.7
PHASE_BACK_G = -0.5
PHASE_BACK_WEIGHT = 0.0957
OVERCAST_HALF_RATE_MM_H = 1.5  # mm/h at which the sky is half-way to rain-grey
GLOW_SHARE = 0.5  # share of the scattered light that forms the visible halo at glow = 1
GLOW_SIGMA_MIN_RAD = math.radians(0.5)  # halo width in light rain …
GLOW_SIGMA_GROWTH_RAD = math.radians(3.0)  # … growing by up to this much as the medium thickens
GLOW_SIGMA_REF_M = 300.0  # m: the halo widens with the optical depth β_m·300 m
NIGHT_AIRLIGHT_CD_M2 = np.array([0.40, 0.36, 0.30])  # mean luminance of a lamp-lit street (4000 K LEDs)
CONTRAST_THRESHOLD = 0.05  # meteorological optical range (WMO)

_GREY = np.array([0.96, 0.99, 1.04])  # overcast grey is slightly cool
_LUMA = np.array([0.2126, 0.7152, 0.0722])


def rain_extinction_per_m(rate_mm_h):
    """Extinction of rain alone (1/m) at rate R (mm/h): 0.312·R^0.67 km⁻¹ (Weber et al. 2015)."""
    return np.asarray(physics.rain_extinction_per_km(rate_mm_h), dtype=np.float64) * 1e-3


def medium_extinction_per_m(rate_mm_h: float, fog_scale: float = 1.0, haze_per_km: float = 0.0) -> float:
    """β_m (1/m): the rain's extinction × fog_scale plus the haze (1/km) — everything except the clear air."""
    try:  # asked every frame (the atmosphere's ``active``, the lightning's medium) with the same three numbers
        return _medium_extinction_per_m(rate_mm_h, fog_scale, haze_per_km)
    except TypeError:  # an argument that is not hashable (an array): no cache
        return _medium_extinction(rate_mm_h, fog_scale, haze_per_km)


def _medium_extinction(rate_mm_h, fog_scale, haze_per_km) -> float:
    return float(fog_scale * rain_extinction_per_m(rate_mm_h) + haze_per_km * 1e-3)


_medium_extinction_per_m = lru_cache(maxsize=64)(_medium_extinction)


def extinction_per_m(rate_mm_h: float, fog_scale: float = 1.0, haze_per_km: float = 0.0) -> float:
    """Total β (1/m) at rain rate R (mm/h): clear air + fog_scale·β_rain(R) + haze (1/km)."""
    return CLEAR_AIR_EXTINCTION_PER_M + medium_extinction_per_m(rate_mm_h, fog_scale, haze_per_km)


def visibility_m(beta_per_m, contrast: float = CONTRAST_THRESHOLD):
    """Distance (m) at which a black object's contrast against the horizon falls to ``contrast``: −ln(c)/β."""
    return -math.log(contrast) / np.asarray(beta_per_m, dtype=np.float64)


def transmittance(beta_per_m, distance_m):
    """exp(−β·d): the share of a surface's light that reaches the eye across d metres."""
    return np.exp(-np.asarray(beta_per_m, dtype=np.float64) * np.asarray(distance_m, dtype=np.float64))


def rain_overcast(rate_mm_h) -> np.ndarray | float:
    """How rain-grey the sky is, in [0, 1), at rate R (mm/h): R / (R + 1.5). 0 when dry; smooth in R."""
    if type(rate_mm_h) is float and 0.0 <= rate_mm_h <= physics.R_MAX_MM_H:  # the scene's every-frame ask, no NumPy
        return rate_mm_h / (rate_mm_h + OVERCAST_HALF_RATE_MM_H)
    r = checks.array("rate_mm_h", rate_mm_h, 0.0, physics.R_MAX_MM_H, "mm/h")
    out = r / (r + OVERCAST_HALF_RATE_MM_H)
    return float(out) if out.ndim == 0 else out


def sky_overcast(section, rate_mm_h: float) -> float:
    """The overcast to pass to ``lighting_for_hour``: the user's ``sky_darkening`` if set, else
    ``rain_overcast(R)`` (R in mm/h); 0 with the atmosphere effect off and no manual value."""
    if section.sky_darkening is not None:
        return float(section.sky_darkening)
    return rain_overcast(rate_mm_h) if section.enabled else 0.0


def phase_hg(mu, g: float):
    """Henyey–Greenstein phase function (1/sr) at cos(scattering angle) ``mu``; integrates to 1 over the sphere."""
    mu = np.asarray(mu, dtype=np.float64)
    d = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) / (4.0 * math.pi * d * np.sqrt(d))


def phase_rain(mu):
    """The medium's phase function (1/sr): (1 − w)·HG(PHASE_G) + w·HG(PHASE_BACK_G), w = PHASE_BACK_WEIGHT."""
    return (1.0 - PHASE_BACK_WEIGHT) * phase_hg(mu, PHASE_G) + PHASE_BACK_WEIGHT * phase_hg(mu, PHASE_BACK_G)


def glow_sigma_rad(medium_per_m: float) -> float:
    """Angular standard deviation (rad) of the halo around lights for the medium's β_m (1/m)."""
    return GLOW_SIGMA_MIN_RAD + GLOW_SIGMA_GROWTH_RAD * (1.0 - math.exp(-medium_per_m * GLOW_SIGMA_REF_M))


@dataclass(frozen=True)
class AtmosphereState:
    """The atmosphere of one frame. β in 1/m, radiance in cd/m², illuminance in lux, directions unit vectors."""

    extinction_per_m: float  # total β (clear air + rain + haze)
    medium_per_m: float  # β_m, the rain + haze share
    airlight: np.ndarray  # isotropic airlight (cd/m², RGB)
    airlight_sun: np.ndarray  # (β_m/β)·E_sun (lux, RGB): weight of the phase function
    sun_direction: np.ndarray
    overcast: float
    glow_strength: float  # k: GLOW_SHARE × the user's glow
    glow_sigma_rad: float
    scatter_per_m: float  # σ_s of the light scattering pass, × the user's scale

    @property
    def visibility_m(self) -> float:
        return float(visibility_m(self.extinction_per_m))


def atmosphere_state(section, rate_mm_h: float, lighting, lamp_lit: bool = False) -> AtmosphereState:
    """The atmosphere for settings ``section`` (AtmosphereSection), rain rate R (mm/h) and ``lighting``
    (rain_core.lighting.Lighting). ``lamp_lit``: the street has lamps, which light the fog at night."""
    haze = section.haze_per_km if section.enabled else 0.0
    scale = section.fog_scale if section.enabled else 0.0
    beta_m = medium_extinction_per_m(rate_mm_h, scale, haze)
    beta = CLEAR_AIR_EXTINCTION_PER_M + beta_m
    overcast = sky_overcast(section, rate_mm_h)
    horizon = np.asarray(lighting.sky_horizon, dtype=np.float64)
    grey = float(horizon @ _LUMA) * _GREY
    airlight = horizon * (1.0 - overcast) + grey * overcast
    if lamp_lit:
        airlight = airlight + NIGHT_AIRLIGHT_CD_M2 * float(lighting.night_factor)
    sun = np.asarray(lighting.sun_illuminance, dtype=np.float64) * (beta_m / beta)
    return AtmosphereState(beta, beta_m, airlight, sun, np.asarray(lighting.sun_direction, dtype=np.float64),
                           overcast, GLOW_SHARE * section.glow if section.enabled else 0.0,
                           glow_sigma_rad(beta_m), beta_m * section.light_scattering if section.enabled else 0.0)


def airlight(state: AtmosphereState, view_dirs) -> np.ndarray:
    """Airlight (cd/m², RGB) seen along unit ``view_dirs`` (…, 3), eye outwards (twin of atmosphere_airlight)."""
    v = np.asarray(view_dirs, dtype=np.float64)
    p = phase_rain(v @ state.sun_direction)
    return state.airlight + state.airlight_sun * p[..., None]


def medium_uniforms(state: AtmosphereState) -> dict:
    """The common/atmosphere.glsl uniforms of the rain medium in ``state`` (beyond β and the isotropic
    airlight); in clear air the renderer's ``clear_air_uniforms`` zero the medium's terms instead."""
    return {"u_medium_extinction_per_m": state.medium_per_m,
            "u_airlight_sun": tuple(float(x) for x in state.airlight_sun),
            "u_airlight_sun_dir": tuple(float(x) for x in state.sun_direction),
            "u_phase_g": PHASE_G, "u_phase_back_g": PHASE_BACK_G, "u_phase_back_weight": PHASE_BACK_WEIGHT}


def atmosphere_uniforms(state: AtmosphereState) -> dict:
    """Every common/atmosphere.glsl uniform for ``state``: total β, the isotropic airlight and the medium."""
    return {"u_extinction_per_m": state.extinction_per_m,
            "u_airlight": tuple(float(x) for x in state.airlight), **medium_uniforms(state)}
