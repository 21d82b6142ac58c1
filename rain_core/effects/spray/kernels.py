"""Compiled kernels of the spray's per-frame spawn (rain_core.jit): each replaces a chain of NumPy calls of the
emitter's fast path (``spawn.spawn_parcels_fast``) with one loop over a frame's parcels.

Their NumPy twins stay the fallback and the oracle: ``launch.launch_droplets_sorted`` / ``launch_mist``
(:func:`launch_parcels`), ``spawn._terminal_velocity``, ``launch.carrier_air_and_tau`` and
``flight.ground_time`` (:func:`fly`), ``body.body_hit_time_fast`` (:func:`body_hit`). The same operations in the
same order, so the results agree to rounding (libm's exp/log/sin/cos/pow against NumPy's, and Newton's
stopping test per parcel instead of over all of them: tests/effects/spray/test_kernels.py states the tolerances).
Random numbers are drawn by the caller, in the twin's order, and passed in. Units: m, s, m/s, mm for drop sizes.
"""

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


@jit.kernel
def settle(t_body, t_ground, cap, speed, nd, life, fate, growth, fate_road, fate_body, fate_air):
    """Each parcel's fate and life (s), as ``spawn.spawn_parcels_fast`` decides them before the rings' horizons:
    droplets [:nd] end at the body (``t_body`` < ``t_ground``) or on the ground, and their spread rate
    ``growth`` is scaled by their launch ``speed``; mist puffs [nd:] fade at their drawn ``cap`` or land. Lives are
    then drawn 1 ms short of the surface (not below 0). Writes life, fate, growth."""
    n = life.shape[0]
    for i in range(n):
        if i < nd:
            tb, tg = t_body[i], t_ground[i]
            fate[i] = fate_body if tb < tg else fate_road
            t = min(tb, tg)
            growth[i] *= speed[i]
        else:
            c, tg = cap[i - nd], t_ground[i]
            fate[i] = fate_air if c < tg else fate_road
            t = min(c, tg)
        life[i] = max(t - 1e-3, 0.0)


@jit.kernel
def file_records(fate, life, horizon_drop, horizon_mist, nd, now, landings_on, mass, p0, v0, u, tau, birth, sigma0,
                 growth, d_mm, vi, vehicle_consts, consts, fates, landings, records, birth_out, death_out):
    """The end of ``spawn.spawn_parcels_fast`` for a frame's parcels (droplets [:nd], then mist): lives past their
    ring's horizon (s) fade in the air; the mass by fate is added to ``fates`` (3,) kg; with ``landings_on`` the
    droplets that land on the road write (time s, x m, z m, downward momentum kg·m/s) rows into ``landings``
    (``_road_landings``); and the GPU records of the parcels still alive at ``now`` (s) are written, ring 0's
    first, into ``records`` (k, 20) float32 (the PARTICLE_DTYPE fields in order, all but ``rand``), their birth
    and death (s) into ``birth_out``/``death_out``. ``consts``: PERIOD_M, Q·1.5, RHO_WATER, SPLASH_MIN_MM,
    MIST_SIGMA_MAX, then the fates road, body, air and kinds droplet, mist, fade. Returns (records of ring 0,
    records, landings)."""
    n = life.shape[0]
    period_m, q15, rho, splash_mm, sigma_max = consts[0], consts[1], consts[2], consts[3], consts[4]
    fate_road, fate_air = int(consts[5]), int(consts[7])
    kind_drop, kind_mist, kind_fade = consts[8], consts[9], consts[10]
    sums = np.zeros(3)  # kg by fate, summed in order as np.bincount does
    k0, k, m = 0, 0, 0
    for i in range(n):
        horizon = horizon_drop if i < nd else horizon_mist
        t = life[i]
        f = fate[i]
        if t > horizon:
            f = fate_air
            t = horizon
        fate[i] = f
        life[i] = t
        sums[f] += mass[i]
        if landings_on and i < nd and f == fate_road:
            tc = tau[i]
            e = -t / tc
            relax = -tc * math.expm1(e)
            landings[m, 0] = birth[i] + t
            landings[m, 1] = p0[i, 0] + u[i, 0] * t + (v0[i, 0] - u[i, 0]) * relax
            landings[m, 2] = p0[i, 2] + u[i, 2] * t + (v0[i, 2] - u[i, 2]) * relax
            vel_y = u[i, 1] + (v0[i, 1] - u[i, 1]) * math.exp(e)
            landings[m, 3] = mass[i] * max(-vel_y, 0.0)
            m += 1
        death = birth[i] + t
        if not death > now:
            continue
        rec = records[k]
        period = math.floor(p0[i, 2] / period_m)
        rec[0], rec[1], rec[2] = p0[i, 0], p0[i, 1], p0[i, 2] - period * period_m
        rec[3] = period
        rec[4], rec[5], rec[6] = v0[i, 0], v0[i, 1], v0[i, 2]
        rec[7] = tau[i]
        rec[8], rec[9], rec[10] = u[i, 0], u[i, 1], u[i, 2]
        rec[11], rec[12], rec[13], rec[14] = birth[i], t, sigma0[i], growth[i]
        rec[15] = q15 * mass[i] / (rho * d_mm[i] * 1e-3)  # optics.extinction_area_m2
        kind = kind_drop + kind_fade if f == fate_air else kind_drop
        if i < nd:
            rec[16] = kind
            rec[19] = 1.0 if d_mm[i] >= splash_mm else 0.5
            k0 += 1
        else:
            rec[16] = kind + (kind_mist - kind_drop)
            rec[19] = sigma_max * vehicle_consts[vi[i], 0]  # mist puffs hold σ_max (m)
        rec[17] = d_mm[i]
        birth_out[k] = birth[i]
        death_out[k] = death
        k += 1
    for f in range(3):
        fates[f] += sums[f]
    return k0, k, m


