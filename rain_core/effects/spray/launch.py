"""Where and how parcels leave the wheels: the droplet launches of each water bucket (``BUCKETS``) and the mist
released into the vehicle's wake, with the wake's constants."""

from __future__ import annotations

import numpy as np

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


def launch_droplets(rng, geo: WheelGeometry, w, bucket, age_now):
    """:func:`launch_droplets_reference` with the parcels sorted by bucket (a stable sort keeps each bucket's
    order, so the same random numbers go to the same parcels): every bucket is a contiguous slice, the per-wheel
    quantities are gathered once for all parcels, and the results are put back in the callers' order."""
    n = len(w)
    across = rng.random(n) - 0.5  # where on the tread width (× b below)
    order = np.argsort(bucket, kind="stable")
    bounds = np.searchsorted(bucket[order], np.arange(6))
    ws = w[order]
    vel = geo.wheel_velocity[ws]
    c = geo.contacts[ws] - vel * age_now[order][:, None]  # where the contact patch was at birth
    f, o = geo.travel[ws], geo.outward[ws]
    r, b, v = geo.radius[ws][:, None], geo.width[ws][:, None], geo.speed[ws][:, None]
    across = across[order][:, None] * b
    p0 = np.empty((n, 3))
    v0 = np.empty((n, 3))
    d_mm = np.empty(n)
    sigma0 = np.empty(n)
    air = np.zeros((n, 3))
    updraught = np.zeros(n)
    for k in range(5):
        lo_i, hi_i = int(bounds[k]), int(bounds[k + 1])
        m = hi_i - lo_i
        if m == 0:
            continue
        sl = slice(lo_i, hi_i)
        d_mm[sl] = _lognormal(rng, *_DROPLET_SIZES[k], m)
        sigma0[sl] = _SIGMA0[k] * rng.uniform(0.8, 1.25, m)
        cs, fs, os_, vs, rs, vels = c[sl], f[sl], o[sl], v[sl], r[sl], vel[sl]
        if k < 2:  # spray (see the reference for the physics of each bucket)
            lo, hi = (0.8, 1.8) if k == 0 else (0.2, 1.0)
            back = rs * rng.uniform(1.0, 1.3, (m, 1))
            up = rs * rng.uniform(lo, hi, (m, 1))
            out = b[sl] * rng.uniform(0.4, 1.0, (m, 1))
            p0[sl] = cs - fs * back + os_ * out
            p0[sl, 1] += up[:, 0]
            share = rng.uniform(*SPRAY_AIR_SHARE, (m, 1))
            lift = rng.uniform(0.0, 0.05, (m, 1))
            side = rng.uniform(0.0, 0.08, (m, 1))
            air[sl] = vels * share
            v0[sl] = air[sl] + vs * (os_ * side)
            v0[sl, 1] += (vs * lift)[:, 0]
            updraught[sl] = rng.uniform(0.0, SPRAY_UPDRAUGHT, m)
        elif k == 2:  # tread pickup
            alpha = np.radians(5.0 + 45.0 * rng.random(m) ** 1.6)[:, None]
            speed = vs * rng.uniform(0.6, 1.0, (m, 1))
            lateral = vs * rng.normal(0.1, 0.12, (m, 1))
            ca, sa = np.cos(alpha), np.sin(alpha)
            p0[sl] = cs - fs * (rs * sa) + os_ * across[sl]
            p0[sl, 1] += (rs * (1.0 - ca))[:, 0]
            v0[sl] = vels - fs * (speed * ca) + os_ * lateral
            v0[sl, 1] += (speed * sa)[:, 0]
        elif k == 3:  # side waves
            p0[sl] = cs + fs * (0.3 * rs) + os_ * (b[sl] / 2.0)
            p0[sl, 1] += 0.005
            fwd = rng.uniform(0.2, 0.5, (m, 1))
            aside = rng.uniform(0.3, 0.7, (m, 1))
            lift = 0.04 + 0.3 * rng.random((m, 1)) ** 2
            v0[sl] = vs * (fs * fwd + os_ * aside)
            v0[sl, 1] += (vs * lift)[:, 0]
        else:  # bow waves
            p0[sl] = cs + fs * (0.9 * rs) + os_ * across[sl]
            p0[sl, 1] += 0.01
            fwd = rng.uniform(0.8, 1.15, (m, 1))
            aside = rng.uniform(-0.1, 0.5, (m, 1))
            lift = 0.08 + 0.35 * rng.random((m, 1)) ** 2
            v0[sl] = vs * (fs * fwd + os_ * aside)
            v0[sl, 1] += (vs * lift)[:, 0]
    back_to = np.empty(n, dtype=np.int64)
    back_to[order] = np.arange(n)
    growth = _GROWTH[bucket]
    return p0[back_to], v0[back_to], d_mm[back_to], sigma0[back_to], growth, air[back_to], updraught[back_to]


def launch_mist(rng, geo: WheelGeometry, w, bucket, age_now):
    """Mist puffs: released behind the wheel into the wake, which carries them forward at a share of the
    vehicle's speed; spread rate 2K (m²/s) from the wake's eddy diffusivity."""
    n = len(w)
    vi = w // 4
    c = geo.contacts[w] - geo.wheel_velocity[w] * age_now[:, None]
    f, o = geo.travel[w], geo.outward[w]
    r, v = geo.radius[w][:, None], geo.speed[w][:, None]
    vel = geo.wheel_velocity[w]
    # The fine spray of every wheel is drawn into the wake: puffs start just behind the body, in line with the
    # wheel (the air beside the body streams along it; behind it, it recirculates).
    axle_to_tail = geo.half_length[vi] - np.einsum("nc,nc->n", c - geo.position[vi], -geo.forward[vi])
    behind = np.maximum(axle_to_tail, 0.0)[:, None] + rng.uniform(0.0, 0.8, (n, 1))
    p0 = (c - f * behind + _UP * (r * rng.uniform(0.4, 1.4, (n, 1)))
          + o * rng.uniform(-0.2, 0.2, (n, 1)))
    # The wake's recirculation lifts the mist to about the vehicle's height: upward speed ∝ v·height.
    lift = v * rng.uniform(*WAKE_LIFT, (n, 1)) * (geo.height[vi] / WAKE_LIFT_HEIGHT_M)[:, None]
    v0 = vel * rng.uniform(*WAKE_SHARE, (n, 1)) + _UP * lift + o * (v * rng.uniform(0.0, 0.06, (n, 1)))
    d_mm = np.full(n, MIST_D_MM)
    sigma0 = MIST_SIGMA0_M * rng.uniform(0.8, 1.3, n)
    diffusivity = MIST_DIFFUSIVITY * np.linalg.norm(geo.velocity[vi], axis=1) * geo.height[vi]
    return p0, v0, d_mm, sigma0, 2.0 * diffusivity, np.zeros((n, 3)), np.zeros(n)

