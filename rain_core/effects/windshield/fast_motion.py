"""The fast path's motion: forces, pinning and viscous sliding of every drop at once, and what running drops do
to the film in their path (a mixin of ``sim.WindshieldSim``, ahead of ``dynamics.DropDynamics``; the float64
reference's ``_move`` and ``_sweep_film_and_trail`` are the truth the fast-path tests compare with).

Per-drop values that depend only on the position (air factors, boundary-layer run, gravity along the glass) are
read from the drop rows' columns (``drop_rows``), written when a drop is born, moves or merges."""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.constants import (
    CROSSWIND_GAIN,
    DRAG_CD,
    DROP_EVAP_KG_M_S,
    EVAP_AIR_M_S,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    FRONTAL_PER_RADIUS2,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    KINETIC_PIN,
    M_OBJECT_MIN,
    MU_W,
    TRAIL_FILM_M,
    TRAIL_FRACTION,
    TRAIL_PARENT_MIN,
    TRAIL_SPACING_RADII,
    V_STOP_M_S,
    VISCOUS_C,
    VOLUME_PER_RADIUS3,
    drop_radius,
)
from rain_core.effects.windshield.drop_rows import BL as _BL
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import EV as _EV
from rain_core.effects.windshield.drop_rows import GS as _GS
from rain_core.effects.windshield.drop_rows import GT as _GT
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import RB as _RB
from rain_core.effects.windshield.drop_rows import ROW as _ROW
from rain_core.effects.windshield.drop_rows import TRAIL as _TRAIL
from rain_core.effects.windshield.drop_rows import UP as _UP
from rain_core.effects.windshield.drop_rows import VS as _VS
from rain_core.effects.windshield.drop_rows import VT as _VT
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import Q as _Q
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.physics import RHO_AIR, RHO_WATER

_MASS_PER_A3 = RHO_WATER * VOLUME_PER_RADIUS3  # kg / m³: a drop's mass over its contact radius cubed
_EMPTY1 = np.zeros(0)
_EMPTY_I = np.zeros(0, np.int64)
# A resting drop whose bound RB (drop_rows; see FastMotion._move) is below this is not tested: the margin covers
# the rounding of the bound and the Newton radius's tiny lag behind the mass (relative ≲ 1e-8).
_REST_TEST = 0.999
# The bounds hold for any air within this relative distance of the air of the last full test (the "epoch"), so a
# car whose speed drifts by a fraction of a per cent a frame retests only the drops near their pinning, not all.
_AIR_SLACK = 0.02
_Q_MAX = 1.01  # |Q| of a drop on the glass is at most 1 (its side edge); the margin covers rounding
_U_MIN = min(FLOW_AT_BOTTOM, FLOW_AT_TOP)  # the smallest along-glass factor UP (head·UP is the air's t part)


def _air_deviation(head: float, cross: float, epoch: tuple | None) -> float | None:
    """An upper bound on |A − A_E| / |A_E| over the glass, A the air over a drop (airflow.air_velocity) for
    (head, cross) m/s and A_E that for the epoch's; None when no bound holds (no epoch, a headwind turned
    tailwind, no head air in the epoch). For a headwind A = (head·UP·FLOW_SPREAD·Q + CROSSWIND_GAIN·cross,
    head·UP) (a tailwind: UP = FLOW_AT_BOTTOM and |head| across), so |A − A_E| ≤ |Δhead|·UP·(1 + FLOW_SPREAD·|Q|)
    + CROSSWIND_GAIN·|Δcross| and |A_E| ≥ |head_E|·UP."""
    if epoch is None:
        return None
    h0, c0 = epoch
    if head == h0 and cross == c0:
        return 0.0
    if h0 == 0.0 or (head >= 0.0) != (h0 >= 0.0):
        return None
    return (abs(head - h0) * (1.0 + FLOW_SPREAD * _Q_MAX) + CROSSWIND_GAIN * abs(cross - c0) / _U_MIN) / abs(h0)


