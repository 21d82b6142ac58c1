"""Kernels of the drops' motion: the position columns (place_rows), forces, pinning and sliding (move_drops)
and what running drops leave on the film (run_drops). Twins: ``drop_array``/``sim._placed``, ``fast_motion``.
Units: m, s, kg, m/s."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield.constants import (
    BL_RUN_UP_M,
    CROSSWIND_GAIN,
    DROP_EVAP_KG_M_S,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    KINETIC_PIN,
    M_OBJECT_MIN,
    MU_W,
    NU_AIR,
    TRAIL_FRACTION,
    TRAIL_PARENT_MIN,
    TRAIL_SPACING_RADII,
    V_STOP_M_S,
    VISCOUS_C,
)
from rain_core.effects.windshield.drop_rows import BL, CELL, EV, GS, GT, KEY, RB, TRAIL, UP, VS, VT, A, M, Q, S, T
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.grid import GRID_CELL_M
from rain_core.effects.windshield.kernels.common import (
    _DRAG_K,
    _G0,
    _G1,
    _INF,
    _INV_MASS_PER_A3,
    _O0,
    _O1,
    _WET_PER_AREA,
    film_cell,
    inside,
)


@jit.kernel
def place_row(buf, i, w0, dw, height, g_up, g_sag):
    """``place_rows`` on row i alone (whatever its KEY): the kernels that pass over every row anyway (the motion,
    the sort) place the dirty ones on their way instead of a pass of their own over the 128-byte rows."""
    top0, top1 = _G0 - 1, _G1 - 1
    s = buf[i, S]
    t = buf[i, T]
    w = dw * t + w0
    sw = s / w
    th = t / height
    u = sw * FILM_CELLS + 0.5 * FILM_CELLS
    if u > FILM_CELLS - 0.5:
        u = FILM_CELLS - 0.5
    v = t * (FILM_CELLS / height)
    if v > FILM_CELLS - 0.5:
        v = FILM_CELLS - 0.5
    buf[i, CELL] = int(v) * FILM_CELLS + int(u)
    frac = min(max(th, 0.0), 1.0)
    buf[i, UP] = frac * (FLOW_AT_TOP - FLOW_AT_BOTTOM) + FLOW_AT_BOTTOM
    buf[i, Q] = s * 2.0 / w
    buf[i, BL] = (max(t, 0.0) + BL_RUN_UP_M) * NU_AIR
    x = (sw + 0.5) * 2.0 - 1.0
    y = th * 2.0 - 1.0
    bv = 1.0 - y * y
    dbu = x * -4.0
    buf[i, GS] = dbu / w * bv * g_sag
    g = -s * dw / (w * w) * dbu * bv
    g += (1.0 - x * x) * (y * -4.0) / height
    buf[i, GT] = g * g_sag + g_up
    k0 = min(max(int((s - _O0) / GRID_CELL_M), 0), top0)
    k1 = min(max(int((t - _O1) / GRID_CELL_M), 0), top1)
    buf[i, KEY] = k0 * _G1 + k1


@jit.kernel
def place_rows(buf, n, w0, dw, height, g_up, g_sag):
    """Write the position's columns CELL … KEY (``WindshieldSim._placed``) of the drops among rows [:n] whose KEY
    is DIRTY; ``w0``, ``dw`` the glass's width (m) at its bottom and its growth per metre up, ``height`` (m),
    ``g_up``, ``g_sag`` gravity's folded constants (m/s²). Returns how many rows it wrote."""
    done = 0
    for i in range(n):
        if buf[i, KEY] != _DIRTY:
            continue
        done += 1
        place_row(buf, i, w0, dw, height, g_up, g_sag)
    return done


