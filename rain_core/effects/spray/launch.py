"""Where and how parcels leave the wheels: the droplet launches of each water bucket (``BUCKETS``) and the mist
released into the vehicle's wake, with the wake's constants."""

from __future__ import annotations

import numpy as np

from rain_core.effects.spray import kernels
from rain_core.effects.spray.flight import drag_time_constant_unchecked
from rain_core.effects.spray.water import MIST_D_MM, SPLASH_MIN_MM, SPRAY_MAX_MM
from rain_core.effects.spray.wheels import WheelGeometry

# Mist: the wake carries it forward at a share of the vehicle's speed, decaying with this time constant, and
# spreads it with an eddy diffusivity K = MIST_DIFFUSIVITY·|V|·height (m²/s).
WAKE_SHARE = (0.25, 0.45)
WAKE_TAU_S = 0.8
WAKE_LIFT = (0.02, 0.06)  # upward launch speed of the mist per unit speed, for a vehicle WAKE_LIFT_HEIGHT_M tall
WAKE_LIFT_HEIGHT_M = 2.0
MIST_DIFFUSIVITY = 0.01
MIST_LIFE_S = (2.5, 4.0)
MIST_SIGMA0_M = 0.25
SPRAY_AIR_SHARE = (0.1, 0.35)  # spray drops drift with this share of the vehicle's velocity (dragged air)
SPRAY_UPDRAUGHT = 0.6  # up to this share of their settling speed is held up by the wheel's wake
MIST_SIGMA_MAX = 0.5  # × the vehicle's height: a puff grows no taller than the wake that holds it


_UP = np.array([0.0, 1.0, 0.0])


def _lognormal(rng, median: float, sigma: float, lo: float, hi: float, n: int) -> np.ndarray:
    return np.minimum(np.maximum(median * np.exp(sigma * rng.standard_normal(n)), lo), hi)


# Per droplet bucket: drop diameter (median mm, log-σ, min, max), parcel start size (m), spread per m/s.
# Side and bow waves leave as sheets that break into large drops, so they carry the largest sizes.
_DROPLET_SIZES = {0: (0.25, 0.35, 0.1, SPRAY_MAX_MM), 1: (0.25, 0.35, 0.1, SPRAY_MAX_MM),
                  2: (1.5, 0.3, SPLASH_MIN_MM, 3.0), 3: (3.0, 0.35, 1.5, 5.0), 4: (3.0, 0.35, 1.5, 5.0)}
# A spray parcel is a small cloud; a splash parcel a few large drops. Each parcel stands for many drops that
# leave the tyre spread over several centimetres; at 2–3 cm the parcels drew as separate white "bricks" smeared
# over the exposure, at 5–8 cm they merge into a cloud. The optical depth is the parcel's extinction area over
# its footprint, so the size does not change how much the spray hides.
_DROPLET_SIGMA0_M = {0: 0.075, 1: 0.075, 2: 0.05, 3: 0.06, 4: 0.06}
# Growth of the parcel (m) per metre it travels relative to the air: the spread of its drops' speeds.
_DROPLET_SPREAD = {0: 0.05, 1: 0.05, 2: 0.04, 3: 0.04, 4: 0.04}