class FastMotion:
    """``_move`` and ``_run`` over the drop rows (needs the host's ``_buf``, ``_n``, ``film``, ``_placed``,
    ``_inside``, ``_cells``, ``_append``)."""

    # --- motion (dynamics.DropDynamics._move) ---------------------------------------------------------------
    def _move(self, h: float, air_local: np.ndarray, inputs) -> tuple:
        """Forces, pinning, viscous sliding; returns for the merge test (``_merge_moves``) the drop count before
        the step's trail droplets, the drops that slid (``go``), their start (s, t), displacement and its length
        (m), as columns: the others did not move.

        Only the drops that may slide are tested (``cand``): those whose RB column (drop_rows) is at least
        _REST_TEST. A drop at rest gets RB = max(|G + D|, |G|, |D|) / pin from the forces of its test (G gravity,
        D the air's drag at rest, pin the static pinning): while it rests in the same air and only loses water
        (evaporation: its mass m and radius a shrink), its force over pin is α·G/pin + β·D/pin with α = (m/a)
        over its value then and β = a·profile(a)² over its value then, both in [0, 1] (profile grows with a), so
        it stays ≤ RB (a convex function on [0, 1]² is largest at a corner) and the drop stays put, as the full
        test would find. Anything else (moving, placed, grown) sets RB = +inf.

        The air may change too, within an epoch: while |A' − A| ≤ ε·|A| over every drop (A its air at the test,
        ``_air_deviation``), the drag D = k·a²·q(|A|)²·|A|·A (q the profile, concave in √|A| from 0) changes by
        at most c·|D|, c = (2ε + ε²)(1 + ε) + ε (|A|·q² is within (1 ± ε)² of its value), so RB = max(|G + D| +
        c·|D|, |G|, (1 + c)·|D|) / pin bounds it (the same corners). An air outside the epoch starts a new one:
        every drop is tested. The drops' EV column follows the air of every step."""
        n = self._n
        if n == 0:
            return 0, _EMPTY_I, _EMPTY1, _EMPTY1, _EMPTY1, _EMPTY1, _EMPTY1
        if self._dirty and not jit.active():  # (the kernel places the dirty rows on its way: _move_compiled)
            self._flush_placed()
        d = self._buf[:n]
        head, cross = float(air_local[2]), float(air_local[0])
        new_air = self._step_air != (head, cross)  # then every drop's EV is rewritten
        self._step_air = (head, cross)
        dev = _air_deviation(head, cross, self._rest_air)
        cand = None  # None: every drop
        new_epoch = dev is None or dev > _AIR_SLACK
        if new_epoch:  # a new epoch: every drop is tested, its bound made for this air
            self._rest_air = (head, cross)
            dev = 0.0
        elif not jit.active():
            cand = (d[:, _RB] >= _REST_TEST).nonzero()[0]
            if len(cand) == n:
                cand = None
        # A bound made now must hold for any air of the epoch, within (slack + dev) / (1 − dev) of this one over
        # every drop (relative): the drag then differs from this one's by at most ``grow`` times it (docstring).
        slack = (_AIR_SLACK + dev) / (1.0 - dev) if self._rest_air[0] != 0.0 else 0.0
        grow = (2.0 * slack + slack * slack) * (1.0 + slack) + slack
        if jit.active():
            return self._move_compiled(h, head, cross, new_air, new_epoch, grow)
        c = d if cand is None else d.take(cand, axis=0)
        k = len(c)
        s_g = t_g = ds = dt_ = step_len = _EMPTY1
        go = _EMPTY_I
        whole = cand is None or new_air  # the air over every drop (for EV), the tested ones' taken from it
        if whole or k:
            src = d if whole else c
            # The air over the glass (airflow.air_velocity), from the position's factors (drop_rows).
            if head >= 0.0:
                up = head * src[:, _UP]
                side = up * FLOW_SPREAD * src[:, _Q] + CROSSWIND_GAIN * cross
            else:  # a tailwind: a weak, separated flow down the glass
                up = np.full(len(src), head * FLOW_AT_BOTTOM)
                side = abs(head * FLOW_AT_BOTTOM) * FLOW_SPREAD * src[:, _Q] + CROSSWIND_GAIN * cross
            air_speed = np.sqrt(side * side + up * up)
            ev = np.sqrt(1.0 + air_speed / EVAP_AIR_M_S)  # the air's factor on the evaporation (below)
            if not whole:
                d[cand, _EV] = ev
            else:
                d[:, _EV] = ev
                if cand is not None:
                    up, side, air_speed = up.take(cand), side.take(cand), air_speed.take(cand)
        if k:
            a = c[:, _A]  # the radius at the start of the step (the Newton update below comes after its last use)
            m = c[:, _M]
            # Drag in the boundary layer (airflow.drag).
            delta = 5.0 * np.sqrt(c[:, _BL] / np.maximum(air_speed, 1e-3))
            eta = np.minimum(np.maximum(HEIGHT_PER_RADIUS * a / delta, 0.0), 1.0)
            profile = 1.5 * eta - 0.5 * (eta * eta * eta)
            vs, vt = c[:, _VS], c[:, _VT]
            rel_s = side * profile - vs
            rel_t = up * profile - vt
            rel = np.sqrt(rel_s * rel_s + rel_t * rel_t)
            coef = (0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2) * a**2 * rel
            # Gravity along the curved glass (GlassGeometry.gravity), per unit mass from drop_rows.
            gs, gt = c[:, _GS], c[:, _GT]
            f_s = m * gs + coef * rel_s
            f_t = m * gt + coef * rel_t
            fmag = np.sqrt(f_s * f_s + f_t * f_t)
            pin = GAMMA_W * 2.0 * a * HYSTERESIS
            speed = np.sqrt(vs * vs + vt * vt)
            moving = speed > 0.0
            slides = moving | (fmag > pin)  # moving, or starting to
            # The bound that spares a resting drop the test while it stays put (see the docstring).
            drag = coef * rel
            if grow:
                fmag_hi = drag * grow
                fmag_hi += fmag
                drag *= 1.0 + grow
            else:
                fmag_hi = fmag
            rb = np.maximum(np.maximum(fmag_hi, m * np.sqrt(gs * gs + gt * gt)), drag) / pin
            rb[slides] = np.inf
            if cand is None:
                d[:, _RB] = rb
            else:
                d[cand, _RB] = rb
            go_l = slides.nonzero()[0]
            if len(go_l):
                go = go_l if cand is None else cand[go_l]
                # The sliding update, for the drops that slide (the others stay at rest).
                mv = moving[go_l]
                fs_g, ft_g, fm_g, pin_g, m_g, a_g = f_s[go_l], f_t[go_l], fmag[go_l], pin[go_l], m[go_l], a[go_l]
                vs_g, vt_g, sp_g = vs[go_l], vt[go_l], speed[go_l]
                sp_g, fm_safe = np.maximum(sp_g, 1e-300), np.maximum(fm_g, 1e-300)
                dir_s = np.where(mv, vs_g / sp_g, fs_g / fm_safe)
                dir_t = np.where(mv, vt_g / sp_g, ft_g / fm_safe)
                kp = KINETIC_PIN * pin_g
                damp = 1.0 + h * (VISCOUS_C * MU_W * a_g / m_g)
                nv_s = (vs_g + h * ((fs_g - kp * dir_s) / m_g)) / damp
                nv_t = (vt_g + h * ((ft_g - kp * dir_t) / m_g)) / damp
                stop = mv & (
                    (nv_s * vs_g + nv_t * vt_g <= 0.0)
                    | ((np.sqrt(nv_s * nv_s + nv_t * nv_t) < V_STOP_M_S) & (fm_g < pin_g))
                )
                nv_s[stop] = 0.0
                nv_t[stop] = 0.0
                ds, dt_ = h * nv_s, h * nv_t
                s_g, t_g = c[go_l, _S], c[go_l, _T]
                g = d.take(go, axis=0)  # whole rows: one gather, one scatter
                g[:, _VS] = nv_s
                g[:, _VT] = nv_t
                g[:, _S] = s_g + ds
                g[:, _T] = t_g + dt_
                g[:, _KEY] = _DIRTY  # the position's columns are written before they are read (sim._flush_placed)
                self._rows[go] = g.view(_ROW).ravel()
                self._dirty = True
        # Slow evaporation of the drops themselves (hours for a millimetre drop; kept for the balance).
        a = d[:, _A]
        m = d[:, _M]
        loss = DROP_EVAP_KG_M_S * a
        loss *= d[:, _EV]
        loss *= h
        np.minimum(loss, m, out=loss)
        m -= loss
        self.evaporated += float(np.add.reduce(loss))
        # The radius follows the mass: one Newton step from the last radius (see the module docstring).
        ra2 = a * a
        a -= (ra2 * a - m * (1.0 / _MASS_PER_A3)) / (3.0 * ra2)
        if len(go):
            step_len = np.sqrt(ds * ds + dt_ * dt_)
            run = (step_len > 0.0).nonzero()[0]
            if len(run):
                self._run(go[run], s_g[run], t_g[run], ds[run], dt_[run], step_len[run], a_g[run])
        return n, go, s_g, t_g, ds, dt_, step_len

    def _move_compiled(self, h: float, head: float, cross: float, new_air: bool, new_epoch: bool, grow: float):
        """``_move`` from the epoch's bookkeeping on: the motion (``kernels.move_drops``) and the running drops'
        film and trails (``kernels.run_drops``), the cube roots and sums as the twin takes them."""
        n = self._n
        ks = self._scratch()
        buf = self._buf
        place, self._dirty = self._dirty, False
        n_go = kernels.move_drops(buf, n, h, head, cross, new_air or new_epoch, new_epoch, _REST_TEST, grow,
                                  ks.go, ks.gcol, ks.loss, place, self._w0, self._dw, self._height, self._g_up,
                                  self._g_sag)
        self.evaporated += float(np.add.reduce(ks.loss[:n]))
        if n_go == 0:
            return n, _EMPTY_I, _EMPTY1, _EMPTY1, _EMPTY1, _EMPTY1, _EMPTY1
        self._dirty = True
        room = max(self._budget - n, 0)
        k, n_new = kernels.run_drops(buf, n_go, ks.go, ks.gcol, self.film.ravel(), self._areas_flat, ks.total, room,
                                     self._w0, self._dw, self._height, ks.ridx, ks.rcol, ks.wcol)
        if k:
            self._trails.append(tuple(ks.rcol[:, :k].copy()))
            idx = ks.ridx[:k]
            buf[idx, _A] = drop_radius(buf[idx, _M])
            if n_new:
                self._append_at_rest(ks.wcol[0, :n_new], ks.wcol[1, :n_new], ks.wcol[2, :n_new])
        g = ks.gcol
        return n, ks.go[:n_go], g[0, :n_go], g[1, :n_go], g[2, :n_go], g[3, :n_go], g[4, :n_go]

    def _run(self, idx, s0, t0, ds, dt, step_len, a) -> None:
        """Running drops take up the film in their path, lay a thin wet line and drop trail droplets
        (dynamics.DropDynamics._sweep_film_and_trail on the running drops ``idx``, their start (s0, t0) m,
        displacement (ds, dt) m, its length (m) and their radius (m), as 1-D columns)."""
        ms, mt = s0 + 0.5 * ds, t0 + 0.5 * dt
        inside = self._inside(ms, mt)
        if np.count_nonzero(inside) < len(inside):
            sel = inside.nonzero()[0]
            if len(sel) == 0:
                return
            idx, s0, t0, ds, dt, step_len, a, ms, mt = (v[sel] for v in (idx, s0, t0, ds, dt, step_len, a, ms, mt))
        d = self._buf[: self._n]
        cells = self._cells(ms, mt)
        flat = self.film.ravel()
        swept_area = 2.0 * a * step_len
        frac = swept_area / self._areas_flat[cells]
        total = np.bincount(cells, weights=frac, minlength=flat.size)[cells]
        scale = np.where(total > 1.0, 1.0 / np.maximum(total, 1e-300), 1.0)
        take = flat[cells] * frac * scale
        np.subtract.at(flat, cells, take)
        np.maximum(flat, 0.0, out=flat)
        mass = d[idx, _M]
        wet = np.minimum(RHO_WATER * TRAIL_FILM_M * swept_area, 0.1 * mass)
        np.add.at(flat, cells, wet)
        mass += take - wet
        d[idx, _M] = mass
        es, et = s0 + ds, t0 + dt
        self._trails.append((s0, t0, es, et, a))
        # Trail droplets: one every TRAIL_SPACING_RADII radii of run, behind the drop, from heavy drops only.
        spacing = TRAIL_SPACING_RADII * a
        run = d[idx, _TRAIL] + step_len
        k = np.minimum(np.floor(run / spacing), 4).astype(np.int64)
        k[mass < TRAIL_PARENT_MIN] = 0
        run -= k * spacing
        d[idx, _TRAIL] = np.minimum(run, spacing)
        total_k = int(np.add.reduce(k))
        if total_k:
            if total_k == np.count_nonzero(k):  # one droplet per drop at most: the common case
                local = k.nonzero()[0]
                gap = 1.3 * a[local]
            else:
                local = np.arange(len(idx)).repeat(k)
                first = k.cumsum()
                first -= k
                within = np.arange(total_k) - first.take(local)  # (a gather: repeat copies element by element)
                gap = (1.3 + TRAIL_SPACING_RADII * within) * a[local]
            # Behind the drop on the path it ran, clear of it (so they do not join again at once).
            gap /= step_len[local]
            ws = es[local] - ds[local] * gap
            wt = et[local] - dt[local] * gap
            ok = self._inside(ws, wt)
            if np.count_nonzero(ok) < len(ok):
                local, ws, wt = local[ok], ws[ok], wt[ok]
            parent = idx[local]
            m_t = TRAIL_FRACTION * d[parent, _M]
            np.subtract.at(d[:, _M], parent, m_t)
        d[idx, _A] = drop_radius(d[idx, _M])
        if total_k:
            room = max(self._budget - self._n, 0)
            as_drop = np.zeros(len(m_t), bool)
            as_drop[:room] = m_t[:room] >= M_OBJECT_MIN
            film_part = ~as_drop
            if np.count_nonzero(film_part):
                np.add.at(flat, self._cells(ws[film_part], wt[film_part]), m_t[film_part])
            if np.count_nonzero(as_drop):
                self._append_at_rest(ws[as_drop], wt[as_drop], m_t[as_drop])
