"""The emitter's per-frame fast path: launch, fly and file one frame's parcels, droplets and mist together.

The same numbers as the float64 reference path of ``SprayEmitter._spawn_parcels`` (tests/effects/spray/
test_fast_path.py), in fewer NumPy calls: the parcels arrive sorted by bucket, every launch writes into one set of
reused arrays, nothing is checked again (the emitter made every input itself; the frame was checked at its
boundary), and the records of both rings are assembled in one pass."""

from __future__ import annotations

import numpy as np

from rain_core import jit, layout, physics
from rain_core.effects.spray import body, kernels
from rain_core.effects.spray.flight import DRAG_TAIL_FIT, ground_time
from rain_core.effects.spray.launch import (
    _MIST_CONSTS,
    _MIST_LO_ROW,
    _MIST_SPAN_ROW,
    LAUNCH_TABLES,
    MIST_LIFE_S,
    MIST_SIGMA_MAX,
    WAKE_TAU_S,
    carrier_air_and_tau,
    draw_launches,
    draws_needed,
    launch_droplets_sorted,
    launch_mist,
    launch_parcels_compiled,
    wheel_table,
)
from rain_core.effects.spray.optics import EXTINCTION_EFFICIENCY, extinction_area_m2
from rain_core.effects.spray.parcels import (
    FATE_AIR,
    FATE_BODY,
    FATE_ROAD,
    KIND_DROPLET,
    KIND_FADE,
    KIND_MIST,
    PARTICLE_DTYPE,
    as_floats,
)
from rain_core.effects.spray.water import MIST_D_MM, SPLASH_MIN_MM

_MIST_VT_M_S = physics.terminal_velocity(MIST_D_MM)


# The Gunn–Kinzer interpolant's knots and slopes per interval, for _terminal_velocity's gathers.
_GK_X = physics.GUNN_KINZER_D_MM
_GK_X0, _GK_H = _GK_X[:-1].copy(), _GK_X[1:] - _GK_X[:-1]
_GK_Y0, _GK_Y1 = physics.GUNN_KINZER_V_M_S[:-1].copy(), physics.GUNN_KINZER_V_M_S[1:].copy()
_GK_D0, _GK_D1 = physics._GK_SLOPES[:-1].copy(), physics._GK_SLOPES[1:].copy()


def _terminal_velocity(d_mm: np.ndarray) -> np.ndarray:
    """``physics.terminal_velocity`` (m/s) of the droplets' sizes d_mm (mm), bit for bit, without its argument
    check and its Stokes and break-up branches: the launches clip every size to 0.1–5 mm, inside the table
    (0.078–5.8 mm), where it is ``physics._hermite`` — evaluated here with the same operations in the same order,
    each interval's knots gathered from per-interval tables."""
    k = _GK_X.searchsorted(d_mm, side="right") - 1
    h = _GK_H.take(k)
    t = (d_mm - _GK_X0.take(k)) / h
    t2 = t * t
    t3 = t2 * t
    two_t3, three_t2 = 2 * t3, 3 * t2
    return ((two_t3 - three_t2 + 1) * _GK_Y0.take(k) + (t3 - 2 * t2 + t) * h * _GK_D0.take(k)
            + (three_t2 - two_t3) * _GK_Y1.take(k) + (t3 - t2) * h * _GK_D1.take(k))


def quantile_90(x: np.ndarray) -> float:
    """np.quantile(x, 0.9) (linear interpolation) from a partial sort."""
    n = len(x)
    pos = 0.9 * (n - 1)
    lo = int(pos)
    hi = min(lo + 1, n - 1)
    part = np.partition(x, (lo, hi))
    return float(part[lo] + (pos - lo) * (part[hi] - part[lo]))