@jit.kernel
def move_drops(buf, n, h, head, cross, whole, test_all, rest_test, grow, go, gcol, loss, place, w0, dw, height, g_up,
               g_sag):
    """``FastMotion._move`` over rows [:n] for a sub-step of ``h`` s in the air (``head`` along, ``cross`` across
    the glass, m/s): the air's factor EV (every drop if ``whole``, else the tested ones), forces, pinning and the
    bound RB of the tested drops (``test_all``, or RB ≥ ``rest_test``; ``grow``: the epoch's allowance), the
    viscous slide of those that move or start, then every drop's evaporation (its loss, kg, into ``loss``) and
    Newton radius. The drops that slid go to ``go`` (row indices) and ``gcol`` (6, ·): start s, t, displacement
    ds, dt (m), its length (m) and the radius at the start (m). Returns how many slid. With ``place``, the rows
    whose KEY is DIRTY are placed first (``place_row``; the glass's ``w0`` … ``g_sag`` as ``place_rows`` takes
    them): ``_flush_placed``'s pass folded into this one."""
    n_go = 0
    up = side = air_speed = 0.0
    for i in range(n):
        if place and buf[i, KEY] == _DIRTY:
            place_row(buf, i, w0, dw, height, g_up, g_sag)
        tested = test_all or buf[i, RB] >= rest_test
        if whole or tested:
            # The air over the glass (airflow.air_velocity), from the position's factors.
            if head >= 0.0:
                up = head * buf[i, UP]
                side = up * FLOW_SPREAD * buf[i, Q] + CROSSWIND_GAIN * cross
            else:
                up = head * FLOW_AT_BOTTOM
                side = abs(head * FLOW_AT_BOTTOM) * FLOW_SPREAD * buf[i, Q] + CROSSWIND_GAIN * cross
            air_speed = math.sqrt(side * side + up * up)
            buf[i, EV] = math.sqrt(1.0 + air_speed / EVAP_AIR_M_S)
        a = buf[i, A]
        m = buf[i, M]
        if tested:
            delta = 5.0 * math.sqrt(buf[i, BL] / max(air_speed, 1e-3))
            eta = min(max(HEIGHT_PER_RADIUS * a / delta, 0.0), 1.0)
            profile = 1.5 * eta - 0.5 * (eta * eta * eta)
            vs = buf[i, VS]
            vt = buf[i, VT]
            rel_s = side * profile - vs
            rel_t = up * profile - vt
            rel = math.sqrt(rel_s * rel_s + rel_t * rel_t)
            coef = _DRAG_K * (a * a) * rel
            gs = buf[i, GS]
            gt = buf[i, GT]
            f_s = m * gs + coef * rel_s
            f_t = m * gt + coef * rel_t
            fmag = math.sqrt(f_s * f_s + f_t * f_t)
            pin = GAMMA_W * 2.0 * a * HYSTERESIS
            speed = math.sqrt(vs * vs + vt * vt)
            moving = speed > 0.0
            drag = coef * rel
            if grow != 0.0:
                fmag_hi = drag * grow + fmag
                drag *= 1.0 + grow
            else:
                fmag_hi = fmag
            if moving or fmag > pin:
                buf[i, RB] = _INF
                # The sliding update.
                if moving:
                    sp = max(speed, 1e-300)
                    dir_s = vs / sp
                    dir_t = vt / sp
                else:
                    fm_safe = max(fmag, 1e-300)
                    dir_s = f_s / fm_safe
                    dir_t = f_t / fm_safe
                kp = KINETIC_PIN * pin
                damp = 1.0 + h * (VISCOUS_C * MU_W * a / m)
                nv_s = (vs + h * ((f_s - kp * dir_s) / m)) / damp
                nv_t = (vt + h * ((f_t - kp * dir_t) / m)) / damp
                if moving and (
                    nv_s * vs + nv_t * vt <= 0.0
                    or (math.sqrt(nv_s * nv_s + nv_t * nv_t) < V_STOP_M_S and fmag < pin)
                ):
                    nv_s = 0.0
                    nv_t = 0.0
                ds = h * nv_s
                dt = h * nv_t
                s0 = buf[i, S]
                t0 = buf[i, T]
                go[n_go] = i
                gcol[0, n_go] = s0
                gcol[1, n_go] = t0
                gcol[2, n_go] = ds
                gcol[3, n_go] = dt
                gcol[4, n_go] = math.sqrt(ds * ds + dt * dt)
                gcol[5, n_go] = a
                n_go += 1
                buf[i, VS] = nv_s
                buf[i, VT] = nv_t
                buf[i, S] = s0 + ds
                buf[i, T] = t0 + dt
                buf[i, KEY] = _DIRTY
            else:
                buf[i, RB] = max(max(fmag_hi, m * math.sqrt(gs * gs + gt * gt)), drag) / pin
        # Slow evaporation, and the radius after it (one Newton step from the last radius).
        lo = DROP_EVAP_KG_M_S * a * buf[i, EV] * h
        if lo > m:
            lo = m
        loss[i] = lo
        m -= lo
        buf[i, M] = m
        ra2 = a * a
        buf[i, A] = a - (ra2 * a - m * _INV_MASS_PER_A3) / (3.0 * ra2)
    return n_go


