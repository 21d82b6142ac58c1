"""Kerb streams: rainwater that runs off the crowned road into the gutter along each kerb and down the street's
grade to the drain inlets (NumPy float64; the GLSL twin is ``road_gutter_depth_mm`` in shaders/road/film.glsl).

The road's water model (``water_film``) adds the gutter's water to the standing water, so the road draws it,
the spray throws more water near the kerb and the drips and rain ring it like any water.

Gutter flow by the FHWA's HEC-22 (Urban Drainage Design Manual, 3rd ed., 2009, eq. 4-2), Manning's equation
integrated over a triangular gutter section:

    Q = (K_u / n) · S_x^(5/3) · S_L^(1/2) · T^(8/3)        (SI: K_u = 0.376; Q m³/s, T the spread in m)

with the flow the rational method gives for the strip draining to this kerb (HEC-22 eq. 3-1):
Q = C · i · W · L, i the rain intensity (m/s), W the width draining to the kerb (the half road, the kerb and the
sidewalk), L the distance from the last inlet upstream. Hence the spread T = k · L^(3/8),

    k = (C · i · W · n / (K_u · S_x^(5/3) · S_L^(1/2)))^(3/8),

one number per frame (``spread_coefficient``), and the depth at distance s from the kerb face is S_x·(T − s),
deepest at the kerb. The spread grows from each inlet to the next (``INLET_SPACING_M``, 50 m: the streets are
periodic in 1200 m) and resets at the inlet. The road is drawn flat; the drainage sees a 0.5 % grade falling
towards −z (HEC-22 recommends at least 0.3 %) and a 2 % crown cross slope.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import layout

KU_SI = 0.376  # HEC-22 eq. 4-2 in SI units
MANNING_N = 0.016  # asphalt pavement, rough texture (HEC-22 table 4-1: 0.013–0.016)
CROSS_SLOPE = 0.02  # m/m, the crown's slope towards each kerb
GRADE = 0.005  # m/m, the street's fall towards −z as the drainage sees it
RUNOFF_C = 0.9  # rational-method runoff coefficient of asphalt and concrete (0.7–0.95)
DRAINED_WIDTH_M = layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M  # to each kerb
INLET_SPACING_M = 50.0  # m between drain inlets along each kerb (divides the 1200 m period)
INLET_OFFSET_M = (0.0, 25.0)  # m, where the inlets of the +x and −x kerbs sit along z
GUTTER_MAX_MM = 40.0  # mm, above this the water would top the kerb (150 mm) long before: a cap for safety


def spread_coefficient(rate_mm_h: float, wetness: float = 1.0) -> float:
    """k (m^(5/8)) in T = k·L^(3/8) for rain at rate_mm_h (mm/h) on a road whose runoff has built up to the
    share ``wetness`` (the weather's film level, 0…1: the road first wets, then runs off)."""
    i = max(float(rate_mm_h), 0.0) / 3.6e6 * min(max(float(wetness), 0.0), 1.0)
    if i <= 0.0:
        return 0.0
    conveyance = KU_SI / MANNING_N * CROSS_SLOPE ** (5.0 / 3.0) * math.sqrt(GRADE)
    return (RUNOFF_C * i * DRAINED_WIDTH_M / conveyance) ** 0.375


def gutter_flow_m3_s(spread_m, cross_slope: float = CROSS_SLOPE, grade: float = GRADE, n: float = MANNING_N):
    """HEC-22 eq. 4-2: the flow (m³/s) of a triangular gutter with spread T (m)."""
    t = np.asarray(spread_m, dtype=np.float64)
    return KU_SI / n * cross_slope ** (5.0 / 3.0) * math.sqrt(grade) * t ** (8.0 / 3.0)


def gutter_speed_m_s(spread_m, cross_slope: float = CROSS_SLOPE, grade: float = GRADE, n: float = MANNING_N):
    """Mean flow speed (m/s) in a triangular gutter of spread T (m): Manning's V = (0.752/n)·S_L^½·S_x^⅔·T^⅔
    (HEC-22 eq. 4-5, SI), which is Q / (S_x·T²/2) of eq. 4-2. The road shader drifts the stream's surface with it."""
    t = np.asarray(spread_m, dtype=np.float64)
    return 0.752 / n * math.sqrt(grade) * cross_slope ** (2.0 / 3.0) * t ** (2.0 / 3.0)


def upstream_length_m(x_m, z_m):
    """Distance (m) along the kerb from the inlet upstream (the flow runs towards −z, into the next inlet)."""
    x = np.asarray(x_m, dtype=np.float64)
    z = np.asarray(z_m, dtype=np.float64)
    offset = np.where(x >= 0.0, INLET_OFFSET_M[0], INLET_OFFSET_M[1])
    return INLET_SPACING_M - np.mod(z - offset, INLET_SPACING_M)


def gutter_depth_mm(x_m, z_m, k: float):
    """Gutter water depth (mm) at road points x, z (m; any world z) for spread coefficient k: S_x·(T − s), s the
    distance from the kerb face, T = k·L^(3/8); 0 beyond the spread and off the asphalt."""
    x = np.asarray(x_m, dtype=np.float64)
    if k <= 0.0:
        return np.zeros(np.broadcast(x, np.asarray(z_m)).shape)
    spread = k * upstream_length_m(x, z_m) ** 0.375
    s = layout.ROAD_HALF_WIDTH_M - np.abs(x)
    depth = CROSS_SLOPE * np.maximum(spread - s, 0.0) * 1000.0
    return np.where(s >= 0.0, np.minimum(depth, GUTTER_MAX_MM), 0.0)


def frame_spread_coefficient(frame) -> float:
    """k for a frame: its rain rate and the weather's film level, 0 with ``settings.road.kerb_streams`` off (or no
    weather). What the road draws, the spray reads and the labels mark all come from here."""
    weather = getattr(frame, "weather", None)
    road = getattr(getattr(frame, "settings", None), "road", None)
    if weather is None or (road is not None and not road.kerb_streams):
        return 0.0
    return spread_coefficient(float(getattr(weather, "rate_mm_h", 0.0)), float(getattr(weather, "wetness", 0.0)))