class SpawnBuffers:
    """Arrays reused from frame to frame (grown when a frame spawns more, never shrunk): the launches' outputs
    and the records of both rings, so a frame allocates no parcel-sized arrays of its own for them. Made zeroed:
    reused memory may hold NaN, which the soak (tests/soak) would report as the effect's state."""

    def __init__(self):
        self.size = 0
        self._grow(256)

    def _grow(self, n: int) -> None:
        self.size = n
        self.launch = (np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros((n, 3)),
                       np.zeros(n))
        self.records = np.zeros(n, PARTICLE_DTYPE)
        # The compiled path's flight outputs: u, speed, τ, ground and body ages.
        self.flight = (np.zeros((n, 3)), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n))
        self.draws = np.zeros(draws_needed(n))  # the compiled launches' random draws, and their offsets
        self.offs = np.zeros(7, dtype=np.int64)
        self.q90 = np.zeros(2)  # the compiled settle's running percentiles (SprayEmitter._life_q90), in and out
        # The compiled filing's outputs: road landings, the kept records (as floats) and their birth and death.
        self.landings = np.zeros((n, 4))
        self.record_floats = as_floats(self.records)
        self.birth = np.zeros(n)
        self.death = np.zeros(n)
        # kernels.launch_to_records' scratch: each parcel's vehicle, life and fate.
        self.vi = np.empty(n, dtype=np.int64)
        self.life = np.zeros(n)
        self.fate = np.empty(n, dtype=np.int64)

    def ensure(self, n: int) -> SpawnBuffers:
        if n > self.size:
            self._grow(max(n, 2 * self.size))
        return self


def _vehicle_table(geo) -> np.ndarray:
    """Per vehicle, side by side (V, 20): position (3), velocity (3), right (3), forward (3), the BodyBox fields
    (8) — what the body test reads of each droplet's thrower. Made once per geometry (one per frame)."""
    table = getattr(geo, "_vehicle_table", None)
    if table is None:
        table = np.column_stack([geo.position, geo.velocity, geo.right, geo.forward, geo.box_params])
        geo._vehicle_table = table
    return table


_NO_CAPS = np.zeros(0)  # no mist caps or body ages (the kernels' arrays when a frame has no mist or droplets)
# kernels.file_records' constants: the period, Q·1.5 and ρ_w of the extinction area, the splash size, the mist's
# σ_max share, the fates and the kinds.
_FILE_CONSTS = np.array([layout.PERIOD_M, EXTINCTION_EFFICIENCY * 1.5, physics.RHO_WATER, SPLASH_MIN_MM,
                         MIST_SIGMA_MAX, FATE_ROAD, FATE_BODY, FATE_AIR, KIND_DROPLET, KIND_MIST, KIND_FADE],
                        dtype=np.float64)


# kernels.launch_to_records' grouped constants: fly's (mist v_t, mist τ, g, the drag tail fit, kerb height, road
# half width, Newton tolerance), the Gunn–Kinzer tables, the body test's steps, the fates.
_FLY_CONSTS = np.array([_MIST_VT_M_S, WAKE_TAU_S, physics.G_M_S2, DRAG_TAIL_FIT, layout.KERB_HEIGHT_M,
                        layout.ROAD_HALF_WIDTH_M, 1e-9])
_GK = (_GK_X, _GK_X0, _GK_H, _GK_Y0, _GK_Y1, _GK_D0, _GK_D1)
_BODY_STEPS = np.array([body.SAMPLES, body.ZOOM, body.ROUNDS], dtype=np.int64)
_FATE_IDS = np.array([FATE_ROAD, FATE_BODY, FATE_AIR], dtype=np.int64)


def _horizons(q90: list, life: np.ndarray, nd: int) -> tuple[float, float]:
    """Each ring's horizon (s): the running 90th percentile of its parcels' lives (``q90``, updated in place with
    this frame's droplets [:nd] and mist [nd:]), at least 50 ms."""
    out = [0.0, 0.0]  # (the compiled path's twin: kernels.settle_horizons)
    for ring, sl in ((0, slice(0, nd)), (1, slice(nd, len(life)))):
        if sl.stop > sl.start:
            q90[ring] = 0.9 * q90[ring] + 0.1 * max(quantile_90(life[sl]), 0.05)
            out[ring] = max(q90[ring], 0.05)
    return out[0], out[1]