def launch_droplets_reference(rng, geo: WheelGeometry, w, bucket, age_now):
    """Start points (m), ground velocities (m/s), drop sizes (mm), parcel sizes (m) and spread rates of the
    droplet parcels leaving wheels ``w`` (flat index) from buckets 0–4 (see ``BUCKETS``). The reference, bucket
    by bucket through masks; :func:`launch_droplets` draws the same numbers and gives the same parcels."""
    n = len(w)
    c = geo.contacts[w] - geo.wheel_velocity[w] * age_now[:, None]  # where the contact patch was at birth
    f, o = geo.travel[w], geo.outward[w]
    back = -f
    r, b, v = geo.radius[w], geo.width[w], geo.speed[w]
    vel = geo.wheel_velocity[w]
    centre = c + _UP * r[:, None]
    p0 = np.zeros((n, 3))
    v0 = np.zeros((n, 3))
    d_mm = np.zeros(n)
    sigma0 = np.zeros(n)
    across = (rng.random(n) - 0.5) * b  # where on the tread width
    air = np.zeros((n, 3))  # m/s, air velocity the parcel drifts with (besides the wind)
    updraught = np.zeros(n)  # share of the settling speed the wheel's wake holds up
    for k in range(5):
        sel = bucket == k
        m = int(sel.sum())
        if m == 0:
            continue
        d_mm[sel] = _lognormal(rng, *_DROPLET_SIZES[k], m)
        sigma0[sel] = _DROPLET_SIGMA0_M[k] * rng.uniform(0.8, 1.25, m)
        vs, rs = v[sel][:, None], r[sel][:, None]
        fs, os_, bs = f[sel], o[sel], back[sel]
        if k in (0, 1):
            # Spray: the film flung off the tyre (capillary water off its rear and top, the atomised share of
            # the groove water lower down) breaks into drops too small to keep their launch speed (τ ~ 10 ms):
            # they are caught by the air the wheel and body drag along, and leave the wheel well with it.
            lo, hi = (0.8, 1.8) if k == 0 else (0.2, 1.0)
            p0[sel] = (c[sel] + bs * (rs * rng.uniform(1.0, 1.3, (m, 1))) + _UP * (rs * rng.uniform(lo, hi, (m, 1)))
                       + os_ * (b[sel, None] * rng.uniform(0.4, 1.0, (m, 1))))  # pumped out past the tread
            share = rng.uniform(*SPRAY_AIR_SHARE, (m, 1))
            v0[sel] = vel[sel] * share + vs * (_UP * rng.uniform(0.0, 0.05, (m, 1))
                                               + os_ * rng.uniform(0.0, 0.08, (m, 1)))
            air[sel] = vel[sel] * share  # the dragged air keeps carrying them until they settle
            updraught[sel] = rng.uniform(0.0, SPRAY_UPDRAUGHT, m)
        elif k == 2:
            # Tread pickup: off the tyre at angle α from the bottom towards the rear, at up to the tread's speed
            # relative to the car (v), i.e. up and back; with some sideways spread off the groove edges.
            alpha = np.radians(5.0 + 45.0 * rng.random(m) ** 1.6)[:, None]
            speed = vs * rng.uniform(0.6, 1.0, (m, 1))
            rel = speed * (np.cos(alpha) * bs + np.sin(alpha) * _UP)
            lateral = vs * rng.normal(0.1, 0.12, (m, 1))
            p0[sel] = centre[sel] + rs * (np.sin(alpha) * bs - np.cos(alpha) * _UP) + os_ * across[sel, None]
            v0[sel] = vel[sel] + rel + os_ * lateral
        elif k == 3:
            # Side waves: squeezed out at the front edges of the contact patch, low and sideways.
            p0[sel] = c[sel] + fs * (0.3 * rs) + os_ * (b[sel, None] / 2.0) + _UP * 0.005
            # Most of the water goes low (the sheet's base), little to its top edge.
            v0[sel] = vs * (fs * rng.uniform(0.2, 0.5, (m, 1)) + os_ * rng.uniform(0.3, 0.7, (m, 1))
                            + _UP * (0.04 + 0.3 * rng.random((m, 1)) ** 2))
        else:
            # Bow waves: pushed ahead of the tyre, thrown forward and aside.
            p0[sel] = c[sel] + fs * (0.9 * rs) + os_ * across[sel, None] + _UP * 0.01
            v0[sel] = vs * (fs * rng.uniform(0.8, 1.15, (m, 1)) + os_ * rng.uniform(-0.1, 0.5, (m, 1))
                            + _UP * (0.08 + 0.35 * rng.random((m, 1)) ** 2))
    growth = np.array([_DROPLET_SPREAD[k] for k in range(5)])[bucket]
    return p0, v0, d_mm, sigma0, growth, air, updraught


