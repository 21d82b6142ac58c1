"""Kernel of the launches: every bucket's droplets and the mist puffs of a frame in one loop (``launch``),
from draws the caller made in the twins' order. Twins: ``launch.launch_droplets_sorted``, ``launch_mist``.
Units: m, s, m/s, mm for drop sizes."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit


@jit.kernel
def launch(w, bounds, nd, age_now, draws, offs, wheel, vehicle, mist_vehicle, bucket_table, uniform_lo,
           uniform_span, wave_table, mist_lo, mist_span, mist_consts, p0, v0, d_mm, sigma0, growth, air, updraught):
    """``launch.launch_droplets_sorted`` (rows [:nd], bucket k in rows bounds[k]:bounds[k + 1]) and
    ``launch.launch_mist`` (the rest) of parcels from flat wheels ``w``, ``age_now`` s before now: start points
    ``p0`` (m), ground velocities ``v0`` (m/s), drop sizes ``d_mm`` (mm; holds the droplets' standard normal draws
    on entry), parcel sizes ``sigma0`` (m), spread rates ``growth``, carrier ``air`` (m/s) and ``updraught``.
    ``draws``: the twins' other draws as :func:`launch.launch_parcels_compiled` makes them, in their order —
    the tread's ``across`` at 0, bucket k's uniform rows (row-major, (rows, m)) at offs[k], the tread pickup's
    lateral normals at offs[5], the mist's seven rows at offs[6]. ``wheel`` (W, 15) ``launch.wheel_table``,
    ``vehicle`` (V, 20) ``spawn._vehicle_table``, ``mist_vehicle`` (V, ≥ 2) height and half length (m); the
    per-bucket tables of launch.py; ``mist_consts``: WAKE_LIFT_HEIGHT_M, MIST_SIGMA0_M, MIST_D_MM,
    MIST_DIFFUSIVITY."""
    n = w.shape[0]
    for k in range(5):
        lo, hi = bounds[k], bounds[k + 1]
        m = hi - lo
        off = offs[k]
        med, sig, dmin, dmax = bucket_table[k, 0], bucket_table[k, 1], bucket_table[k, 2], bucket_table[k, 3]
        s0, spread = bucket_table[k, 4], bucket_table[k, 5]
        for i in range(lo, hi):
            j = i - lo
            ww = w[i]
            age = age_now[i]
            vx, vy, vz = wheel[ww, 0], wheel[ww, 1], wheel[ww, 2]
            cx, cy, cz = wheel[ww, 3] - vx * age, wheel[ww, 4] - vy * age, wheel[ww, 5] - vz * age
            fx, fy, fz = wheel[ww, 6], wheel[ww, 7], wheel[ww, 8]
            ox, oy, oz = wheel[ww, 9], wheel[ww, 10], wheel[ww, 11]
            r, b, v = wheel[ww, 12], wheel[ww, 13], wheel[ww, 14]
            across = (draws[i] - 0.5) * b
            u0 = uniform_lo[k, 0] + uniform_span[k, 0] * draws[off + j]
            sigma0[i] = s0 * u0
            if k <= 1:  # spray
                u1 = uniform_lo[k, 1] + uniform_span[k, 1] * draws[off + m + j]
                u2 = uniform_lo[k, 2] + uniform_span[k, 2] * draws[off + 2 * m + j]
                u3 = uniform_lo[k, 3] + uniform_span[k, 3] * draws[off + 3 * m + j]
                share = uniform_lo[k, 4] + uniform_span[k, 4] * draws[off + 4 * m + j]
                u5 = uniform_lo[k, 5] + uniform_span[k, 5] * draws[off + 5 * m + j]
                u6 = uniform_lo[k, 6] + uniform_span[k, 6] * draws[off + 6 * m + j]
                back, up, out_ = r * u1, r * u2, b * u3
                p0[i, 0] = cx - fx * back + ox * out_
                p0[i, 1] = cy - fy * back + oy * out_ + up
                p0[i, 2] = cz - fz * back + oz * out_
                ax, ay, az = vx * share, vy * share, vz * share
                air[i, 0], air[i, 1], air[i, 2] = ax, ay, az
                v0[i, 0] = ax + v * (ox * u6)
                v0[i, 1] = ay + v * (oy * u6) + v * u5
                v0[i, 2] = az + v * (oz * u6)
                updraught[i] = uniform_lo[k, 7] + uniform_span[k, 7] * draws[off + 7 * m + j]
            else:
                air[i, 0], air[i, 1], air[i, 2] = 0.0, 0.0, 0.0
                updraught[i] = 0.0
                u1 = uniform_lo[k, 1] + uniform_span[k, 1] * draws[off + m + j]
                u2 = uniform_lo[k, 2] + uniform_span[k, 2] * draws[off + 2 * m + j]
                if k == 2:  # tread pickup
                    alpha = (5.0 + 45.0 * u1 ** 1.6) * (math.pi / 180.0)
                    speed = v * u2
                    lateral = v * (0.1 + 0.12 * draws[offs[5] + j])
                    ca, sa = math.cos(alpha), math.sin(alpha)
                    rsa = r * sa
                    p0[i, 0] = cx - fx * rsa + ox * across
                    p0[i, 1] = cy - fy * rsa + oy * across + r * (1.0 - ca)
                    p0[i, 2] = cz - fz * rsa + oz * across
                    sca = speed * ca
                    v0[i, 0] = vx - fx * sca + ox * lateral
                    v0[i, 1] = vy - fy * sca + oy * lateral + speed * sa
                    v0[i, 2] = vz - fz * sca + oz * lateral
                else:  # side (3) and bow (4) waves
                    u3 = uniform_lo[k, 3] + uniform_span[k, 3] * draws[off + 3 * m + j]
                    ahead, height, lift_a, lift_b = (wave_table[k - 3, 0], wave_table[k - 3, 1],
                                                     wave_table[k - 3, 2], wave_table[k - 3, 3])
                    aside = b / 2.0 if k == 3 else across
                    kr = ahead * r
                    p0[i, 0] = cx + fx * kr + ox * aside
                    p0[i, 1] = cy + fy * kr + oy * aside + height
                    p0[i, 2] = cz + fz * kr + oz * aside
                    lift = lift_a + lift_b * (u3 * u3)
                    v0[i, 0] = v * (fx * u1 + ox * u2)
                    v0[i, 1] = v * (fy * u1 + oy * u2) + v * lift
                    v0[i, 2] = v * (fz * u1 + oz * u2)
            d_mm[i] = min(max(med * math.exp(sig * d_mm[i]), dmin), dmax)
            growth[i] = spread
    nm = n - nd
    off = offs[6]
    lift_h, sigma_m, mist_d, diffusivity = mist_consts[0], mist_consts[1], mist_consts[2], mist_consts[3]
    u = np.empty(7)
    for i in range(nd, n):
        j = i - nd
        ww = w[i]
        vi = ww // 4
        age = age_now[i]
        vx, vy, vz = wheel[ww, 0], wheel[ww, 1], wheel[ww, 2]
        cx, cy, cz = wheel[ww, 3] - vx * age, wheel[ww, 4] - vy * age, wheel[ww, 5] - vz * age
        fx, fy, fz = wheel[ww, 6], wheel[ww, 7], wheel[ww, 8]
        ox, oy, oz = wheel[ww, 9], wheel[ww, 10], wheel[ww, 11]
        r, v = wheel[ww, 12], wheel[ww, 14]
        for q in range(7):
            u[q] = mist_lo[q] + mist_span[q] * draws[off + q * nm + j]
        # Behind the body's tail, in line with the wheel: half length − (c − position)·(−forward).
        # (np.einsum's order for three components: x + z, then y.)
        to_tail = mist_vehicle[vi, 1] - (((cx - vehicle[vi, 0]) * -vehicle[vi, 9] + (cz - vehicle[vi, 2])
                                           * -vehicle[vi, 11]) + (cy - vehicle[vi, 1]) * -vehicle[vi, 10])
        behind = max(to_tail, 0.0) + u[0]
        up = r * u[1]
        p0[i, 0] = cx - fx * behind + 0.0 * up + ox * u[2]
        p0[i, 1] = cy - fy * behind + 1.0 * up + oy * u[2]
        p0[i, 2] = cz - fz * behind + 0.0 * up + oz * u[2]
        lift = v * u[3] * (mist_vehicle[vi, 0] / lift_h)
        side = v * u[5]
        v0[i, 0] = vx * u[4] + 0.0 * lift + ox * side
        v0[i, 1] = vy * u[4] + 1.0 * lift + oy * side
        v0[i, 2] = vz * u[4] + 0.0 * lift + oz * side
        d_mm[i] = mist_d
        sigma0[i] = sigma_m * u[6]
        # 2K, the eddy diffusivity K = MIST_DIFFUSIVITY·|V|·height of the vehicle's wake (m²/s).
        wx, wy, wz = vehicle[vi, 3], vehicle[vi, 4], vehicle[vi, 5]
        growth[i] = 2.0 * (diffusivity * math.sqrt(wx * wx + wy * wy + wz * wz) * mist_vehicle[vi, 0])
        air[i, 0], air[i, 1], air[i, 2] = 0.0, 0.0, 0.0
        updraught[i] = 0.0
