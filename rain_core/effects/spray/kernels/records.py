"""Kernels of what a frame files: fates and lives (``settle``), the GPU records, ring horizons and road
landings (``file_records``), the accounts (``tally``), the pending landings and the horizon's percentile.
Units: m, s, kg."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit


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
def _floor_005(v):
    """Python's max(v, 0.05) (v kept unless 0.05 > v: NaN stays NaN)."""
    return 0.05 if 0.05 > v else v


@jit.kernel
def settle_horizons(t_body, t_ground, cap, speed, nd, life, fate, growth, fate_road, fate_body, fate_air, q90):
    """:func:`settle`, then each ring's horizon (s) as ``spawn._horizons`` makes it: the running 90th percentile
    of its parcels' lives ``q90`` (2,) s (droplets [:nd], mist [nd:]), updated in place for a ring with parcels
    this frame, at least 50 ms. One call instead of three. Returns (droplets' horizon, mist's); 0 for a ring
    without parcels."""
    settle(t_body, t_ground, cap, speed, nd, life, fate, growth, fate_road, fate_body, fate_air)
    n = life.shape[0]
    h_drop = 0.0
    h_mist = 0.0
    if nd > 0:
        q90[0] = 0.9 * q90[0] + 0.1 * _floor_005(quantile_90(life[:nd]))
        h_drop = _floor_005(q90[0])
    if n > nd:
        q90[1] = 0.9 * q90[1] + 0.1 * _floor_005(quantile_90(life[nd:]))
        h_mist = _floor_005(q90[1])
    return h_drop, h_mist


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


@jit.kernel
def push_rows(src, birth, death, dst, dst_birth, dst_death, head, ranges):
    """``parcels.ParcelRing.push`` of n ≤ capacity plain records: rows ``src`` (n, F) float32 with their ``birth``
    and ``death`` (s) written over the oldest slots of the ring ``dst`` (capacity, F), ``dst_birth``,
    ``dst_death`` from slot ``head`` on, wrapping once at most. The (start, count) slot ranges written into
    ``ranges`` (2, 2) int64. Returns (the new head, how many ranges, the largest death: NumPy's max, NaN if any)."""
    n = src.shape[0]
    cap = dst.shape[0]
    width = src.shape[1]
    start = head
    done = 0
    count_ranges = 0
    while done < n:
        count = min(n - done, cap - start)
        for r in range(count):
            for c in range(width):
                dst[start + r, c] = src[done + r, c]
            dst_birth[start + r] = birth[done + r]
            dst_death[start + r] = death[done + r]
        ranges[count_ranges, 0] = start
        ranges[count_ranges, 1] = count
        count_ranges += 1
        done += count
        start = (start + count) % cap
    top = death[0]
    for i in range(1, n):  # np.max: the first NaN wins
        if top != top:
            break
        d = death[i]
        if d > top or d != d:
            top = d
    return start, count_ranges, top
