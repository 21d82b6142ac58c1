"""Vehicle bodies for the spray's collision test: a box with open wheel wells, moving with its vehicle."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from rain_core.effects.spray.flight import flight_position


@dataclass(frozen=True)
class BodyBox:
    """A vehicle body for the spray's collision test, local frame (forward −Z, right +X, up +Y), m: the box
    |x| < half_width, floor_y < y < height, |z| < half_length, with open wheel wells around the axles at
    z = ±half_wheelbase (|Δz| < well_half_length, y < well_top, |x| > well_inner_x)."""

    half_width: float
    half_length: float
    floor_y: float
    height: float
    half_wheelbase: float
    well_half_length: float
    well_top: float
    well_inner_x: float

    @staticmethod
    def of(spec) -> BodyBox:
        r = spec.wheel_radius_m
        floor = 0.5 * r if spec.kind == "car" else r  # ground clearance: cars low, vans and lorries high
        return BodyBox(spec.width_m / 2.0, spec.length_m / 2.0, floor, spec.height_m, spec.wheelbase_m / 2.0,
                       r + 0.1, 2.0 * r + 0.05, spec.track_m / 2.0 - spec.tire_width_m / 2.0 - 0.05)

    def contains(self, local) -> np.ndarray:
        """Whether local points (..., 3) m lie inside the body (wheel wells excluded)."""
        x, y, z = np.abs(local[..., 0]), local[..., 1], local[..., 2]
        box = (x < self.half_width) & (y > self.floor_y) & (y < self.height) & (np.abs(z) < self.half_length)
        in_well_z = np.abs(np.abs(z) - self.half_wheelbase) < self.well_half_length
        well = in_well_z & (y < self.well_top) & (x > self.well_inner_x)
        return box & ~well


def body_hit_time(p0, v0, u, tau, t_max, body_origin, body_velocity, right, forward, boxes: list[BodyBox],
                  box_index, samples: int = 20, refine: int = 12) -> np.ndarray:
    """First age (s, ≤ t_max) at which each drop is inside its thrower's body, else t_max.

    The body moves at body_velocity (m/s) from body_origin (m, the vehicle's ground point at the drop's birth)
    without turning (right/forward: its unit axes). Per drop: p0, v0, u (n, 3), tau, t_max (n,),
    body_origin, body_velocity, right, forward (n, 3); box_index (n,) into ``boxes``. The flight is sampled
    at ``samples`` ages (denser early) and the first entry refined by bisection; the returned age is the last
    one found outside, so the drop is drawn only up to the body's surface."""
    n = len(tau)
    if n == 0:
        return np.zeros(0)
    frac = (np.arange(1, samples + 1) / samples) ** 2
    ts = t_max[:, None] * frac[None, :]  # (n, S)

    def inside(t):  # t (n, k) → (n, k) bool
        pos = flight_position(p0[:, None, :], v0[:, None, :], u[:, None, :], tau[:, None], t)
        rel = pos - (body_origin[:, None, :] + body_velocity[:, None, :] * t[..., None])
        local = np.stack([np.einsum("nkc,nc->nk", rel, right), rel[..., 1],
                          -np.einsum("nkc,nc->nk", rel, forward)], axis=-1)
        out = np.zeros(t.shape, dtype=bool)
        for i, box in enumerate(boxes):
            sel = box_index == i
            if sel.any():
                out[sel] = box.contains(local[sel])
        return out

    hit = inside(ts)
    any_hit = hit.any(axis=1)
    result = np.asarray(t_max, dtype=np.float64).copy()
    if not any_hit.any():
        return result
    first = np.argmax(hit, axis=1)
    rows = np.nonzero(any_hit)[0]
    hi = ts[rows, first[rows]]
    lo = np.where(first[rows] > 0, ts[rows, np.maximum(first[rows] - 1, 0)], 0.0)
    sub = (p0[rows], v0[rows], u[rows], tau[rows], body_origin[rows], body_velocity[rows], right[rows],
           forward[rows], box_index[rows])

    def inside_rows(t):
        pos = flight_position(sub[0], sub[1], sub[2], sub[3], t)
        rel = pos - (sub[4] + sub[5] * t[:, None])
        local = np.stack([np.einsum("nc,nc->n", rel, sub[6]), rel[:, 1], -np.einsum("nc,nc->n", rel, sub[7])],
                         axis=-1)
        out = np.zeros(len(t), dtype=bool)
        for i, box in enumerate(boxes):
            sel = sub[8] == i
            if sel.any():
                out[sel] = box.contains(local[sel])
        return out

    for _ in range(refine):
        mid = 0.5 * (lo + hi)
        ins = inside_rows(mid)
        hi = np.where(ins, mid, hi)
        lo = np.where(ins, lo, mid)
    result[rows] = lo
    return result