def _file_compiled(em, frame, geo, buf, nd, now, horizons, fate, life, mass, p0, v0, u, tau, birth, sigma0, growth,
                   d_mm, vi) -> None:
    """The compiled path's end of :func:`spawn_parcels_fast`: ``kernels.file_records`` (horizons, fates, road
    landings, the kept records), then the records' ``rand`` draw (the twin's one call) and the rings' push."""
    landings_on = bool(nd) and em._standing_water_possible(frame)
    k0, k, m = kernels.file_records(fate, life, horizons[0], horizons[1], nd, now, landings_on, mass, p0, v0, u, tau,
                                    birth, sigma0, growth, d_mm, vi, _vehicle_consts(geo), _FILE_CONSTS,
                                    em.stats.fates, buf.landings, buf.record_floats, buf.birth, buf.death)
    _push_filed(em, buf, k0, k, m, len(life), nd)


def _push_filed(em, buf, k0: int, k: int, m: int, n: int, nd: int) -> None:
    """After ``kernels.file_records`` (k records, k0 of ring 0, m road landings, of n parcels, nd droplets): the
    landings to the candidates, the records' ``rand`` draw (the twin's one call), the rings' push, the counts."""
    if m:
        em._candidates = np.concatenate([em._candidates, buf.landings[:m]])
    if k:
        rec = buf.records[:k]
        rec["rand"] = em.rng.random(k)
        for ring, sl in ((0, slice(0, k0)), (1, slice(k0, k))):
            if sl.stop > sl.start:
                em.dirty[ring].extend(em.rings[ring].push(rec[sl], buf.birth[sl], buf.death[sl]))
    st = em.stats
    st.parcels += nd
    st.last_parcels += nd
    st.mist_puffs += n - nd
    st.last_mist += n - nd


def _vehicle_consts(geo) -> np.ndarray:
    """(V, ≥ 2) float64, each vehicle's height and half length (m) in its first columns: gather_wheels' table of
    the fleet's constants, or made once for a geometry built otherwise."""
    table = getattr(geo, "_vehicle_consts", None)
    if table is None:
        table = np.column_stack([geo.height, geo.half_length])
        geo._vehicle_consts = table
    return table