@jit.kernel
def run_drops(buf, n_go, go, gcol, flat, areas, total, room, w0, dw, height, ridx, rcol, wcol):
    """``FastMotion._run`` on the drops that slid (``move_drops``' ``go``, ``gcol``): the running ones (step > 0)
    whose path's midpoint is on the glass take up the film (``flat``, kg per cell; ``areas`` m² per cell;
    ``total`` a zeroed scratch per cell, left zeroed) in their path, lay a wet line and drop trail droplets; of
    these, the first ``room`` heavy enough become drops, the others film. Writes the running drops' rows to
    ``ridx`` and their trails to ``rcol`` (5, ·: s0, t0, s1, t1, radius m), the droplets that become drops to
    ``wcol`` (3, ·: s, t m, mass kg). Returns (running drops, new drops). The caller then sets the radius of the
    running drops from their mass (a cube root) and appends the new drops."""
    sel = np.empty(n_go, np.int64)  # the running drops on the glass: their place in go, film cell, share
    cell = np.empty(n_go, np.int64)
    frac = np.empty(n_go)
    k = 0
    for g in range(n_go):
        sl = gcol[4, g]
        if not sl > 0.0:
            continue
        ms = gcol[0, g] + 0.5 * gcol[2, g]
        mt = gcol[1, g] + 0.5 * gcol[3, g]
        if not inside(ms, mt, w0, dw, height):
            continue
        c = film_cell(ms, mt, w0, dw, height)
        f = 2.0 * gcol[5, g] * sl / areas[c]
        total[c] += f
        sel[k] = g
        cell[k] = c
        frac[k] = f
        k += 1
    if k == 0:
        return 0, 0
    # What each takes of its cell's film (the film before any of them took; a cell asked for more than it has
    # gives each its share).
    take = np.empty(k)
    for r in range(k):
        tot = total[cell[r]]
        scale = 1.0 / max(tot, 1e-300) if tot > 1.0 else 1.0
        take[r] = flat[cell[r]] * frac[r] * scale
    for r in range(k):
        flat[cell[r]] -= take[r]
        total[cell[r]] = 0.0
    for c in range(flat.shape[0]):
        if flat[c] < 0.0:
            flat[c] = 0.0
    for r in range(k):
        g = sel[r]
        i = go[g]
        mass = buf[i, M]
        wet = min(_WET_PER_AREA * (2.0 * gcol[5, g] * gcol[4, g]), 0.1 * mass)
        flat[cell[r]] += wet
        buf[i, M] = mass + (take[r] - wet)
    # Trail droplets: one every TRAIL_SPACING_RADII radii of run, behind the drop, from heavy drops only.
    drops = np.empty((4, 4 * k))  # s, t (m), mass (kg) and parent row of each droplet on the glass
    n_w = 0
    for r in range(k):
        g = sel[r]
        i = go[g]
        s0, t0, ds, dt, sl, a = gcol[0, g], gcol[1, g], gcol[2, g], gcol[3, g], gcol[4, g], gcol[5, g]
        es = s0 + ds
        et = t0 + dt
        ridx[r] = i
        rcol[0, r] = s0
        rcol[1, r] = t0
        rcol[2, r] = es
        rcol[3, r] = et
        rcol[4, r] = a
        spacing = TRAIL_SPACING_RADII * a
        run = buf[i, TRAIL] + sl
        kk = int(min(math.floor(run / spacing), 4.0))
        mass = buf[i, M]
        if mass < TRAIL_PARENT_MIN:
            kk = 0
        run -= kk * spacing
        buf[i, TRAIL] = min(run, spacing)
        m_t = TRAIL_FRACTION * mass
        for within in range(kk):
            gap = (1.3 + TRAIL_SPACING_RADII * within) * a
            gap /= sl
            ws = es - ds * gap
            wt = et - dt * gap
            if inside(ws, wt, w0, dw, height):
                drops[0, n_w] = ws
                drops[1, n_w] = wt
                drops[2, n_w] = m_t
                drops[3, n_w] = i
                n_w += 1
    n_drop = 0
    for w in range(n_w):
        m_t = drops[2, w]
        buf[int(drops[3, w]), M] -= m_t
    for w in range(n_w):
        m_t = drops[2, w]
        if w < room and m_t >= M_OBJECT_MIN:
            wcol[0, n_drop] = drops[0, w]
            wcol[1, n_drop] = drops[1, w]
            wcol[2, n_drop] = m_t
            n_drop += 1
        else:
            flat[film_cell(drops[0, w], drops[1, w], w0, dw, height)] += m_t
    return k, n_drop
