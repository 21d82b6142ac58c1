"""Compiled kernels of the windshield's drop simulation (rain_core.jit): each replaces a chain of NumPy calls of
the fast path (``sim.WindshieldSim``) with one loop over the drop rows (``drop_rows``: one row a drop of the
(capacity, COLS) float64 array ``buf``; only rows [:n] are drops).

Their NumPy twins stay the fallback and the oracle: ``DropArray._flush_placed`` / ``WindshieldSim._placed``
(:func:`place_rows`), ``FastMotion._move`` (:func:`move_drops`) and ``_run`` (:func:`run_drops`),
``FastMerging._merge_moves`` with ``grid.PairFinder`` (:func:`merge_drops`), ``FastWiping._sweep``'s drops, film
and off-glass bead (:func:`sweep_blades`), ``WindshieldSim._arrive_fast`` (:func:`sample_arrivals`,
:func:`land_arrivals`) and ``_give_to_drops`` (:func:`drops_in_cells`, :func:`give_to_drops`). The same operations
in the same order on the same values, so the results are the twins' bit for bit (cube roots and the sums that NumPy
adds pairwise stay in NumPy, done by the caller on the kernels' outputs), but for the blade's angle to a drop:
libm's atan2 may differ from NumPy's by an ulp, which flips a drop's sweep only within an ulp of the blade's edge.
Random numbers are drawn by the caller, in the twins' order. Units: m, s, kg, m/s, rad.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BL_RUN_UP_M,
    BLADE_HALF_WIDTH_M,
    CROSSWIND_GAIN,
    DRAG_CD,
    DROP_EVAP_KG_M_S,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    FRONTAL_PER_RADIUS2,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    KINETIC_PIN,
    M_OBJECT_MIN,
    MERGE_CELLS_MAX,
    MERGE_PAIRS_MAX,
    MU_W,
    NU_AIR,
    SPLASH_MAX,
    SPLASH_SPEED_M_S,
    TRAIL_FILM_M,
    TRAIL_FRACTION,
    TRAIL_PARENT_MIN,
    TRAIL_SPACING_RADII,
    V_STOP_M_S,
    VISCOUS_C,
    VOLUME_PER_RADIUS3,
)
from rain_core.effects.windshield.drop_rows import BL, CELL, EV, GS, GT, KEY, RB, TRAIL, UP, VS, VT, A, M, Q, S, T
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.grid import _BOX_MARGIN_CELLS, _GRID_ORIGIN, GRID_CELL_M, NEAR_CELL_M, _grid_shape
from rain_core.physics import RHO_AIR, RHO_WATER

# The twins' constants, folded in the same order (so to the same bits).
_DRAG_K = 0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2
_INV_MASS_PER_A3 = 1.0 / (RHO_WATER * VOLUME_PER_RADIUS3)
_WET_PER_AREA = RHO_WATER * TRAIL_FILM_M
_KG_PER_MM3 = RHO_WATER * math.pi / 6.0 * 1e-9  # a raindrop's mass over its diameter (mm) cubed
_SPLASH_LO, _SPLASH_HI = SPLASH_SPEED_M_S
_SLICES = 1024  # sample_arrivals: slices of the CDF, each starting a short walk to a sample's interval
_O0, _O1 = float(_GRID_ORIGIN[0]), float(_GRID_ORIGIN[1])
_G0, _G1 = _grid_shape(GRID_CELL_M)
_N0, _N1 = _grid_shape(NEAR_CELL_M)
_P1 = _N1 + 2  # PairFinder's padded near grid: a border of empty cells
NEAR_CELLS = (_N0 + 2) * _P1  # cells of the scratch tables merge_drops needs (the padded grid is the larger)
_INF = math.inf


@jit.kernel
def inside(s, t, w0, dw, height):
    """Whether the point (s, t) m lies on the glass (``WindshieldSim._inside``)."""
    return t >= 0.0 and t <= height and abs(s) <= 0.5 * (w0 + dw * t)


@jit.kernel
def film_cell(s, t, w0, dw, height):
    """The film cell (flat index) under the point (s, t) m (``WindshieldSim._cells``)."""
    u = s / (w0 + dw * t) * FILM_CELLS + 0.5 * FILM_CELLS
    if u > FILM_CELLS - 0.5:
        u = FILM_CELLS - 0.5
    v = t * (FILM_CELLS / height)
    if v > FILM_CELLS - 0.5:
        v = FILM_CELLS - 0.5
    return int(v) * FILM_CELLS + int(u)


@jit.kernel
def place_rows(buf, n, w0, dw, height, g_up, g_sag):
    """Write the position's columns CELL … KEY (``WindshieldSim._placed``) of the drops among rows [:n] whose KEY
    is DIRTY; ``w0``, ``dw`` the glass's width (m) at its bottom and its growth per metre up, ``height`` (m),
    ``g_up``, ``g_sag`` gravity's folded constants (m/s²). Returns how many rows it wrote."""
    done = 0
    top0, top1 = _G0 - 1, _G1 - 1
    for i in range(n):
        if buf[i, KEY] != _DIRTY:
            continue
        done += 1
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
    return done