_GROWTH = np.array([_DROPLET_SPREAD[k] for k in range(5)])
_SIGMA0 = np.array([_DROPLET_SIGMA0_M[k] for k in range(5)])
# Per bucket: the lognormal's median, log-σ, min and max (columns), for all buckets' drop sizes in one pass.
_SIZES = np.array([_DROPLET_SIZES[k] for k in range(5)], dtype=np.float64)
# The uniform draws of each bucket after its size's normal draw, in the reference's order: (low, high) each.
# ``rng.uniform(lo, hi, m)`` is lo + (hi − lo)·``rng.random(m)`` bit for bit, and consecutive draws of m are
# one draw of (k, m): one generator call per bucket instead of up to eight. None: a plain ``rng.random``.
_UNIFORMS = {
    0: ((0.8, 1.25), (1.0, 1.3), (0.8, 1.8), (0.4, 1.0), SPRAY_AIR_SHARE, (0.0, 0.05), (0.0, 0.08),
        (0.0, SPRAY_UPDRAUGHT)),
    1: ((0.8, 1.25), (1.0, 1.3), (0.2, 1.0), (0.4, 1.0), SPRAY_AIR_SHARE, (0.0, 0.05), (0.0, 0.08),
        (0.0, SPRAY_UPDRAUGHT)),
    2: ((0.8, 1.25), None, (0.6, 1.0)),
    3: ((0.8, 1.25), (0.2, 0.5), (0.3, 0.7), None),
    4: ((0.8, 1.25), (0.8, 1.15), (-0.1, 0.5), None),
}
_UNIFORM_LO = {k: np.array([[0.0 if r is None else r[0]] for r in rows]) for k, rows in _UNIFORMS.items()}
_UNIFORM_SPAN = {k: np.array([[1.0 if r is None else r[1] - r[0]] for r in rows]) for k, rows in _UNIFORMS.items()}


def _rows(a: np.ndarray, idx) -> np.ndarray:
    """a[idx] for a 2-D a: np.take, several times faster than fancy indexing on these small arrays."""
    return a.take(idx, axis=0)


def _uniform_rows(rng, k: int, m: int) -> np.ndarray:
    """Bucket k's uniform draws (rows in ``_UNIFORMS[k]`` order, (rows, m)): the same numbers as the reference's
    one-by-one ``rng.uniform``/``rng.random`` calls (lo + (hi − lo)·u; 1·u + 0 is u)."""
    return _UNIFORM_LO[k] + _UNIFORM_SPAN[k] * rng.random((len(_UNIFORMS[k]), m))


def launch_droplets(rng, geo: WheelGeometry, w, bucket, age_now):
    """:func:`launch_droplets_reference` with the parcels sorted by bucket (a stable sort keeps each bucket's
    order, so the same random numbers go to the same parcels), through :func:`launch_droplets_sorted`; the
    results are put back in the callers' order."""
    n = len(w)
    order = np.argsort(bucket, kind="stable")
    bounds = np.searchsorted(bucket[order], np.arange(6))
    out = launch_droplets_sorted(rng, geo, w[order], bounds, age_now[order], order=order)
    back_to = np.empty(n, dtype=np.int64)
    back_to[order] = np.arange(n)
    return tuple(a[back_to] for a in out)


def wheel_table(geo: WheelGeometry) -> np.ndarray:
    """The per-wheel quantities the launches read, side by side, (W, 15): wheel velocity (3), contact (3), travel
    (3), outward (3), radius, width, speed — so a frame's parcels gather them in one ``np.take``. Made once per
    geometry (the emitter makes one per frame)."""
    table = getattr(geo, "_wheel_table", None)
    if table is None:
        table = np.column_stack([geo.wheel_velocity, geo.contacts, geo.travel, geo.outward, geo.radius, geo.width,
                                 geo.speed])
        geo._wheel_table = table
    return table


# Per bucket: the lognormal's median, log-σ, min and max, the parcel's start size and spread rate (columns).
_BUCKET_TABLE = np.column_stack([_SIZES, _SIGMA0, _GROWTH])
# Side (3) and bow (4) waves share one formula with these per-bucket constants: the start ahead of the contact
# (× radius), its height (m), and the lift law a + b·u² (× speed).
_WAVE_TABLE = np.array([[0.3, 0.005, 0.04, 0.3], [0.9, 0.01, 0.08, 0.35]])


def _draws(rng, d_mm, bounds, ks):
    """Each bucket of ``ks`` in turn: its size's normal draw (into d_mm) and its uniform draws, the reference's
    order; returns the uniform rows of the buckets side by side, (rows, parcels), or None if they have none."""
    rows = []
    for k in ks:
        lo, hi = int(bounds[k]), int(bounds[k + 1])
        if hi > lo:
            if d_mm.flags.c_contiguous:
                rng.standard_normal(out=d_mm[lo:hi])  # the same draws as standard_normal(hi − lo), in place
            else:
                d_mm[lo:hi] = rng.standard_normal(hi - lo)
            rows.append(_uniform_rows(rng, k, hi - lo))
    if not rows:
        return None
    return rows[0] if len(rows) == 1 else np.concatenate(rows, axis=1)


