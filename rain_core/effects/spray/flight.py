"""Droplet flight: one closed form shared with the GPU (``shaders/spray/flight.glsl``), and its RK4 reference.

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
"""

from __future__ import annotations

import numpy as np

from rain_core import layout, physics
from rain_core.physics import G_M_S2

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
    tau_fast = vt * np.log(safe) / (G_M_S2 * (safe - 1.0))
    # Linear drag gives up the excess speed exponentially, quadratic drag like 1/t (a long tail): stretch τ
    # by up to DRAG_TAIL_FIT for fast launches (1 at terminal speed, so τ stays continuous there).
    stretch = 1.0 + (DRAG_TAIL_FIT - 1.0) * (1.0 - 1.0 / ratio**2)
    return np.where(fast, tau_fast * stretch, vt / G_M_S2)


def relax(t, tau):
    """τ·(1 − e^(−t/τ)), accurate for small t/τ."""
    return -tau * np.expm1(-t / tau)


def flight_position(p0, v0, u, tau, t) -> np.ndarray:
    """Position (m) at age t (s): x0 + u·t + (v0 − u)·τ·(1 − e^(−t/τ)). p0, v0, u (..., 3); tau, t (...)."""
    p0, v0, u = (np.asarray(a, dtype=np.float64) for a in (p0, v0, u))
    tau = np.asarray(tau, dtype=np.float64)[..., None]
    t = np.asarray(t, dtype=np.float64)[..., None]
    return p0 + u * t + (v0 - u) * relax(t, tau)


def flight_velocity(v0, u, tau, t) -> np.ndarray:
    """Velocity (m/s) at age t (s): u + (v0 − u)·e^(−t/τ)."""
    v0, u = np.asarray(v0, dtype=np.float64), np.asarray(u, dtype=np.float64)
    decay = np.exp(-np.asarray(t, dtype=np.float64) / np.asarray(tau, dtype=np.float64))[..., None]
    return u + (v0 - u) * decay


def _height(y0, w0, uy, tau, t):
    return y0 + uy * t + (w0 - uy) * relax(t, tau)


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
    k = G_M_S2 / (vt * vt)
    w = np.asarray(wind, dtype=np.float64)
    gvec = np.array([0.0, -G_M_S2, 0.0])

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