def _inside(local, faces, well):
    """``BodyBox.contains`` for local coordinates ``local`` (3, m, k) (right, up, back) and per-drop box fields:
    ``faces`` (2, 3, 1, k) the lower and upper face of each axis (−half width, floor, −half length; half width,
    height, half length: −h < x < h is |x| < h exactly), ``well`` (4, k) half wheelbase, well half length, well
    top and well inner x."""
    hwb, well_hl, well_top, well_x = well
    in_box = ((local > faces[0]) & (local < faces[1])).all(axis=0)
    ax, az = np.abs(local[::2])
    in_well = (np.abs(az - hwb) < well_hl) & (local[1] < well_top) & (ax > well_x)
    return in_box > in_well  # in_box & ~in_well


@lru_cache(maxsize=8)
def _steps(k: int) -> np.ndarray:
    """(k, 1) float32 fractions 1/k … 1 of a search window (made once per k)."""
    return (np.arange(1, k + 1, dtype=np.float32) / np.float32(k))[:, None]


# body_hit_time_fast's search: coarse samples, then rounds of zoom ages (its compiled twin reads them too).
SAMPLES, ZOOM, ROUNDS = 12, 16, 2


def body_hit_time_fast(p0, v0, u, tau, t_max, body_origin, body_velocity, right, forward, box_params,
                       samples: int = SAMPLES, zoom: int = ZOOM, rounds: int = ROUNDS) -> np.ndarray:
    """First age (s, ≤ t_max) at which each drop is inside its thrower's body, else t_max: what
    :func:`body_hit_time` (the reference) finds, in fewer and narrower NumPy passes.

    The flight is written once in the body's moving frame, local(t) = P + U·t + D·τ(1 − e^(−t/τ)) (P the start,
    U the drift relative to the body, D the launch excess, projected on its axes); since 0 ≤ τ(1 − e^(−t/τ)) ≤ τ,
    each coordinate has linear bounds, which give the time after which the drop is for good beyond the body's
    length, width or below its floor. Only that window is searched: ``samples`` equal steps find the first
    entry, then ``rounds`` passes of ``zoom`` ages narrow it (16² = 256×); the returned age is the last one found
    outside. All vehicles' boxes are tested together (``box_params`` (n, 8): the BodyBox fields per drop), in
    float32 (positions to a few µm). Drops that never come near the body skip the search."""
    n = len(tau)
    result = np.asarray(t_max, dtype=np.float64).copy()
    if n == 0:
        return result
    # Local coordinates (right, up, back) of the start, the relative drift and the excess, (vectors, axes, drops)
    # in one array, so each step below is one NumPy call for all three (the calls, not the arithmetic on a
    # frame's few hundred drops, are the cost). The bodies turn about +Y only: right and forward lie in the
    # x–z plane, and x·r_x + z·r_z is the products' sum in that order.
    vecs = np.empty((3, n, 3))
    np.subtract(p0, body_origin, out=vecs[0])
    np.subtract(u, body_velocity, out=vecs[1])
    np.subtract(v0, u, out=vecs[2])
    flat = vecs[..., ::2]
    local = np.empty((3, 3, n))
    on_right = flat * right[:, ::2]
    np.add(on_right[..., 0], on_right[..., 1], out=local[:, 0])
    local[:, 1] = vecs[..., 1]
    on_fwd = flat * forward[:, ::2]
    np.add(on_fwd[..., 0], on_fwd[..., 1], out=local[:, 2])
    np.negative(local[:, 2], out=local[:, 2])
    P, U, D = local
    box = box_params.T  # (8, n)
    # Per axis (x, y, z) the faces: |x| < half width, floor < y < height, |z| < half length.
    faces = np.empty((2, 3, n))
    lower, upper = faces
    box.take([0, 3, 1], axis=0, out=upper)
    np.negative(upper, out=lower)
    lower[1] = box[2]
    tau_ = np.asarray(tau, dtype=np.float64)
    # Beyond the body for good: past the face each coordinate moves away from, from t_out on, where the
    # coordinate's linear bound crosses that face (U = 0: never).
    lo_b = P + np.minimum(D, 0.0) * tau_  # coordinate ≥ lo_b + U·t when U ≥ 0
    hi_b = P + np.maximum(D, 0.0) * tau_  # ≤ hi_b + U·t when U ≤ 0
    rising = U > 0.0
    exit_t = np.where(rising, upper, lower)
    exit_t -= np.where(rising, lo_b, hi_b)
    still = U == 0.0
    np.divide(exit_t, U, out=exit_t, where=~still)
    exit_t[still] = np.inf
    t_end = np.minimum(np.maximum(exit_t.min(axis=0), 0.0), t_max)
    # Never near: the whole flight's bounds miss the box.
    span_lo = lo_b + np.minimum(U, 0.0) * t_end
    span_hi = hi_b + np.maximum(U, 0.0) * t_end
    near = (span_lo < upper).all(axis=0) & (span_hi > lower).all(axis=0) & (t_end > 0.0)
    rows = near.nonzero()[0]
    if len(rows) == 0:
        return result
    f32 = np.float32
    # Ages run along the first axis, drops along the second (m, k): each drop's constants are then (k,) rows that
    # broadcast over a contiguous inner loop of k drops. Laid out (k, m), the inner loop is the m ≤ 16 ages with
    # the constants at stride 0, which NumPy buffers and copies: most of this search's cost, for the same values.
    # (Negating, then rounding to float32, is rounding, then negating: the faces stay symmetric.)
    local = local.take(rows, axis=-1).astype(f32)[:, :, None]  # (vectors, axes, 1, k), k contiguous
    faces = faces.take(rows, axis=-1).astype(f32)[:, :, None]
    well = box[4:8, rows].astype(f32)
    tau_r = tau_[rows].astype(f32)
    rate = -1.0 / tau_r

    one = f32(1.0)

    def inside(t, coarse=False):  # (m, k) ages → (m, k) inside the body
        # −τ(1 − e^(−t/τ)), the negated relaxation (negation is exact: the same bits as negating the result).
        if coarse:
            # The first, coarse pass: e^(−t/τ) − 1 with exp, not expm1 (cheaper on NumPy builds whose float32
            # expm1 is a scalar loop). The cancellation moves a point ≲ 1e-7·τ·|D| (≪ 1 mm): it only picks the
            # interval the zoom then searches with expm1.
            rel = np.exp(t * rate)
            rel -= one
        else:
            rel = np.expm1(t * rate)
        rel *= tau_r
        # P + U·t + D·rel for the three axes at once, in that order (the same float32 operations per point):
        # + D·rel is − D·(−rel), bit for bit.
        pos = local[0] + local[1] * t
        pos -= local[2] * rel
        return _inside(pos, faces, well)

    # Row 0 age 0, rows 1… the samples (as in the zoom below: the first sample inside, at row j, leaves the
    # window rows j − 1 to j).
    ts = np.empty((samples + 1, len(rows)), dtype=f32)
    ts[0] = 0.0
    np.multiply(t_end[rows].astype(f32), _steps(samples), out=ts[1:])
    hit = inside(ts[1:], coarse=True)
    any_hit = hit.any(axis=0)
    if not any_hit.any():
        return result
    keep = any_hit.nonzero()[0]
    first = hit.argmax(axis=0)[keep]
    lo = ts[first, keep]
    hi = ts[first + 1, keep]
    local, faces, well = local.take(keep, axis=-1), faces.take(keep, axis=-1), well.take(keep, axis=-1)
    tau_r, rate = tau_r[keep], rate[keep]
    zsteps = _steps(zoom)
    idx = np.arange(len(keep))
    # Row 0 the window's start ``lo``, rows 1… its ages: the first age inside, at row j, leaves the window
    # rows j - 1 (outside, or ``lo``) to j.
    ts = np.empty((zoom + 1, len(keep)), dtype=f32)
    for _ in range(rounds):
        ts[0] = lo
        np.add(lo, (hi - lo) * zsteps, out=ts[1:])
        ts[-1] = hi  # exactly the previous ``hi``, known inside
        first = inside(ts[1:]).argmax(axis=0)
        lo = ts[first, idx]
        hi = ts[first + 1, idx]
    result[rows[keep]] = lo
    return result
