"""Kernels of a parcel's flight: terminal velocity, carrier air, τ and the Newton landing ages on the road and
the kerb top (``fly``). Twins: ``spawn._terminal_velocity``, ``launch.carrier_air_and_tau``,
``flight.ground_time``. Units: m, s, m/s, mm for drop sizes."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit


@jit.kernel
def _times_to_height(p0, v0, u, tau, rows, m, level, tol_s, max_steps, out, drop, slope, excess, active):
    """``flight.time_to_height_newton`` (s; 0 where a parcel starts at or below ``level`` m) of parcels
    ``rows[:m]`` into ``out[row]``: the same Newton steps, but each parcel stops once its own step is under
    ``tol_s`` (the twin stops when every parcel's is under 1e-5 s, after at least six: at quadratic
    convergence a last step of 1e-9 s leaves ≪ 1e-12 s). Step by step over all parcels still going, so their
    independent chains of expm1 overlap. ``drop``, ``slope``, ``excess``, ``active``: scratch of ≥ m rows."""
    k = 0
    for j in range(m):
        i = rows[j]
        y0 = p0[i, 1]
        if y0 <= level:
            out[i] = 0.0
            continue
        uy = min(u[i, 1], -1e-6)
        a = v0[i, 1] - uy
        drop[j] = max(y0 - level, 0.0)
        slope[j] = uy + a  # the clamped u_y's slope at t = 0 (the twin's w0)
        excess[j] = a
        out[i] = (drop[j] + a * tau[i]) / -uy if a > 0.0 else 0.0
        active[k] = j
        k += 1
    for _ in range(max_steps):
        going = 0
        for q in range(k):
            j = active[q]
            i = rows[j]
            t = out[i]
            tc = tau[i]
            a = excess[j]
            uy = min(u[i, 1], -1e-6)
            em1 = math.expm1(t * (-1.0 / tc))
            step = ((drop[j] + uy * t) - (a * tc) * em1) / (slope[j] - (-a) * em1)
            out[i] = t - step
            if abs(step) > tol_s:
                active[going] = j
                going += 1
        k = going
        if k == 0:
            break


@jit.kernel
def fly(p0, v0, d_mm, air, updraught, nd, wind, mist_vt, mist_tau, gk_x, gk_x0, gk_h, gk_y0, gk_y1, gk_d0, gk_d1,
        g, tail_fit, kerb_m, half_width_m, tol_s, max_steps, u, speed, tau, t_ground):
    """Per parcel (rows [:nd] droplets, the rest mist): its terminal velocity (m/s; droplets by Gunn–Kinzer's
    Hermite interpolant of d_mm, mist ``mist_vt``), the air it drifts in ``u`` (n, 3) m/s (``wind`` + ``air``, less
    the unheld part ``1 − updraught`` of its settling), its launch ``speed`` relative to that air (m/s), its drag
    time constant ``tau`` (s; mist ``mist_tau``) and ``t_ground`` (s), its age at the road or kerb-top (levels 0 and
    ``kerb_m`` m, the kerb line at |x| = ``half_width_m``). Writes u, speed, tau, t_ground."""
    n = p0.shape[0]
    nk = gk_x.shape[0]
    for i in range(n):
        if i < nd:
            d = d_mm[i]
            # gk_x.searchsorted(d, side="right") − 1: the last knot at or below d.
            lo, hi = 0, nk
            while lo < hi:
                mid = (lo + hi) // 2
                if gk_x[mid] <= d:
                    lo = mid + 1
                else:
                    hi = mid
            k = lo - 1
            h = gk_h[k]
            t = (d - gk_x0[k]) / h
            t2 = t * t
            t3 = t2 * t
            two_t3, three_t2 = 2 * t3, 3 * t2
            vt = ((two_t3 - three_t2 + 1) * gk_y0[k] + (t3 - 2 * t2 + t) * h * gk_d0[k]
                  + (three_t2 - two_t3) * gk_y1[k] + (t3 - t2) * h * gk_d1[k])
        else:
            vt = mist_vt
        ux = wind[0] + air[i, 0]
        uy = wind[1] + air[i, 1]
        uz = wind[2] + air[i, 2]
        uy -= vt * (1.0 - updraught[i])
        u[i, 0], u[i, 1], u[i, 2] = ux, uy, uz
        ex, ey, ez = v0[i, 0] - ux, v0[i, 1] - uy, v0[i, 2] - uz
        s0 = math.sqrt((ex * ex + ez * ez) + ey * ey)  # np.einsum's order for three components
        speed[i] = s0
        if i < nd:
            # flight.drag_time_constant_unchecked
            vtc = max(vt, 1e-3)
            ratio = max(s0 / vtc, 1.0)
            if ratio > 1.0 + 1e-6:
                stretch = 1.0 + (tail_fit - 1.0) * (1.0 - 1.0 / (ratio * ratio))
                tc = vtc * math.log(ratio) / (g * (ratio - 1.0)) * stretch
            else:
                tc = vtc / g
        else:
            tc = mist_tau
        tau[i] = tc
    # flight.ground_time: the road crossing of every parcel, then the kerb-top's of those that may need it.
    rows = np.arange(n)
    drop, slope, excess, active = np.empty(n), np.empty(n), np.empty(n), np.empty(n, np.int64)
    _times_to_height(p0, v0, u, tau, rows, n, 0.0, tol_s, max_steps, t_ground, drop, slope, excess, active)
    m = 0
    for i in range(n):
        # The kerb-top crossing (at or before the road's) matters only if x can reach the kerb line by then:
        # x(t) lies within px + u_x·t + [min(0, Δv_x·τ), max(0, Δv_x·τ)] (a µm margin for rounding).
        tc, t_road, ux = tau[i], t_ground[i], u[i, 0]
        px, dvx_tau = p0[i, 0], (v0[i, 0] - ux) * tc
        x_road = px + ux * t_road - dvx_tau * math.expm1(-t_road / tc)
        drift = ux * t_road
        lo = px + min(drift, 0.0) + min(dvx_tau, 0.0)
        hi = px + max(drift, 0.0) + max(dvx_tau, 0.0)
        if abs(x_road) >= half_width_m or not (hi < half_width_m - 1e-6 and lo > 1e-6 - half_width_m):
            rows[m] = i
            m += 1
    if m == 0:
        return
    t_kerb = np.empty(n)
    _times_to_height(p0, v0, u, tau, rows, m, kerb_m, tol_s, max_steps, t_kerb, drop, slope, excess, active)
    for j in range(m):
        i = rows[j]
        tc, t_road, ux = tau[i], t_ground[i], u[i, 0]
        px, dvx_tau = p0[i, 0], (v0[i, 0] - ux) * tc
        x_road = px + ux * t_road - dvx_tau * math.expm1(-t_road / tc)
        x_kerb = px + ux * t_kerb[i] - dvx_tau * math.expm1(-t_kerb[i] / tc)
        if abs(x_kerb) >= half_width_m or abs(x_road) >= half_width_m:
            t_ground[i] = t_kerb[i]