def launch_droplets_sorted(rng, geo: WheelGeometry, w, bounds, age_now, out=None, order=None):
    """The droplet launches of parcels already sorted by bucket (bucket k is rows bounds[k]:bounds[k + 1]), as
    the emitter makes them: every bucket is a contiguous slice, the per-wheel quantities are gathered once for
    all parcels (:func:`wheel_table`), each bucket's uniform draws are one generator call, and the buckets that
    share a formula (spray 0–1, side and bow waves 3–4) are computed together. Writes (p0, v0, d_mm, sigma0,
    growth, air, updraught) into ``out`` (arrays of at least len(w) rows) if given; returns them. ``order``: the
    sort that made these rows (only for the ``across`` draw, which the reference makes in the callers' order)."""
    n = len(w)
    if out is None:
        out = (np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty(n), np.empty(n), np.empty((n, 3)),
               np.empty(n))
    p0, v0, d_mm, sigma0, growth, air, updraught = (a[:n] for a in out)
    across = rng.random(n) - 0.5  # where on the tread width (× b below)
    if order is not None:
        across = across[order]
    rows = wheel_table(geo).take(w, axis=0)
    vel = rows[:, 0:3]
    c = rows[:, 3:6] - vel * age_now[:, None]  # where the contact patch was at birth
    f, o = rows[:, 6:9], rows[:, 9:12]
    r, b, v = rows[:, 12:13], rows[:, 13:14], rows[:, 14:15]
    across = across[:, None] * b
    counts = bounds[1:6] - bounds[:5]
    per = _BUCKET_TABLE.repeat(counts, axis=0)  # (n, 6) each parcel's bucket's constants
    b0, b2, b3, b5 = int(bounds[0]), int(bounds[2]), int(bounds[3]), int(bounds[5])
    # Spray (buckets 0 and 1; see the reference for the physics of each bucket).
    u = _draws(rng, d_mm, bounds, (0, 1))
    if u is not None:
        sl = slice(b0, b2)
        sigma0[sl] = u[0]
        cs, fs, os_, vs, rs, vels = c[sl], f[sl], o[sl], v[sl], r[sl], vel[sl]
        back, up, out_ = rs * u[1, :, None], rs * u[2, :, None], b[sl] * u[3, :, None]
        p0[sl] = cs - fs * back + os_ * out_
        p0[sl, 1] += up[:, 0]
        share = u[4, :, None]
        np.multiply(vels, share, out=air[sl])
        v0[sl] = air[sl] + vs * (os_ * u[6, :, None])
        v0[sl, 1] += (vs * u[5, :, None])[:, 0]
        updraught[sl] = u[7]
    air[b2:] = 0.0
    updraught[b2:] = 0.0
    # Tread pickup (bucket 2).
    u = _draws(rng, d_mm, bounds, (2,))
    if u is not None:
        sl = slice(b2, b3)
        m = b3 - b2
        sigma0[sl] = u[0]
        cs, fs, os_, vs, rs, vels = c[sl], f[sl], o[sl], v[sl], r[sl], vel[sl]
        alpha = np.radians(5.0 + 45.0 * u[1] ** 1.6)[:, None]
        speed = vs * u[2, :, None]
        lateral = vs * (0.1 + 0.12 * rng.standard_normal(m))[:, None]  # rng.normal(0.1, 0.12), bit for bit
        ca, sa = np.cos(alpha), np.sin(alpha)
        p0[sl] = cs - fs * (rs * sa) + os_ * across[sl]
        p0[sl, 1] += (rs * (1.0 - ca))[:, 0]
        v0[sl] = vels - fs * (speed * ca) + os_ * lateral
        v0[sl, 1] += (speed * sa)[:, 0]
    # Side waves (3) and bow waves (4).
    u = _draws(rng, d_mm, bounds, (3, 4))
    if u is not None:
        sl = slice(b3, b5)
        sigma0[sl] = u[0]
        cs, fs, os_, vs, rs = c[sl], f[sl], o[sl], v[sl], r[sl]
        k = _WAVE_TABLE.repeat(counts[3:5], axis=0)
        n3 = int(counts[3])
        aside = np.empty((b5 - b3, 1))
        np.divide(b[b3:b3 + n3], 2.0, out=aside[:n3])  # side waves leave at the tread's edge
        aside[n3:] = across[b3 + n3:b5]
        p0[sl] = cs + fs * (k[:, 0:1] * rs) + os_ * aside
        p0[sl, 1] += k[:, 1]
        lift = k[:, 2] + k[:, 3] * u[3] ** 2
        v0[sl] = vs * (fs * u[1, :, None] + os_ * u[2, :, None])
        v0[sl, 1] += (vs * lift[:, None])[:, 0]
    # _lognormal and the parcel sizes of every bucket at once (the same operations, parcel by parcel).
    np.minimum(np.maximum(per[:, 0] * np.exp(per[:, 1] * d_mm), per[:, 2]), per[:, 3], out=d_mm)
    np.multiply(per[:, 4], sigma0, out=sigma0)
    growth[:] = per[:, 5]
    return p0, v0, d_mm, sigma0, growth, air, updraught


