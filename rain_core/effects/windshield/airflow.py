"""The air over the glass and the drag it puts on a drop.

The air over the glass is the car's relative wind: the headwind turns to run up the glass, slow near the cowl
(stagnation) and faster towards the roof, spreading outwards towards the A-pillars; a crosswind adds a sideways
flow. A drop's top sits inside a laminar boundary layer (Pohlhausen profile, δ = 5·√(ν·x/U)); the drag on the
cap is ½·ρ_air·C_d·A·|u|·u with A the cap's frontal area and u the air at its top minus the drop's own velocity.
Since that drag grows faster with size than the drop's weight, large drops start to climb first
(``airflow_onset_speed_m_s``).
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import (
    BL_RUN_UP_M,
    CROSSWIND_GAIN,
    DRAG_CD,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    FRONTAL_PER_RADIUS2,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    NU_AIR,
    drop_mass,
    norm2,
)
from rain_core.effects.windshield.glass import GlassGeometry
from rain_core.physics import RHO_AIR
from rain_core.vehicles import CAR_SPEC, VehicleSpec


def air_velocity(glass: GlassGeometry, st: np.ndarray, air_local: np.ndarray) -> np.ndarray:
    """Air velocity just outside the boundary layer over the glass, (n, 2) m/s in (s, t), for the air velocity
    ``air_local`` (3,) m/s relative to the car in its local frame (+z a headwind)."""
    head, cross = float(air_local[2]), float(air_local[0])
    t = st[:, 1]
    frac = np.clip(t / glass.height, 0.0, 1.0)
    if head >= 0.0:
        up = head * (FLOW_AT_BOTTOM + (FLOW_AT_TOP - FLOW_AT_BOTTOM) * frac)
    else:  # tailwind or reversing: a weak, separated flow down the glass
        up = np.full_like(t, head * FLOW_AT_BOTTOM)
    side = np.abs(up) * FLOW_SPREAD * (2.0 * st[:, 0] / glass.width(t)) + CROSSWIND_GAIN * cross
    return np.stack([side, up], axis=-1)


def drag(glass: GlassGeometry, st: np.ndarray, radius: np.ndarray, air: np.ndarray, vel: np.ndarray) -> np.ndarray:
    """Aerodynamic force (n, 2) N on caps of contact radius ``radius`` (m) moving at ``vel`` in the air ``air``."""
    speed = norm2(air)
    delta = 5.0 * np.sqrt(NU_AIR * (BL_RUN_UP_M + np.maximum(st[:, 1], 0.0)) / np.maximum(speed, 1e-3))
    eta = np.clip(HEIGHT_PER_RADIUS * radius / delta, 0.0, 1.0)
    profile = 1.5 * eta - 0.5 * eta**3  # Pohlhausen's cubic boundary-layer profile u/U
    rel = air * profile[:, None] - vel
    rel_speed = norm2(rel)
    coef = 0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2 * radius**2 * rel_speed
    return coef[:, None] * rel


def airflow_onset_speed_m_s(radius_m: float, t_m: float | None = None, spec: VehicleSpec = CAR_SPEC) -> float:
    """Car speed (m/s, still air) at which a drop of contact radius ``radius_m`` (m), at rest at height t_m (m;
    default mid-glass) on the centre line, starts to creep up the glass (bisection on the force balance)."""
    glass = GlassGeometry(spec)
    t = 0.5 * glass.height if t_m is None else float(t_m)
    st = np.array([[0.0, t]])
    m = float(drop_mass(radius_m))

    def up_force(v: float) -> float:
        air = air_velocity(glass, st, np.array([0.0, 0.0, v]))
        f = m * glass.gravity(st)[0] + drag(glass, st, np.array([radius_m]), air, np.zeros((1, 2)))[0]
        pin = GAMMA_W * 2.0 * radius_m * HYSTERESIS
        return f[1] - pin

    lo, hi = 0.0, 150.0
    if up_force(hi) <= 0:
        return math.inf
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if up_force(mid) <= 0 else (lo, mid)
    return hi