def spawn_parcels_fast(em, frame, geo, nd: int, w, bounds, mass, birth, age_now, now: float, wind,
                       body_hit) -> None:
    """What ``SprayEmitter._spawn_parcels`` does on its reference path, for parcels sorted by bucket: rows [:nd]
    droplets (bucket k in rows bounds[k]:bounds[k + 1]), [nd:] mist puffs; ``w`` the flat wheel index of each.
    ``body_hit``: the body test (``body_hit_time_fast``'s signature), looked up by the emitter."""
    rng = em.rng
    n = len(w)
    nm = n - nd
    buf = em._spawn_buffers.ensure(n)
    out = buf.launch
    compiled = jit.active()
    if compiled and body_hit is body.body_hit_time_fast:
        _launch_to_records(em, frame, geo, buf, nd, n, w, bounds, mass, birth, age_now, now, wind)
        return
    # Below: the NumPy twins, or the compiled kernels one by one around a body test a test plugged in.
    if compiled:
        launch_parcels_compiled(rng, geo, w, bounds, nd, age_now, tuple(a[:n] for a in out), _vehicle_table(geo),
                                _vehicle_consts(geo), buf.draws, buf.offs)
    else:
        if nd:
            launch_droplets_sorted(rng, geo, w[:nd], bounds, age_now[:nd], out)
        if nm:
            launch_mist(rng, geo, w[nd:], None, age_now[nd:], out=tuple(a[nd:n] for a in out))
    p0, v0, d_mm, sigma0, growth, air, updraught = (a[:n] for a in out)
    if compiled:
        u, speed, tau, t_ground, t_body = (a[:n] for a in buf.flight)
        kernels.fly(p0, v0, d_mm, air, updraught, nd, np.ascontiguousarray(wind, dtype=np.float64), _MIST_VT_M_S,
                    WAKE_TAU_S, _GK_X, _GK_X0, _GK_H, _GK_Y0, _GK_Y1, _GK_D0, _GK_D1, physics.G_M_S2, DRAG_TAIL_FIT,
                    layout.KERB_HEIGHT_M, layout.ROAD_HALF_WIDTH_M, 1e-9, 40, u, speed, tau, t_ground)
    else:
        vt = np.empty(n)
        vt[:nd] = _terminal_velocity(d_mm[:nd])
        vt[nd:] = _MIST_VT_M_S
        u, speed, tau = carrier_air_and_tau(wind, air, updraught, v0, d_mm, vt, nd)
        t_ground = ground_time(p0, v0, u, tau)
    vi = w // 4
    life = np.empty(n)
    fate = np.empty(n, dtype=np.int64)
    if nd:
        d = slice(0, nd)
        rows = _vehicle_table(geo).take(vi[d], axis=0)  # one gather for all the per-vehicle quantities
        vel = rows[:, 3:6]
        t_body = body_hit(p0[d], v0[d], u[d], tau[d], t_ground[d], rows[:, 0:3] - vel * age_now[d, None], vel,
                          rows[:, 6:9], rows[:, 9:12], rows[:, 12:20])
    if compiled:
        cap = rng.uniform(*MIST_LIFE_S, nm) if nm else _NO_CAPS
        q90 = buf.q90
        q90[0], q90[1] = em._life_q90
        horizons = kernels.settle_horizons(t_body if nd else _NO_CAPS, t_ground, cap, speed, nd, life, fate, growth,
                                           FATE_ROAD, FATE_BODY, FATE_AIR, q90)
        em._life_q90[0], em._life_q90[1] = q90.tolist()
        _file_compiled(em, frame, geo, buf, nd, now, horizons, fate, life, mass, p0, v0, u, tau, birth, sigma0, growth,
                       d_mm, vi)
        return
    if nd:
        hit = t_body < t_ground[d]
        fate[d] = np.where(hit, FATE_BODY, FATE_ROAD)
        np.minimum(t_body, t_ground[d], out=life[d])
        growth[d] *= speed[d]
    if nm:
        cap = rng.uniform(*MIST_LIFE_S, nm)
        fate[nd:] = np.where(cap < t_ground[nd:], FATE_AIR, FATE_ROAD)
        np.minimum(cap, t_ground[nd:], out=life[nd:])
    # Drawn up to 1 ms before the surface so float32 never shows it past the road or the body.
    life -= 1e-3
    np.maximum(life, 0.0, out=life)
    horizon = np.empty(n)
    horizon[:nd], horizon[nd:] = _horizons(em._life_q90, life, nd)
    # The ring is refilled every q90 seconds (that is how the emission rate was set): a parcel living longer
    # would be overwritten in flight, so it fades out at that age instead.
    faded = life > horizon
    fate[faded] = FATE_AIR
    np.minimum(life, horizon, out=life)
    em.stats.fates += np.bincount(fate, weights=mass, minlength=3)
    if nd:
        _road_landings(em, frame, fate[:nd], p0, v0, u, tau, life, birth, mass)
    # The records of both rings, in one array: ring 0's rows first.
    rec = buf.records[:n]
    period = np.floor(p0[:, 2] / layout.PERIOD_M)
    p0[:, 2] -= period * layout.PERIOD_M  # z within its period, so float32 keeps mm
    rec["p0"], rec["period"], rec["v0"], rec["tau"], rec["u"], rec["birth"] = p0, period, v0, tau, u, birth
    rec["life"], rec["sigma0"], rec["growth"] = life, sigma0, growth
    rec["area"] = extinction_area_m2(mass, d_mm)
    kind = rec["kind"]
    kind[:] = np.where(fate == FATE_AIR, KIND_DROPLET + KIND_FADE, KIND_DROPLET)
    kind[nd:] += KIND_MIST - KIND_DROPLET
    rec["d_mm"] = d_mm
    glint = rec["glint"]
    glint[:nd] = np.where(d_mm[:nd] >= SPLASH_MIN_MM, 1.0, 0.5)
    glint[nd:] = MIST_SIGMA_MAX * geo.height[vi[nd:]]  # mist puffs hold σ_max (m)
    _file(em, rec, birth, birth + life, nd, now)
    st = em.stats
    st.parcels += nd
    st.last_parcels += nd
    st.mist_puffs += nm
    st.last_mist += nm