# The mist's uniform draws, in the reference's order: behind, up, aside, lift, wake share, sideways speed, size.
_MIST_UNIFORMS = ((0.0, 0.8), (0.4, 1.4), (-0.2, 0.2), WAKE_LIFT, WAKE_SHARE, (0.0, 0.06), (0.8, 1.3))
_MIST_LO = np.array([[lo] for lo, _ in _MIST_UNIFORMS])
_MIST_SPAN = np.array([[hi - lo] for lo, hi in _MIST_UNIFORMS])  # hi − lo as rng.uniform computes it


def launch_mist(rng, geo: WheelGeometry, w, bucket, age_now, out=None):
    """Mist puffs: released behind the wheel into the wake, which carries them forward at a share of the
    vehicle's speed; spread rate 2K (m²/s) from the wake's eddy diffusivity. ``out``: as for
    :func:`launch_droplets_sorted`."""
    n = len(w)
    vi = w // 4
    rows = wheel_table(geo).take(w, axis=0)
    vel = rows[:, 0:3]
    c = rows[:, 3:6] - vel * age_now[:, None]
    f, o = rows[:, 6:9], rows[:, 9:12]
    r, v = rows[:, 12:13], rows[:, 14:15]
    # Its seven uniform draws (_MIST_UNIFORMS) in one call, as _uniform_rows: (7, n, 1).
    u = (_MIST_LO + _MIST_SPAN * rng.random((7, n)))[..., None]
    # The fine spray of every wheel is drawn into the wake: puffs start just behind the body, in line with the
    # wheel (the air beside the body streams along it; behind it, it recirculates).
    axle_to_tail = geo.half_length[vi] - np.einsum("nc,nc->n", c - _rows(geo.position, vi), -_rows(geo.forward, vi))
    behind = np.maximum(axle_to_tail, 0.0)[:, None] + u[0]
    p0 = c - f * behind + _UP * (r * u[1]) + o * u[2]
    # The wake's recirculation lifts the mist to about the vehicle's height: upward speed ∝ v·height.
    height = geo.height.take(vi)
    lift = v * u[3] * (height / WAKE_LIFT_HEIGHT_M)[:, None]
    v0 = vel * u[4] + _UP * lift + o * (v * u[5])
    sigma0 = MIST_SIGMA0_M * u[6, :, 0]
    # K per vehicle, then per puff (np.linalg.norm(·, axis=1) is sqrt(add.reduce(x·x, axis=1)): the same bits).
    vel_v = geo.velocity
    diffusivity = (MIST_DIFFUSIVITY * np.sqrt(np.add.reduce(vel_v * vel_v, axis=1)) * geo.height).take(vi)
    if out is None:
        return p0, v0, np.full(n, MIST_D_MM), sigma0, 2.0 * diffusivity, np.zeros((n, 3)), np.zeros(n)
    dst = [a[:n] for a in out]
    dst[0][:], dst[1][:], dst[2][:], dst[3][:], dst[4][:], dst[5][:], dst[6][:] = (
        p0, v0, MIST_D_MM, sigma0, 2.0 * diffusivity, 0.0, 0.0)
    return tuple(dst)