@jit.kernel
def wheel_kinematics(state, cos_yaw, sin_yaw, local, consts, side, vehicle, wheel, signed):
    """``wheels.gather_wheels``' rigid-body kinematics of every vehicle's wheels (``Vehicle.to_world`` and
    ``_point_velocity``, about the rear axle): from ``state`` (V, 6) x, z (m), yaw, speed (m/s), yaw rate (rad/s),
    y (m), the yaw's cosine and sine (NumPy's, as the twin), the wheels' local contacts (V, 4, 3) m, the fleet's
    constants (V, 4; column 3 the half wheelbase) and the wheels' sides ``side`` (4V,) ±1. Writes the vehicle
    table's position, velocity, right and forward (``vehicle`` (V, 20) columns 0–11) and the wheel table's
    velocity, contact, travel, outward and speed (``wheel`` (4V, 15) columns 0–11 and 14); ``signed`` (4V,) the
    wheels' ground speeds with the sign of travel (m/s)."""
    for vi in range(state.shape[0]):
        px, pz, speed, omega, py = state[vi, 0], state[vi, 1], state[vi, 3], state[vi, 4], state[vi, 5]
        c, s = cos_yaw[vi], sin_yaw[vi]
        fx, fz = -s, -c  # forward (−sin, 0, −cos), right (cos, 0, −sin)
        row = vehicle[vi]
        row[0], row[1], row[2] = px, py, pz
        row[6], row[8] = c, fx
        row[9], row[11] = fx, fz
        hwb = consts[vi, 3]
        ax = px + s * hwb  # the rear axle
        az = pz + c * hwb
        bx, by, bz = fx * speed, row[10] * speed, fz * speed
        row[3] = bx + omega * (pz - az)
        row[5] = bz + omega * (ax - px)
        vx, vy, vz = row[3], row[4], row[5]
        back = -1.0 if speed < 0.0 else 1.0
        for k in range(4):
            w = 4 * vi + k
            lx, ly, lz = local[vi, k, 0], local[vi, k, 1], local[vi, k, 2]
            cx = c * lx + s * lz + px
            cz = c * lz - s * lx + pz
            out = wheel[w]
            out[0], out[1], out[2] = vx, vy, vz
            out[3], out[4], out[5] = cx, ly + py, cz
            wx = bx + omega * (cz - az)
            wz = bz - omega * (cx - ax)
            sp = math.sqrt((wx * wx + wz * wz) + by * by)  # np.einsum's order
            out[14] = sp
            signed[w] = sp * back
            out[6], out[7], out[8] = fx * back, row[10] * back, fz * back
            sg = side[w]
            out[9], out[10], out[11] = c * sg, row[7] * sg, fx * sg


