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

from rain_core import checks, layout, physics
from rain_core.physics import G_M_S2

DRAG_TAIL_FIT = 1.4  # fitted: drops 0.2–5 mm launched at 5–30 m/s, 10–45° up (python -m rain_core.bench spray)


def drag_time_constant(d_mm, launch_speed_m_s, terminal_m_s=None) -> np.ndarray:
    """Time constant τ (s) of the linear-drag flight model for drops of d_mm (mm, > 0) launched at
    launch_speed_m_s (m/s, a speed: ≥ 0) relative to their drift velocity: quadratic drag's distance from s0 down
    to v_t, v_t²·ln(s0/v_t) / (g·(s0 − v_t)), divided by (s0 − v_t) — stretched for fast launches by up to
    DRAG_TAIL_FIT. ``terminal_m_s``: physics.terminal_velocity(d_mm) if the caller has it already (m/s, > 0).
    Checks its arguments (ValueError naming the one out of range); the emitter's per-frame loop calls the
    unchecked ``drag_time_constant_unchecked`` with values it made itself."""
    d_mm = checks.array("d_mm", d_mm, 0.0, 10.0, unit="mm", lo_open=True)
    launch_speed_m_s = checks.array("launch_speed_m_s", launch_speed_m_s, 0.0, 1000.0, unit="m/s")
    if terminal_m_s is not None:
        terminal_m_s = checks.array("terminal_m_s", terminal_m_s, 0.0, 100.0, unit="m/s", lo_open=True)
    return drag_time_constant_unchecked(d_mm, launch_speed_m_s, terminal_m_s)


def drag_time_constant_unchecked(d_mm, launch_speed_m_s, terminal_m_s=None) -> np.ndarray:
    """``drag_time_constant`` without the argument checks (the emitter's hot path; its inputs are its own)."""
    if terminal_m_s is None:
        terminal_m_s = physics.terminal_velocity(np.asarray(d_mm, dtype=np.float64))
    vt = np.maximum(np.asarray(terminal_m_s, dtype=np.float64), 1e-3)
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
    (arrays, m and m/s; u_y < 0). 0 where the start is already at or below it. Bisection after the apex: the
    float64 reference of :func:`time_to_height_newton`, which the emitter uses."""
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


def time_to_height_newton(y0, w0, uy, tau, level, tol_s: float = 1e-5, max_steps: int = 40) -> np.ndarray:
    """The same root as :func:`time_to_height` (s; 0 where the start is at or below ``level``) by Newton's
    method, a handful of steps instead of a hundred bisections.

    With a = w0 − u_y the height is y0 + u_y·t + a·τ·(1 − e^(−t/τ)). For a > 0 it is concave: its asymptote
    y0 + u_y·t + a·τ lies above it, so the asymptote's crossing of ``level`` is at or past the root and Newton
    steps from there approach the root from the right, never overshooting. For a < 0 (thrown down faster than
    the drift) it is convex and decreasing: Newton from t = 0 approaches from the left. Either way every step
    stays on one side and the error falls quadratically: it stops once a step is under ``tol_s`` (s), which
    leaves an error of the order of step²/τ (≪ 1 µs at the default)."""
    y0, w0, uy, tau, level = (np.asarray(x, dtype=np.float64) for x in (y0, w0, uy, tau, level))
    uy = np.minimum(uy, -1e-6)
    a = w0 - uy
    w0 = uy + a  # the clamped u_y's slope at t = 0
    below = y0 <= level
    drop = np.maximum(y0 - level, 0.0)  # rows already at or below the level: f(0) = 0, and they answer 0
    t = np.where(a > 0.0, (drop + a * tau) / -uy, 0.0)
    rate = -1.0 / tau
    # The loop runs on preallocated buffers (the arrays are small: NumPy's per-call cost dominates, and a new
    # array per operation is most of it); the same operations in the same order, so the same bits. f and its
    # slope are made together: ``parts`` holds (drop + u_y·t, w0) and ``coef`` (a·τ, −a), so parts − coef·em1
    # is (f, slope) in two calls (x + a·e is x − (−a)·e, bit for bit).
    coef = np.empty((2,) + t.shape)
    coef[0], coef[1] = a * tau, -a
    parts = np.empty_like(coef)
    parts[1] = w0
    em1, step = np.empty_like(t), np.empty_like(coef)
    f_part, num, den = parts[0, ...], step[0, ...], step[1, ...]  # views, also of 0-d t
    for i in range(max_steps):
        np.multiply(t, rate, out=em1)
        np.expm1(em1, out=em1)  # e^(−t/τ) − 1
        # f = height − level; its slope u_y + a·e^(−t/τ) = w0 + a·em1 is < 0 at every iterate (see above).
        np.multiply(uy, t, out=f_part)
        np.add(drop, f_part, out=f_part)
        np.multiply(coef, em1, out=step)
        np.subtract(parts, step, out=step)
        np.divide(num, den, out=num)  # the Newton step
        t -= num
        # Spray launches need 6–12 steps: testing for convergence before the sixth only costs time.
        if i >= 5 and not np.abs(num, out=num).max(initial=0.0) > tol_s:
            break
    return np.where(below, 0.0, t)


_LEVELS: dict[int, np.ndarray] = {}  # ground_time's two levels (road, kerb-top), shaped per tau.ndim


def ground_time(p0, v0, u, tau, reference: bool = False) -> np.ndarray:
    """Age (s) at which a drop meets the ground: the road (y = 0), or the kerb-top (KERB_HEIGHT_M) where it is
    beyond the kerb (|x| ≥ ROAD_HALF_WIDTH_M). A drop crossing the kerb line below the kerb-top is stopped at
    the time it was last at kerb-top height (so it never passes below either surface). Both crossings are
    found in one Newton solve (:func:`time_to_height_newton`); ``reference=True`` uses the bisection
    (:func:`time_to_height`), the float64 reference the tests compare with."""
    p0, v0, u = (np.asarray(a, dtype=np.float64) for a in (p0, v0, u))
    tau = np.asarray(tau, dtype=np.float64)
    if reference:
        t_road = time_to_height(p0[..., 1], v0[..., 1], u[..., 1], tau, 0.0)
        t_kerb = time_to_height(p0[..., 1], v0[..., 1], u[..., 1], tau, layout.KERB_HEIGHT_M)
        x_kerb = flight_position(p0, v0, u, tau, t_kerb)[..., 0]
        x_road = flight_position(p0, v0, u, tau, t_road)[..., 0]
    else:
        # Road and kerb-top crossings solved together (one pass over twice the rows), x from the closed form.
        levels = _LEVELS.get(tau.ndim)
        if levels is None:
            levels = _LEVELS[tau.ndim] = np.array([0.0, layout.KERB_HEIGHT_M]).reshape((2,) + (1,) * tau.ndim)
        t_both = time_to_height_newton(p0[..., 1], v0[..., 1], u[..., 1], tau, levels)
        t_road, t_kerb = t_both[0], t_both[1]
        x_both = p0[..., 0] + u[..., 0] * t_both - (v0[..., 0] - u[..., 0]) * tau * np.expm1(-t_both / tau)
        x_road, x_kerb = x_both[0], x_both[1]
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