def carrier_air_and_tau(wind, air, updraught, v0, d_mm, vt, nd: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, speed, τ) of freshly launched parcels, droplets first (``nd`` of them) then mist: u (n, 3) m/s the air
    they move in (``wind`` plus each parcel's ``air``, minus the part ``1 − updraught`` of its terminal fall
    ``vt`` m/s), speed (n,) m/s their launch speed relative to it, τ (n,) s the drag time constant (droplets by
    their size ``d_mm`` and that speed; mist WAKE_TAU_S). One formula for the emitter's reference and fast
    paths."""
    u = wind + air
    u[:, 1] -= vt * (1.0 - updraught)
    excess = v0 - u
    speed = np.sqrt(np.einsum("nc,nc->n", excess, excess))
    tau = np.empty(len(u))
    tau[:nd] = drag_time_constant_unchecked(d_mm[:nd], speed[:nd], vt[:nd])
    tau[nd:] = WAKE_TAU_S
    return u, speed, tau


# The compiled launches' tables (kernels.launch): each bucket's uniform rows padded to 8 (lo 0, span 1: a plain
# draw), the mist's rows, and its constants.
_UNIFORM_ROWS = tuple(len(_UNIFORMS[k]) for k in range(5))
_UNIFORM_LO_TABLE = np.zeros((5, 8))
_UNIFORM_SPAN_TABLE = np.ones((5, 8))
for _k in range(5):
    _UNIFORM_LO_TABLE[_k, :_UNIFORM_ROWS[_k]] = _UNIFORM_LO[_k][:, 0]
    _UNIFORM_SPAN_TABLE[_k, :_UNIFORM_ROWS[_k]] = _UNIFORM_SPAN[_k][:, 0]
_MIST_LO_ROW, _MIST_SPAN_ROW = _MIST_LO[:, 0].copy(), _MIST_SPAN[:, 0].copy()
_MIST_CONSTS = np.array([WAKE_LIFT_HEIGHT_M, MIST_SIGMA0_M, MIST_D_MM, MIST_DIFFUSIVITY])
# kernels.launch_to_records takes the four per-bucket tables as one argument.
LAUNCH_TABLES = (_BUCKET_TABLE, _UNIFORM_LO_TABLE, _UNIFORM_SPAN_TABLE, _WAVE_TABLE)


def draws_needed(n: int) -> int:
    """Size of the draws buffer :func:`launch_parcels_compiled` needs for n parcels (≤ 8 uniform rows, the
    tread's across and lateral normal each)."""
    return 10 * n


def launch_parcels_compiled(rng, geo: WheelGeometry, w, bounds, nd: int, age_now, out, vehicle, vehicle_consts,
                            draws, offs) -> None:
    """What :func:`launch_droplets_sorted` (rows [:nd]) and :func:`launch_mist` (the rest) write into ``out``,
    by ``kernels.launch``: the same generator calls in the same order here (into ``draws``, a flat float64
    buffer of at least draws_needed(len(w)), with their offsets in ``offs`` (7,) int64), the arithmetic there.
    ``vehicle``: spawn's (V, 20) vehicle table; ``vehicle_consts`` (V, ≥ 2) height and half length."""
    draw_launches(rng, bounds, nd, len(w), draws, offs, out[2])
    p0, v0, d_mm, sigma0, growth, air, updraught = out
    kernels.launch(w, bounds, nd, age_now, draws, offs, wheel_table(geo), vehicle, vehicle_consts, _BUCKET_TABLE,
                   _UNIFORM_LO_TABLE, _UNIFORM_SPAN_TABLE, _WAVE_TABLE, _MIST_LO_ROW, _MIST_SPAN_ROW, _MIST_CONSTS,
                   p0, v0, d_mm, sigma0, growth, air, updraught)


def draw_launches(rng, bounds, nd: int, n: int, draws, offs, d_mm) -> None:
    """The generator calls of :func:`launch_parcels_compiled` for n parcels (droplets [:nd], bucket k in rows
    bounds[k]:bounds[k + 1], then mist), in the twins' order: the droplets' size normals into ``d_mm``, the other
    draws into ``draws`` with their offsets in ``offs`` (what ``kernels.launch`` reads)."""
    nm = n - nd
    pos = 0
    if nd:
        rng.random(out=draws[:nd])  # the tread position's ``across``
        pos = nd
        b = bounds.tolist()
        for k in range(5):
            lo, hi = b[k], b[k + 1]
            offs[k] = pos
            if hi > lo:
                m = hi - lo
                rng.standard_normal(out=d_mm[lo:hi])
                rows = _UNIFORM_ROWS[k]
                rng.random(out=draws[pos:pos + rows * m].reshape(rows, m))
                pos += rows * m
                if k == 2:  # the tread pickup's lateral speed, after its uniforms
                    offs[5] = pos
                    rng.standard_normal(out=draws[pos:pos + m])
                    pos += m
    if nm:
        offs[6] = pos
        rng.random(out=draws[pos:pos + 7 * nm].reshape(7, nm))