@jit.kernel
def move_drops(buf, n, h, head, cross, whole, test_all, rest_test, grow, go, gcol, loss):
    """``FastMotion._move`` over rows [:n] for a sub-step of ``h`` s in the air (``head`` along, ``cross`` across
    the glass, m/s): the air's factor EV (every drop if ``whole``, else the tested ones), forces, pinning and the
    bound RB of the tested drops (``test_all``, or RB ≥ ``rest_test``; ``grow``: the epoch's allowance), the
    viscous slide of those that move or start, then every drop's evaporation (its loss, kg, into ``loss``) and
    Newton radius. The drops that slid go to ``go`` (row indices) and ``gcol`` (6, ·): start s, t, displacement
    ds, dt (m), its length (m) and the radius at the start (m). Returns how many slid."""
    n_go = 0
    up = side = air_speed = 0.0
    for i in range(n):
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


@jit.kernel
def _root(parent, x):
    """The root of x in the union-find ``parent`` (path halving: a parent is never larger than its child)."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@jit.kernel
def _motion(x, buf, gcol, gidx):
    """Drop x's start s, t and displacement ds, dt (m) this step: ``gcol``'s if it slid (``gidx``), else its row."""
    g = gidx[x]
    if g >= 0:
        return gcol[0, g], gcol[1, g], gcol[2, g], gcol[3, g]
    return buf[x, S], buf[x, T], 0.0, 0.0


@jit.kernel
def _touch(x, y, buf, gcol, gidx):
    """Whether drops x and y touched during the step: the closest approach of their straight motions within the
    sum of their radii (merging.Merging's test, as FastMerging computes it)."""
    s0x, t0x, dsx, dtx = _motion(x, buf, gcol, gidx)
    s0y, t0y, dsy, dty = _motion(y, buf, gcol, gidx)
    ps = s0x - s0y
    pt = t0x - t0y
    qs = dsx - dsy
    qt = dtx - dty
    dd = max(qs * qs + qt * qt, 1e-300)
    tau = min(max(-(ps * qs + pt * qt) / dd, 0.0), 1.0)
    ps += tau * qs
    pt += tau * qt
    rr = buf[x, A] + buf[y, A]
    return ps * ps + pt * pt <= rr * rr


@jit.kernel
def _join(x, y, parent, nodes, k):
    """Union of x and y (the smaller root wins), their entries made on first sight (``nodes``: those seen, ``k``
    of them); returns the new count."""
    for z in (x, y):
        if parent[z] < 0:
            parent[z] = z
            nodes[k] = z
            k += 1
    rx = _root(parent, x)
    ry = _root(parent, y)
    if rx < ry:
        parent[ry] = rx
    elif ry < rx:
        parent[rx] = ry
    return k


@jit.kernel
def merge_drops(buf, n, n_moved, fresh, n_go, go, gcol, gidx, active, parent, nodes, mark, sums, count, head, nxt,
                owner, ekey, out):
    """``FastMerging._merge_moves`` (with ``grid.PairFinder``'s search) on rows [:n]: of the first ``n_moved``,
    the ``n_go`` drops in ``go`` moved as ``gcol`` says (``move_drops``), the others stayed. Drops that touched
    during the step join into the smallest row of their group (mass-weighted means of S … TRAIL; the caller sets
    its radius from its mass, a cube root); ``fresh`` (bool) is updated as the twin does.

    Candidates as PairFinder finds them, with its work budget: all drops reaching ≤ NEAR_CELL_M / 2 from the 3 × 3
    near cells around each active one (past MERGE_PAIRS_MAX candidates the remaining lookups are deferred: those
    drops stay fresh); otherwise the drops sharing a near cell of their boxes. If those boxes pass the budget
    (MERGE_CELLS_MAX cells, MERGE_PAIRS_MAX pairs) nothing is changed and the result is -1: the caller runs the
    twin (its far grid). Scratch over the rows: ``gidx``, ``parent`` int64 (-1, left so), ``active`` bool,
    ``nodes`` int64, ``mark`` bool (False, left so), ``sums`` (7, ·); per near cell ``count`` (0) and ``head``
    (-1) int64, left so; per box cell ``nxt``, ``owner``, ``ekey`` int64. Writes the groups' rows to ``out``:
    roots, then the rows joined into them (ascending). Returns (status, roots, joined)."""
    if n < 2:
        for x in range(n):
            fresh[x] = False
        return 0, 0, 0
    for g in range(n_go):
        gidx[go[g]] = g
    any_active = False
    all_near = True
    for x in range(n):
        g = gidx[x]
        act = fresh[x] and x < n_moved
        reach = buf[x, A]
        if g >= 0:
            act = act or gcol[2, g] != 0.0 or gcol[3, g] != 0.0
            reach += 0.5 * gcol[4, g]
        active[x] = act
        any_active = any_active or act
        all_near = all_near and reach <= 0.5 * NEAR_CELL_M
    status = 0
    k = 0  # drops in a touching pair
    n_def = 0  # deferred lookups (their rows, in out's tail)
    if any_active:
        inv = 1.0 / NEAR_CELL_M
        if all_near:
            # Near grid (PairFinder.pairs): every drop in the cell of its centre; each active one looks in the 3 × 3
            # cells around its own, in row order, until the budget runs out.
            for x in range(n):
                g = gidx[x]
                ms, mt = buf[x, S], buf[x, T]
                if g >= 0:
                    ms = gcol[0, g] + 0.5 * gcol[2, g]
                    mt = gcol[1, g] + 0.5 * gcol[3, g]
                k0 = min(max(int((ms - _O0) * inv), 0), _N0 - 1)
                k1 = min(max(int((mt - _O1) * inv), 0), _N1 - 1)
                key = k0 * _P1 + (k1 + _P1 + 1)
                ekey[x] = key
                nxt[x] = head[key]
                head[key] = x
                count[key] += 1
            cum = 0
            for q in range(n):
                if not active[q]:
                    continue
                late = False
                for di in range(-1, 2):
                    for dj in range(-1, 2):
                        cell = ekey[q] + di * _P1 + dj
                        c = count[cell]
                        if c == 0:
                            continue
                        cum += c
                        if cum > MERGE_PAIRS_MAX:
                            late = True
                            continue
                        f = head[cell]
                        while f >= 0:
                            if f != q and q < n_moved and f < n_moved and _touch(q, f, buf, gcol, gidx):
                                k = _join(q, f, parent, nodes, k)
                            f = nxt[f]
                if late:
                    out[n - 1 - n_def] = q
                    n_def += 1
            for x in range(n):
                head[ekey[x]] = -1
                count[ekey[x]] = 0
        else:
            # Boxes (PairFinder._box_pairs): every drop in each near cell its box (centre ± reach) touches; an active
            # drop's candidates are the drops sharing a cell with it.
            total = 0
            n_pairs = 0
            cap = min(MERGE_CELLS_MAX, nxt.shape[0])
            for x in range(n):
                g = gidx[x]
                ms, mt, reach = buf[x, S], buf[x, T], buf[x, A]
                if g >= 0:
                    ms = gcol[0, g] + 0.5 * gcol[2, g]
                    mt = gcol[1, g] + 0.5 * gcol[3, g]
                    reach += 0.5 * gcol[4, g]
                cs = (ms - _O0) * inv
                ct = (mt - _O1) * inv
                rc = reach * inv + _BOX_MARGIN_CELLS
                lo0 = int(min(max(cs - rc, 0.0), _N0 - 1.0))
                lo1 = int(min(max(ct - rc, 0.0), _N1 - 1.0))
                hi0 = int(min(max(cs + rc, 0.0), _N0 - 1.0))
                hi1 = int(min(max(ct + rc, 0.0), _N1 - 1.0))
                if total + (hi0 - lo0 + 1) * (hi1 - lo1 + 1) > cap:
                    status = -1
                    break
                for c0 in range(lo0, hi0 + 1):
                    for c1 in range(lo1, hi1 + 1):
                        key = c0 * _N1 + c1
                        ekey[total] = key
                        owner[total] = x
                        nxt[total] = head[key]
                        head[key] = total
                        n_pairs += count[key]
                        count[key] += 1
                        total += 1
            if n_pairs > MERGE_PAIRS_MAX:
                status = -1
            if status == 0:
                for e in range(total):
                    x = owner[e]
                    if not active[x] or x >= n_moved:
                        continue
                    f = head[ekey[e]]
                    while f >= 0:
                        y = owner[f]
                        # A pair of active drops is found from the smaller one's side.
                        if y != x and y < n_moved and not (active[y] and y < x) and _touch(x, y, buf, gcol, gidx):
                            k = _join(x, y, parent, nodes, k)
                        f = nxt[f]
            for e in range(total):
                head[ekey[e]] = -1
                count[ekey[e]] = 0
    for g in range(n_go):
        gidx[go[g]] = -1
    if status < 0:
        return -1, 0, 0
    # The twin's bookkeeping of which drops the next merge test looks at.
    for x in range(n):
        fresh[x] = x >= n_moved
    for d in range(n_def):
        fresh[out[n - 1 - d]] = True
    if k == 0:
        return 0, 0, 0
    # Groups: each joins into its smallest row, the mass-weighted means added in row order (as the twin's
    # bincount and add.at add them).
    members = np.sort(nodes[:k])
    n_roots = 0
    for x in members:
        r = _root(parent, x)
        parent[x] = r
        if r != x and not mark[r]:
            mark[r] = True
            n_roots += 1
    n_gone = 0
    r_at = 0
    for x in members:
        r = parent[x]
        wm = buf[x, M]
        if r == x:
            out[r_at] = x
            r_at += 1
            for c in range(TRAIL + 1):
                sums[c, x] = 0.0 + buf[x, c] * wm
            sums[6, x] = 0.0 + wm
        else:
            out[n_roots + n_gone] = x
            n_gone += 1
            for c in range(TRAIL + 1):
                sums[c, r] += buf[x, c] * wm
            sums[6, r] += wm
    for q in range(n_roots):
        r = out[q]
        mark[r] = False
        g_mass = sums[6, r]
        for c in range(TRAIL + 1):
            buf[r, c] = sums[c, r] / g_mass
        buf[r, M] = g_mass
        buf[r, KEY] = _DIRTY
        buf[r, RB] = _INF
        fresh[r] = True
    for x in members:
        parent[x] = -1
    return 0, n_roots, n_gone


@jit.kernel
def sweep_blades(buf, n, par, gone, beads, flat, areas, order, phi, off, bins, bin_r, per_area, w0, dw, height,
                 offv, offk):
    """``FastWiping._sweep`` for one stroke segment, but the drops' removal and the stroke's end: each blade b
    that moves (``par[b]``, per blade: moving, has a wedge, the wedge's two half-planes (normal s, t and bound),
    lo, hi (rad), up (1 when moving towards +angle), pivot s, t, r_inner, r_outer (m), capacity (kg a bin), cos and
    sin of its angle at the end) gathers the drops among rows [:n] it passes over (marked in ``gone``, bool, the
    first blade first) and the film cells whose centres it passes (``order``/``phi``: the cells within its radii
    sorted by angle, blade b's from ``off[b]`` to ``off[b + 1]``; ``bins`` (blade, cell) its bead bin over each)
    into its bead (``beads``, kg a bin), leaves a residue of ``per_area`` kg/m² paid from the bead and leaks what
    passes the capacity; then every blade's bins off the glass (``bin_r``: bin radii, m) are emptied into ``offv``
    (blade, bin), ``offk`` their count (the caller adds them to ``wiped``). Returns how many drops are gone."""
    nb = par.shape[0]
    n_gone = 0
    for i in range(n):
        gone[i] = False
        s = buf[i, S]
        t = buf[i, T]
        for b in range(nb):
            p = par[b]
            if p[0] == 0.0:
                continue
            if p[1] != 0.0 and not (s * p[2] + t * p[3] >= p[4] and s * p[5] + t * p[6] >= p[7]):
                continue
            rel_s = s - p[11]
            rel_t = t - p[12]
            r = math.hypot(rel_s, rel_t)
            ac = buf[i, A]
            if not (r + ac >= p[13] and r - ac <= p[14]):
                continue
            ang = math.atan2(rel_t, rel_s)
            margin = (ac + BLADE_HALF_WIDTH_M) / max(r, 1e-3)
            if p[10] != 0.0:
                swept = ang >= p[8] and ang <= p[9] + margin
            else:
                swept = ang >= p[8] - margin and ang <= p[9]
            if swept:
                k = min(max(int((r - p[13]) / (p[14] - p[13]) * BEAD_BINS), 0), BEAD_BINS - 1)
                beads[b, k] += buf[i, M]
                gone[i] = True
                n_gone += 1
                break
    for b in range(nb):
        p = par[b]
        bead = beads[b]
        if p[0] != 0.0:
            _sweep_film(flat, areas, bead, order, phi, off[b], off[b + 1], bins[b], p[8], p[9], per_area, p[15])
        offk[b] = 0
        nonzero = False
        for k in range(BEAD_BINS):
            nonzero = nonzero or bead[k] != 0.0
        if not nonzero:
            continue
        for k in range(BEAD_BINS):
            if not inside(p[11] + bin_r[b, k] * p[16], p[12] + bin_r[b, k] * p[17], w0, dw, height):
                offv[b, offk[b]] = bead[k]
                offk[b] += 1
                bead[k] = 0.0
    return n_gone


@jit.kernel
def _sweep_film(flat, areas, bead, order, phi, start, end, bins, lo, hi, per_area, cap):
    """``FastWiping._sweep_film`` of one blade between angles lo and hi (rad): see ``sweep_blades``."""
    cells = np.sort(order[start + np.searchsorted(phi[start:end], lo, "left") :
                          start + np.searchsorted(phi[start:end], hi, "right")])
    if len(cells) == 0:
        return
    for c in cells:
        bead[bins[c]] += flat[c]
        flat[c] = 0.0
    # The rubber leaves a thin residue where it pushed water, paid from the bead.
    need = np.zeros(BEAD_BINS)
    n_cells = np.zeros(BEAD_BINS, np.int64)
    for c in cells:
        need[bins[c]] += per_area * areas[c]
        n_cells[bins[c]] += 1
    scale = np.zeros(BEAD_BINS)
    for k in range(BEAD_BINS):
        has = need[k] > 0.0 if per_area > 0.0 else n_cells[k] > 0
        if has:
            scale[k] = min(1.0, bead[k] / max(need[k], 1e-300))
    paid = np.zeros(BEAD_BINS)
    for c in cells:
        leave = per_area * areas[c] * scale[bins[c]]
        flat[c] += leave
        paid[bins[c]] += leave
    leak = False
    for k in range(BEAD_BINS):
        bead[k] -= paid[k]
        has = need[k] > 0.0 if per_area > 0.0 else n_cells[k] > 0
        # Over capacity the bead leaks past the rubber: spread the excess over the cells just swept.
        scale[k] = max(bead[k] - cap, 0.0) if has else 0.0
        leak = leak or scale[k] != 0.0
    if leak:
        area_bin = np.zeros(BEAD_BINS)
        for c in cells:
            area_bin[bins[c]] += areas[c]
        for c in cells:
            flat[c] += scale[bins[c]] * (areas[c] / area_bin[bins[c]])
        for k in range(BEAD_BINS):
            bead[k] -= scale[k]
    for k in range(BEAD_BINS):
        if bead[k] < 0.0:
            bead[k] = 0.0


@jit.kernel
def sample_arrivals(u, n, cdf, coef, total, w0, dw, height, imp, cells, obj):
    """``WindshieldSim._arrive_fast``'s draws made arrivals: ``n`` raindrops from the uniform numbers ``u`` (3n:
    the size's quantile, then across and up the glass), the size law's CDF ``cdf`` over the diameter grid and
    ``coef`` (ArrivalTable._coef: per grid interval the diameter's slope, the CDF, the diameter, the closing
    speed's slope and the closing speed), ``total`` the CDF's end; the glass's width ``w0`` (m) at its bottom,
    growing by ``dw`` per metre up, ``height`` (m). Writes ``imp`` rows s, t (m), diameter (mm), splash
    fraction, mass and kept mass (kg), the film cell of each to ``cells`` and the rows of those that are
    objects (kept mass ≥ M_OBJECT_MIN) to ``obj``; returns how many are."""
    dwh = dw * height
    n_cdf = len(cdf)
    last = n_cdf - 2
    # ArrivalTable.sample's interval: the last grid point at or below x (cdf.searchsorted(x, "right") − 1), found
    # by a walk from the interval at the left edge of x's slice of the CDF (a table of _SLICES, made per call):
    # the walk goes down as well as up, so the answer is the search's whatever the rounding of the slice.
    slice_j = np.empty(_SLICES, np.int64)
    j = 0
    for b in range(_SLICES):
        edge = b * (total / _SLICES)
        while j + 1 < n_cdf and cdf[j + 1] <= edge:
            j += 1
        slice_j[b] = j
    n_obj = 0
    for k in range(n):
        x = u[k] * total
        j = slice_j[min(int(u[k] * _SLICES), _SLICES - 1)]
        while j > 0 and cdf[j] > x:
            j -= 1
        while j + 1 < n_cdf and cdf[j + 1] <= x:
            j += 1
        j = min(j, last)
        d = (x - coef[j, 1]) * coef[j, 0] + coef[j, 2]
        closing = (d - coef[j, 2]) * coef[j, 3] + coef[j, 4]
        m = _KG_PER_MM3 * (d * d * d)
        # GlassGeometry.sample_uniform: uniform over the trapezoid.
        q = u[n + k] * (w0 + 0.5 * dwh)
        up = 2.0 * q / (w0 + math.sqrt(w0 * w0 + 2.0 * dwh * q)) if dwh != 0 else q / w0
        t = min(max(up, 0.0), 1.0) * height
        s = (u[2 * n + k] - 0.5) * (w0 + dw * t)
        splash = min(max((closing - _SPLASH_LO) / (_SPLASH_HI - _SPLASH_LO), 0.0), 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        imp[0, k] = s
        imp[1, k] = t
        imp[2, k] = d
        imp[3, k] = splash
        imp[4, k] = m
        imp[5, k] = keep
        cells[k] = film_cell(s, t, w0, dw, height)
        if keep >= M_OBJECT_MIN:
            obj[n_obj] = k
            n_obj += 1
    return n_obj


@jit.kernel
def land_arrivals(flat, acc, cells, imp, n, obj, n_obj, room, placed):
    """What of ``sample_arrivals``' arrivals goes to the film (``flat``, kg per cell): all but the kept mass of
    the first ``room`` objects (``obj``) and of the others ``placed`` (bool, joined to a drop); written to
    ``imp`` row 6 and added per cell (``acc``: a zeroed scratch per cell, left zeroed) as the twin's bincount."""
    for k in range(n):
        imp[6, k] = 1.0  # (until below: 0 where it landed as a drop or on one)
    for q in range(n_obj):
        if q < room or placed[q - room]:
            imp[6, obj[q]] = 0.0
    for k in range(n):
        to_film = imp[4, k] - (imp[5, k] if imp[6, k] == 0.0 else 0.0)
        imp[6, k] = to_film
        acc[cells[k]] += to_film
    for c in range(flat.shape[0]):
        flat[c] += acc[c]
        acc[c] = 0.0


@jit.kernel
def drops_in_cells(buf, n, any_dirty, w0, dw, height, cells, mark, per_cell, start, hits, members, c_out, first_out):
    """For ``WindshieldSim._give_to_drops``: the drops among rows [:n] in each of the film ``cells`` (flat
    indices), grouped by cell in row order into ``members``; per query its cell's count ``c_out`` and where its
    group starts ``first_out``. The film cell of a row is its CELL column, or for a row placed this sub-step (KEY
    DIRTY; only looked at if ``any_dirty``) computed. ``mark``, ``per_cell``, ``start``: zeroed scratch per cell,
    left zeroed; ``hits`` (2, ·) int64 scratch over the rows."""
    k = len(cells)
    for q in range(k):
        mark[cells[q]] = 1
    m = 0  # the rows in a marked cell, in order, and their cells
    for i in range(n):
        if any_dirty and buf[i, KEY] == _DIRTY:
            c = film_cell(buf[i, S], buf[i, T], w0, dw, height)
        else:
            c = int(buf[i, CELL])
        if mark[c]:
            per_cell[c] += 1
            hits[0, m] = i
            hits[1, m] = c
            m += 1
    at = 0
    for q in range(k):
        c = cells[q]
        if mark[c] == 1:
            mark[c] = 2
            start[c] = at
            at += per_cell[c]
        c_out[q] = per_cell[c]
        first_out[q] = start[c]
    for h in range(m):
        c = hits[1, h]
        members[start[c]] = hits[0, h]
        start[c] += 1
    for q in range(k):
        c = cells[q]
        mark[c] = 0
        per_cell[c] = 0
        start[c] = 0


@jit.kernel
def give_to_drops(buf, fresh, members, first, c, draw, mass, picks):
    """Add each ``mass`` (kg) whose cell has drops (``c`` > 0) to the drop ``draw`` (its random index among them:
    ``drops_in_cells``' ``members`` from ``first``), in order; the drop is tested again (RB) and fresh. Writes the
    rows to ``picks``; returns how many. The caller sets their radius from their mass."""
    n_p = 0
    for q in range(len(c)):
        if c[q] > 0:
            i = members[first[q] + draw[n_p]]
            buf[i, M] += mass[q]
            buf[i, RB] = _INF
            fresh[i] = True
            picks[n_p] = i
            n_p += 1
    return n_p


@jit.kernel
def compact_rows(buf, fresh, n, drop):
    """``DropArray._keep``: remove the rows [:n] marked in ``drop`` (bool), the others keeping their order (and
    their ``fresh`` flag); returns the new count."""
    k = 0
    for i in range(n):
        if drop[i]:
            continue
        if k != i:
            buf[k] = buf[i]
            fresh[k] = fresh[i]
        k += 1
    return k


@jit.kernel
def shed_rows(buf, fresh, n, test_all, gone, flat, w0, dw, height, drop, shed_m):
    """``WindshieldSim._shed_outside``: of rows [:n], those off the glass (every one if ``test_all``, else those
    placed this sub-step: KEY DIRTY) are shed (their masses, kg, in row order into ``shed_m``), those below half
    the object size become film (``flat``, kg per cell) where they are, and the rows ``gone`` (joined into others
    by the merge) go too: one compaction. ``drop``: bool scratch over the rows. Returns (new count, shed)."""
    for i in range(n):
        drop[i] = False
    for g in gone:
        drop[g] = True
    n_shed = 0
    for i in range(n):
        if drop[i]:
            continue
        if (test_all or buf[i, KEY] == _DIRTY) and not inside(buf[i, S], buf[i, T], w0, dw, height):
            shed_m[n_shed] = buf[i, M]
            n_shed += 1
            drop[i] = True
    for i in range(n):
        if not drop[i] and buf[i, M] < 0.5 * M_OBJECT_MIN:
            flat[film_cell(buf[i, S], buf[i, T], w0, dw, height)] += buf[i, M]
            drop[i] = True
    return compact_rows(buf, fresh, n, drop), n_shed


@jit.kernel
def sort_rows(buf, fresh, n, hist, order, tmp, tmp_fresh):
    """``DropArray._sort_drops`` (after the position columns are written): rows [:n] in stable order of their
    merge-grid KEY (integers below 2^18: two 9-bit passes of a radix sort), only the span of rows that change
    places rewritten. ``hist``: int64 scratch of 512, ``order`` int64 scratch of 4n, ``tmp`` (rows) and
    ``tmp_fresh`` scratch of the shapes of ``buf`` and ``fresh``. Returns 0 (in order already), 1 (sorted in
    place) or 2 (most rows move: the sorted rows [:n] are in ``tmp`` and ``tmp_fresh``, for the caller to swap
    with ``buf`` and ``fresh``: one pass over the rows instead of two)."""
    ordered = True
    for i in range(1, n):
        if buf[i, KEY] < buf[i - 1, KEY]:
            ordered = False
            break
    if ordered:
        return 0
    keys = order[2 * n : 3 * n]
    keys2 = order[3 * n : 4 * n]
    src = order[:n]
    dst = order[n : 2 * n]
    for i in range(n):
        keys[i] = int(buf[i, KEY])
    # Pass 1: by the low 9 bits, from row order (stable).
    hist[:] = 0
    for i in range(n):
        hist[keys[i] & 511] += 1
    at = 0
    for b in range(512):
        c = hist[b]
        hist[b] = at
        at += c
    for i in range(n):
        b = keys[i] & 511
        dst[hist[b]] = i
        keys2[hist[b]] = keys[i]
        hist[b] += 1
    # Pass 2: by the high bits, keeping pass 1's order within each.
    hist[:] = 0
    for i in range(n):
        hist[keys2[i] >> 9] += 1
    at = 0
    for b in range(512):
        c = hist[b]
        hist[b] = at
        at += c
    for i in range(n):
        b = keys2[i] >> 9
        src[hist[b]] = dst[i]
        hist[b] += 1
    lo = 0
    while src[lo] == lo:
        lo += 1
    hi = n
    while src[hi - 1] == hi - 1:
        hi -= 1
    cols = buf.shape[1]
    if 2 * (hi - lo) > n:
        # Most rows move: all of them are written in order into tmp once, and the caller swaps the arrays.
        for j in range(n):
            r = src[j]
            for c in range(cols):
                tmp[j, c] = buf[r, c]
            tmp_fresh[j] = fresh[r]
        return 2
    for j in range(lo, hi):
        r = src[j]
        for c in range(cols):
            tmp[j, c] = buf[r, c]
        tmp_fresh[j] = fresh[r]
    for j in range(lo, hi):
        for c in range(cols):
            buf[j, c] = tmp[j, c]
        fresh[j] = tmp_fresh[j]
    return 1


@jit.kernel
def evaporate_film(flat, evap, loss, bead_mass, thick):
    """``WindshieldSim._film_step``'s drying: each cell of ``flat`` (kg) loses its ``evap`` (kg this sub-step),
    at most what it has (into ``loss``); the cells then above ``bead_mass`` (kg) go to ``thick`` in order.
    Returns how many."""
    k = 0
    for c in range(flat.shape[0]):
        lo = min(flat[c], evap[c])
        loss[c] = lo
        flat[c] -= lo
        if flat[c] > bead_mass[c]:
            thick[k] = c
            k += 1
    return k


@jit.kernel
def film_drying(head, cross, cell_up, cell_q, areas, evap):
    """``WindshieldSim._prepare``'s drying of the film: per cell (factors ``cell_up``, ``cell_q`` of its centre,
    area ``areas`` m²) the air over it for ``head`` along and ``cross`` across the glass (m/s; airflow's formula)
    and the film's evaporation in it, kg/s for a wet cell, into ``evap``."""
    for c in range(evap.shape[0]):
        up = head * cell_up[c] if head >= 0.0 else head * FLOW_AT_BOTTOM
        side = abs(up) * FLOW_SPREAD * cell_q[c] + CROSSWIND_GAIN * cross
        air = math.sqrt(side * side + up * up)
        evap[c] = FILM_EVAP_KG_M2_S * (1.0 + air / EVAP_AIR_M_S) * areas[c]


@jit.kernel
def sensor_masses(buf, n, s_lo, s_hi, t_lo, t_hi, out):
    """The masses (kg) of the drops among rows [:n] inside the rain sensor's box (s, t within the bounds, m), in
    row order into ``out``; returns how many (the caller sums them as the twin does)."""
    k = 0
    for i in range(n):
        s = buf[i, S]
        t = buf[i, T]
        if s >= s_lo and s <= s_hi and t >= t_lo and t <= t_hi:
            out[k] = buf[i, M]
            k += 1
    return k


@jit.kernel
def arrival_law(d_grid, v_grid, shape, n_up, a, closing, cdf, coef):
    """``WindshieldSimReference.arrival_rate_per_s``'s law and ``ArrivalTable``'s interpolation table in one loop
    over the diameter grid ``d_grid`` (mm; terminal speeds ``v_grid`` m/s, the size law's ``shape`` per diameter):
    for the glass's world normal's up component ``n_up`` and the air's closing offset ``a`` (m/s), the closing
    speed per diameter (m/s) into ``closing``, the flux-weighted CDF (trapezoid rule) into ``cdf``, and per grid
    interval the rows of ArrivalTable._coef into ``coef``."""
    k = d_grid.shape[0]
    for i in range(k):
        closing[i] = max(v_grid[i] * n_up - a, 0.0)
    cdf[0] = 0.0
    for i in range(k - 1):
        x = 0.5 * (shape[i + 1] * closing[i + 1] + shape[i] * closing[i]) * (d_grid[i + 1] - d_grid[i])
        cdf[i + 1] = x if i == 0 else cdf[i] + x
    for i in range(k - 1):
        dd = d_grid[i + 1] - d_grid[i]
        dc = cdf[i + 1] - cdf[i]
        coef[i, 0] = dd / dc if dc != 0.0 else _INF  # (a flat stretch: never selected)
        coef[i, 1] = cdf[i]
        coef[i, 2] = d_grid[i]
        coef[i, 3] = (closing[i + 1] - closing[i]) / dd
        coef[i, 4] = closing[i]