@jit.kernel
def wheel_water(signed, wheel, depth, planing_speed, bands, consts):
    """``water.allocate_water_unchecked`` and ``hydroplaning_risk_unchecked`` at every wheel: its ground speed
    ``signed`` (m/s, either sign), tread width ``wheel[:, 13]`` (m) and the film ``depth`` the road's sampler gave
    (mm: NaN counts as dry, below 0 as 0, capped at MAX_FILM_DEPTH_MM). ``bands`` (4, 4): per mechanism its depth
    band's start and width (mm) and its release ramp's start and span (m/s); ``consts``: ρ_w·1e-3, the tread
    spray ramp's start and span, TREAD_SPRAY_SHARE, 1 − MIST_SHARE, MIST_SHARE, HYDRO_LIFT_ONSET, 1 − onset,
    the drained depth's start and span (mm), MAX_FILM_DEPTH_MM. Returns the depths (mm), M_w, the allocation and
    what is thrown per mechanism (kg/s), the six buckets (kg/s), the hydroplaning risk and whether any wheel
    throws water."""
    n = signed.shape[0]
    depth_out, available, risk = np.empty(n), np.empty(n), np.empty(n)
    allocated, thrown, buckets = np.empty((n, 4)), np.empty((n, 4)), np.empty((n, 6))
    rho_mm, spray_lo, spray_span, tread_share = consts[0], consts[1], consts[2], consts[3]
    keep_share, mist_share, onset, onset_span = consts[4], consts[5], consts[6], consts[7]
    drain_lo, drain_span, max_mm = consts[8], consts[9], consts[10]
    throwing = False
    for i in range(n):
        d = depth[i]
        d = 0.0 if not d > 0.0 else d  # np.fmax(d, 0): NaN and below 0 → 0
        d = min(d, max_mm)
        depth_out[i] = d
        h_mm = (d * 1e-3) * 1e3
        v = abs(signed[i])
        flux = v * wheel[i, 13] * rho_mm
        available[i] = flux * h_mm
        total = 0.0
        for j in range(4):
            a = flux * min(max(h_mm - bands[j, 0], 0.0), bands[j, 1])
            allocated[i, j] = a
            thrown[i, j] = a * min(max((v - bands[j, 2]) / bands[j, 3], 0.0), 1.0)
            total += a
        scale = available[i] / total if total > 0.0 else 1.0
        for j in range(4):
            allocated[i, j] *= scale
            thrown[i, j] *= scale
            if thrown[i, j] > 0.0:
                throwing = True
        share = tread_share * min(max((v - spray_lo) / spray_span, 0.0), 1.0)
        tread_spray = thrown[i, 1] * share
        buckets[i, 0] = thrown[i, 0] * keep_share
        buckets[i, 1] = tread_spray * keep_share
        buckets[i, 2] = thrown[i, 1] - tread_spray
        buckets[i, 3] = thrown[i, 2]
        buckets[i, 4] = thrown[i, 3]
        buckets[i, 5] = (thrown[i, 0] + tread_spray) * mist_share
        lift = v / planing_speed[i]
        lift = lift * lift
        speed_part = min(max((lift - onset) / onset_span, 0.0), 1.0)
        depth_part = min(max(((d * 1e-3) * 1e3 - drain_lo) / drain_span, 0.0), 1.0)
        risk[i] = speed_part * depth_part
    return depth_out, available, allocated, thrown, buckets, risk, throwing


