"""The wheels' wakes on the ripple field, the NumPy twin of ``kernels.wake_bumps``: each wheel's path over a
frame, clipped to the field's window, as a row of trough bumps with a crest on either side. Units: m, m/s, mm."""

from __future__ import annotations

import numpy as np

_EMPTY = np.zeros(0)


def wake_bumps(wheels, ox: float, oz: float, length_m: float, cell_m: float, max_radius_m: float,
               wake_gain: float, min_reach_m: float, ref_speed_m_s: float):
    """Bumps of W wheels: ``wheels`` rows (x0, z0, x1, z1 world m, speed m/s, film depth mm, tyre width m); the
    window's origin (ox, oz) m and side ``length_m``; its cell ``cell_m``, the widest bump ``max_radius_m`` and
    the smallest footprint reach ``min_reach_m`` (m); a trough is film depth × speed / ``ref_speed_m_s`` deep
    (× ``wake_gain``). Returns window x, z (m), radii (m), peaks (m) of every bump, and the bumps per wheel."""
    x0, z0, x1, z1, speed, depth_mm, width = wheels.T
    radius = np.minimum(0.5 * width, max_radius_m)
    trough = wake_gain * depth_mm * 1e-3 * speed / ref_speed_m_s
    ax, az, bx, bz, inside = clip_segments(x0 - ox, z0 - oz, x1 - ox, z1 - oz, radius + 2.0 * cell_m, length_m)
    live = inside & (trough != 0.0)
    counts = np.zeros(len(wheels), np.int64)
    if not live.any():
        return _EMPTY, _EMPTY, _EMPTY, _EMPTY, counts
    if not live.all():
        ax, az, bx, bz, radius, trough = (v[live] for v in (ax, az, bx, bz, radius, trough))
    dx, dz = bx - ax, bz - az
    length = np.hypot(dx, dz)
    count = np.maximum(1, np.ceil(length / cell_m)).astype(np.int64)
    moving = length > 0.0
    # A row of raised cosines of radius R spaced ds sums to R/ds times one peak along its axis: scale each
    # peak by ds/R so the trough depth does not depend on the frame rate or the grid.
    spacing = np.where(moving, length / count, radius)
    peak = -trough * np.minimum(spacing / radius, 1.0)
    # The water under the tyre is not lost: it is pushed out sideways (the side waves of DESIGN §3's
    # Flintsch allocation). Each trough bump gets a crest on either side, touching its rim (2 × the
    # footprint radius the solver will use off the path), each holding half its volume, so a wake leaves
    # the film's mean level unchanged (a net trough would drain the puddle). Paths of zero length (a wheel
    # that did not move) have no sideways direction: they press the trough alone.
    reach = np.maximum(radius, min_reach_m)
    with np.errstate(divide="ignore", invalid="ignore"):
        nx = np.where(moving, -dz / length, 0.0) * 2.0 * reach
        nz = np.where(moving, dx / length, 0.0) * 2.0 * reach
    # Each wheel's values to each of its bumps in one gather (the counts are exact as float64).
    wheel = np.arange(count.size).repeat(count)
    ax_, dx_, az_, dz_, count_, nx_, nz_, peak_, radius_ = np.array(
        [ax, dx, az, dz, count, nx, nz, peak, radius])[:, wheel]
    t = (np.arange(wheel.size) - (count.cumsum() - count).repeat(count) + 0.5) / count_
    xs, zs = ax_ + t * dx_, az_ + t * dz_
    if moving.all():  # every wheel rolled: crests on every bump
        sx, sz, crest, x_side, z_side, r_side = nx_, nz_, -0.5 * peak_, xs, zs, radius_
    else:
        side = moving[wheel]
        sx, sz, crest = nx_[side], nz_[side], -0.5 * peak_[side]
        x_side, z_side, r_side = xs[side], zs[side], radius_[side]
    counts[live] = count * np.where(moving, 3, 1)
    return (np.concatenate([xs, x_side + sx, x_side - sx]), np.concatenate([zs, z_side + sz, z_side - sz]),
            np.concatenate([radius_, r_side, r_side]), np.concatenate([peak_, crest, crest]), counts)



def clip_segments(ax, az, bx, bz, pad, length_m: float):
    """Liang–Barsky clip of segments (window metres, arrays) to the window [0, length_m]² grown by pad (per
    segment): the clipped ends and whether anything is left."""
    lo, hi = -pad, length_m + pad
    dx, dz = bx - ax, bz - az
    # The four edges at once, (4, W): a wheel's worth of tiny arrays costs NumPy's per-call overhead only.
    p = np.array([-dx, dx, -dz, dz])
    q = np.array([ax - lo, hi - ax, az - lo, hi - az])
    flat = p == 0.0
    inside = ~(flat & (q < 0.0)).any(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(flat, 0.0, q / np.where(flat, 1.0, p))
    t0 = np.where(p < 0.0, r, 0.0).max(axis=0)  # entering edges (and 0)
    t1 = np.where(p > 0.0, r, 1.0).min(axis=0)  # leaving edges (and 1)
    inside &= t0 <= t1
    return ax + t0 * dx, az + t0 * dz, ax + t1 * dx, az + t1 * dz, inside

