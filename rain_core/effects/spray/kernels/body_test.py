"""Kernel of the body test: when a drop first enters a vehicle's body (the linear-bound window, then the
float32 coarse and zoom search of ``body_hit``). Twin: ``body.body_hit_time_fast``. Units: m, s."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit


@jit.kernel
def _inside(px, py, pz, hw, floor, height, hl, hwb, well_hl, well_top, well_x):
    """``BodyBox.contains`` of one local point (float32: right, up, back) — ``body._inside``'s comparisons."""
    in_box = (px > -hw) and (px < hw) and (py > floor) and (py < height) and (pz > -hl) and (pz < hl)
    if not in_box:
        return False
    in_well = (abs(abs(pz) - hwb) < well_hl) and (py < well_top) and (abs(px) > well_x)
    return not in_well


@jit.kernel
def _local_at(t, coarse, P, U, D, tau32, rate32):
    """The float32 local position P + U·t + D·τ(1 − e^(−t/τ)) at age t (coarse: e^x − 1 by exp, as the twin's
    first pass)."""
    x = t * rate32
    if coarse:
        rel = np.float32(math.exp(x)) - np.float32(1.0)
    else:
        rel = np.float32(math.expm1(x))
    rel = rel * tau32
    return (P[0] + U[0] * t - D[0] * rel, P[1] + U[1] * t - D[1] * rel, P[2] + U[2] * t - D[2] * rel)


@jit.kernel
def body_hit(p0, v0, u, tau, t_max, vehicle, vi, age_now, nd, samples, zoom, rounds, out):
    """``body.body_hit_time_fast`` for droplets [:nd] (s, ≤ t_max; t_max where the drop never enters its
    thrower's body): the body frame from ``vehicle`` (V, 20) (position, velocity, right, forward, BodyBox fields;
    ``spawn._vehicle_table``) of vehicle ``vi`` moved back by ``age_now`` (s), the window where the drop can meet
    the body from linear bounds (float64), then ``samples`` coarse ages and ``rounds`` zooms of ``zoom`` ages in
    float32. Writes ``out[:nd]``."""
    f32 = np.float32
    P = np.empty(3, np.float32)
    U = np.empty(3, np.float32)
    D = np.empty(3, np.float32)
    Pd = np.empty(3)
    Ud = np.empty(3)
    Dd = np.empty(3)
    upper = np.empty(3)
    lower = np.empty(3)
    for i in range(nd):
        t_mx = t_max[i]
        out[i] = t_mx
        row = vehicle[vi[i]]
        age = age_now[i]
        # The drop's start, drift and excess in the body's moving frame (right, up, back).
        ox, oy, oz = row[0] - row[3] * age, row[1] - row[4] * age, row[2] - row[5] * age
        for a in range(3):
            if a == 0:
                vx, vy, vz = p0[i, 0] - ox, p0[i, 1] - oy, p0[i, 2] - oz
            elif a == 1:
                vx, vy, vz = u[i, 0] - row[3], u[i, 1] - row[4], u[i, 2] - row[5]
            else:
                vx, vy, vz = v0[i, 0] - u[i, 0], v0[i, 1] - u[i, 1], v0[i, 2] - u[i, 2]
            lx = vx * row[6] + vz * row[8]
            lz = -(vx * row[9] + vz * row[11])
            if a == 0:
                Pd[0], Pd[1], Pd[2] = lx, vy, lz
            elif a == 1:
                Ud[0], Ud[1], Ud[2] = lx, vy, lz
            else:
                Dd[0], Dd[1], Dd[2] = lx, vy, lz
        upper[0], upper[1], upper[2] = row[12], row[15], row[13]
        lower[0], lower[1], lower[2] = -row[12], row[14], -row[13]
        tc = tau[i]
        # Beyond the body for good past t_end (linear bounds of each coordinate).
        exit_min = np.inf
        for a in range(3):
            lo_b = Pd[a] + min(Dd[a], 0.0) * tc
            hi_b = Pd[a] + max(Dd[a], 0.0) * tc
            if Ud[a] > 0.0:
                e = (upper[a] - lo_b) / Ud[a]
            elif Ud[a] < 0.0:
                e = (lower[a] - hi_b) / Ud[a]
            else:
                e = np.inf
            exit_min = min(exit_min, e)
        t_end = min(max(exit_min, 0.0), t_mx)
        if not t_end > 0.0:
            continue
        near = True
        for a in range(3):
            lo_b = Pd[a] + min(Dd[a], 0.0) * tc
            hi_b = Pd[a] + max(Dd[a], 0.0) * tc
            span_lo = lo_b + min(Ud[a], 0.0) * t_end
            span_hi = hi_b + max(Ud[a], 0.0) * t_end
            if not (span_lo < upper[a] and span_hi > lower[a]):
                near = False
        if not near:
            continue
        for a in range(3):
            P[a], U[a], D[a] = f32(Pd[a]), f32(Ud[a]), f32(Dd[a])
        hw, hl, floor, height = f32(row[12]), f32(row[13]), f32(row[14]), f32(row[15])
        hwb, well_hl, well_top, well_x = f32(row[16]), f32(row[17]), f32(row[18]), f32(row[19])
        tau32 = f32(tc)
        rate32 = f32(-1.0) / tau32
        te32 = f32(t_end)
        # Coarse pass: the first of ``samples`` equal steps inside.
        lo = f32(0.0)
        hi = f32(-1.0)
        for j in range(1, samples + 1):
            t = te32 * (f32(j) / f32(samples))
            # Skipped where the drop is surely outside the box at this age: each coordinate lies within
            # P + U·t + D·[0, min(t, τ)] (τ(1 − e^(−t/τ)) ≤ min(t, τ)), and a mm of margin covers float32's rounding
            # of the twin's point (≲ 10 µm): the same answer as evaluating it, without the exp.
            td = float(t)
            reach = min(td, tc)
            far = False
            for a in range(3):
                base = Pd[a] + Ud[a] * td
                dm = Dd[a] * reach
                if base + max(dm, 0.0) < lower[a] - 1e-3 or base + min(dm, 0.0) > upper[a] + 1e-3:
                    far = True
                    break
            if far:
                lo = t
                continue
            x, y, z = _local_at(t, True, P, U, D, tau32, rate32)
            if _inside(x, y, z, hw, floor, height, hl, hwb, well_hl, well_top, well_x):
                hi = t
                break
            lo = t
        if hi < f32(0.0):
            continue
        for _ in range(rounds):
            # The first zoomed age inside (the last is ``hi`` itself); none found: the first step (as argmax).
            width = hi - lo
            first = 1
            for j in range(1, zoom + 1):
                t = hi if j == zoom else lo + width * (f32(j) / f32(zoom))
                x, y, z = _local_at(t, False, P, U, D, tau32, rate32)
                if _inside(x, y, z, hw, floor, height, hl, hwb, well_hl, well_top, well_x):
                    first = j
                    break
            new_lo = lo if first == 1 else lo + width * (f32(first - 1) / f32(zoom))
            new_hi = hi if first == zoom else lo + width * (f32(first) / f32(zoom))
            lo, hi = new_lo, new_hi
        out[i] = lo