@jit.kernel
def tally(acc, rates, elapsed, on_drop, scale_drop, total_drop, draws_drop, on_mist, scale_mist, total_mist,
          draws_mist, wheel_thrown, wheel_emitted):
    """``SprayEmitter._spawn``'s accounts: how many parcels each (vehicle, wheel, bucket) cell of ``acc`` (V, 4, 6)
    kg not yet emitted gets this step — per ring (droplets: buckets 0–4, mist: 5), if ``on``, its share of
    ``scale`` parcels (the ring's rate × the step, capped) by its mass over the ring's ``total`` kg, the fraction
    rounded up where its uniform ``draws`` (NumPy's, the twin's call) fall below it. The emitted cells' mass
    leaves ``acc`` (into ``wheel_emitted`` (V, 4) kg); ``wheel_thrown`` (V, 4) kg grows by ``rates`` (V, 4, 6)
    kg/s × ``elapsed`` s. Returns the emitted cells bucket-major (as ``counts.transpose(2, 0, 1).nonzero()``:
    each cell's parcel mass kg and count), one row per parcel (its flat wheel and mass kg) and ``bounds`` (7,)
    (bucket k in rows bounds[k]:bounds[k + 1])."""
    nv = acc.shape[0]
    counts = np.zeros((nv, 4, 6), np.int64)
    for v in range(nv):
        for k in range(4):
            for b in range(6):
                if b < 5:
                    if not on_drop:
                        continue
                    expected = scale_drop * (acc[v, k, b] / total_drop)
                    draw = draws_drop[v, k, b]
                else:
                    if not on_mist:
                        continue
                    expected = scale_mist * (acc[v, k, b] / total_mist)
                    draw = draws_mist[v, k, 0]
                whole = math.floor(expected)
                counts[v, k, b] = int(whole + (1.0 if draw < expected - whole else 0.0))
    n_cells, n_rows = 0, 0
    bounds = np.zeros(7, np.int64)
    for v in range(nv):
        for k in range(4):
            emitted, thrown = 0.0, 0.0
            for b in range(6):
                c = counts[v, k, b]
                emitted += acc[v, k, b] if c > 0 else 0.0
                thrown += rates[v, k, b]
                if c > 0:
                    n_cells += 1
                    n_rows += c
                    bounds[b + 1] += c
            wheel_emitted[v, k] += emitted
            wheel_thrown[v, k] += thrown * elapsed
    for b in range(6):
        bounds[b + 1] += bounds[b]
    cell_mass, cell_reps = np.empty(n_cells), np.empty(n_cells, np.int64)
    rows_w, rows_mass = np.empty(n_rows, np.int64), np.empty(n_rows)
    j, r = 0, 0
    for b in range(6):
        for v in range(nv):
            for k in range(4):
                c = counts[v, k, b]
                if c > 0:
                    m = acc[v, k, b] / c
                    acc[v, k, b] = 0.0
                    cell_mass[j], cell_reps[j] = m, c
                    j += 1
                    for _ in range(c):
                        rows_w[r], rows_mass[r] = 4 * v + k, m
                        r += 1
    return cell_mass, cell_reps, rows_w, rows_mass, bounds


@jit.kernel
def add_wet_landings(pending, candidates, depth_mm, standing_mm):
    """``pending`` (k, 4) landings in standing water still in flight (time s, x m, z m, momentum kg·m/s), with
    the ``candidates`` (m, 4) whose film ``depth_mm`` (m,) is at least ``standing_mm`` appended in order (a NaN
    depth is dry): a new array (``SprayEmitter.observe_only``)."""
    k = pending.shape[0]
    wet = 0
    for j in range(candidates.shape[0]):
        if depth_mm[j] >= standing_mm:
            wet += 1
    out = np.empty((k + wet, 4))
    out[:k] = pending
    r = k
    for j in range(candidates.shape[0]):
        if depth_mm[j] >= standing_mm:
            out[r] = candidates[j]
            r += 1
    return out


@jit.kernel
def due_landings(pending, now):
    """Split ``pending`` (k, 4) landings (time s, x m, z m, momentum) at ``now`` (s): those due (time ≤ now) as
    (x, z, momentum) rows, and the rest, both in order (``SprayEmitter._pop_landings``)."""
    due = 0
    for j in range(pending.shape[0]):
        if pending[j, 0] <= now:
            due += 1
    landed = np.empty((due, 3))
    rest = np.empty((pending.shape[0] - due, 4))
    a, b = 0, 0
    for j in range(pending.shape[0]):
        if pending[j, 0] <= now:
            landed[a, 0], landed[a, 1], landed[a, 2] = pending[j, 1], pending[j, 2], pending[j, 3]
            a += 1
        else:
            rest[b] = pending[j]
            b += 1
    return landed, rest


@jit.kernel
def quantile_90(x):
    """``spawn.quantile_90``: np.quantile(x, 0.9) with linear interpolation (s), from the same order
    statistics."""
    n = x.shape[0]
    pos = 0.9 * (n - 1)
    lo = int(pos)
    hi = min(lo + 1, n - 1)
    part = np.partition(x, lo)
    upper = part[lo]
    if hi > lo:
        upper = part[hi]
        for j in range(hi + 1, n):  # the next order statistic: the least above the lo-th's slot
            if part[j] < upper:
                upper = part[j]
    return part[lo] + (pos - lo) * (upper - part[lo])