def _launch_to_records(em, frame, geo, buf, nd: int, n: int, w, bounds, mass, birth, age_now, now: float, wind) -> None:
    """:func:`spawn_parcels_fast`'s compiled path in one kernel call: every draw the launches and the mist caps
    need (the same calls in the same order as the five-kernel path below), then ``kernels.launch_to_records``,
    then the records' ``rand`` draw and the rings' push (:func:`_push_filed`)."""
    rng = em.rng
    nm = n - nd
    p0, v0, d_mm, sigma0, growth, air, updraught = (a[:n] for a in buf.launch)
    draw_launches(rng, bounds, nd, n, buf.draws, buf.offs, d_mm)
    cap = rng.uniform(*MIST_LIFE_S, nm) if nm else _NO_CAPS
    u, speed, tau, t_ground, t_body = (a[:n] for a in buf.flight)
    q90 = buf.q90
    q90[0], q90[1] = em._life_q90
    landings_on = bool(nd) and em._standing_water_possible(frame)
    k0, k, m = kernels.launch_to_records(
        w, bounds, nd, age_now, buf.draws, buf.offs, wheel_table(geo), _vehicle_table(geo), _vehicle_consts(geo),
        LAUNCH_TABLES, _MIST_LO_ROW, _MIST_SPAN_ROW, _MIST_CONSTS, p0, v0, d_mm, sigma0, growth, air, updraught,
        np.ascontiguousarray(wind, dtype=np.float64), _FLY_CONSTS, _GK, 40, u, speed, tau, t_ground, buf.vi,
        _BODY_STEPS, t_body, cap, buf.life[:n], buf.fate[:n], _FATE_IDS, q90, now, landings_on, mass, birth,
        _FILE_CONSTS, em.stats.fates, buf.landings, buf.record_floats, buf.birth, buf.death)
    em._life_q90[0], em._life_q90[1] = q90.tolist()
    _push_filed(em, buf, k0, k, m, n, nd)


def _road_landings(em, frame, fate_d, p0, v0, u, tau, life, birth, mass) -> None:
    """The droplets that land on the road: (time, x, z, downward momentum) to the candidates whose water depth
    the next frame's film lookup decides (SprayEmitter.observe): flight_position / flight_velocity at landing,
    for the columns used."""
    road = (fate_d == FATE_ROAD).nonzero()[0]
    if len(road) == 0 or not em._standing_water_possible(frame):
        return
    t, tau_r = life[road], tau[road]
    p, v, ur = p0[road], v0[road], u[road]
    e = -t / tau_r
    relax = -tau_r * np.expm1(e)
    rows = np.empty((len(road), 4))
    rows[:, 0] = birth[road] + t
    # x and z together (columns 0 and 2 of the flight): the same operations element by element.
    rows[:, 1:3] = p[:, ::2] + ur[:, ::2] * t[:, None] + (v[:, ::2] - ur[:, ::2]) * relax[:, None]
    vel_y = ur[:, 1] + (v[:, 1] - ur[:, 1]) * np.exp(e)
    rows[:, 3] = mass[road] * np.maximum(-vel_y, 0.0)
    em._candidates = np.concatenate([em._candidates, rows])


def _file(em, rec, birth, death, nd: int, now: float) -> None:
    """Push the records still alive at ``now`` (parcels that died within this frame are not drawn) into their
    rings: rows [:nd] ring 0, the rest ring 1. Each ring's ``rand`` draw as the reference makes them (ring 0's,
    then ring 1's: one call)."""
    keep = death > now
    k0 = int(np.count_nonzero(keep[:nd]))
    k = int(np.count_nonzero(keep))
    if k == 0:
        return
    if k < len(keep):
        idx = np.flatnonzero(keep)
        rec = as_floats(rec).take(idx, axis=0).view(PARTICLE_DTYPE).reshape(k)
        birth, death = birth[idx], death[idx]
    rec["rand"] = em.rng.random(k)
    for ring, sl in ((0, slice(0, k0)), (1, slice(k0, k))):
        if sl.stop > sl.start:
            em.dirty[ring].extend(em.rings[ring].push(rec[sl], birth[sl], death[sl]))
