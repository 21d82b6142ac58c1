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



def _inside(x, y, z, box):
    """``BodyBox.contains`` for local coordinates (n, k) and per-row box fields ``box`` (8 arrays of (n, 1))."""
    hw, hl, floor, height, hwb, well_hl, well_top, well_x = box
    ax, az = np.abs(x), np.abs(z)
    in_box = (ax < hw) & (y > floor) & (y < height) & (az < hl)
    in_well = (np.abs(az - hwb) < well_hl) & (y < well_top) & (ax > well_x)
    return in_box & ~in_well


@lru_cache(maxsize=8)
def _steps(k: int) -> np.ndarray:
    """(k, 1) float32 fractions 1/k … 1 of a search window (made once per k)."""
    return (np.arange(1, k + 1, dtype=np.float32) / np.float32(k))[:, None]


def body_hit_time_fast(p0, v0, u, tau, t_max, body_origin, body_velocity, right, forward, box_params,
                       samples: int = 12, zoom: int = 16, rounds: int = 2) -> np.ndarray:
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
    # Local coordinates (right, up, back) of the start, the relative drift and the excess: (3, n) each. The
    # bodies turn about +Y only, so right and forward lie in the x–z plane. (Written into one buffer: np.stack
    # costs more than the arithmetic on a frame's few hundred drops.)
    vecs = np.empty((3, n, 3))
    np.subtract(p0, body_origin, out=vecs[0])
    np.subtract(u, body_velocity, out=vecs[1])
    np.subtract(v0, u, out=vecs[2])
    vx, vz = vecs[..., 0], vecs[..., 2]
    local = np.empty((3, 3, n))  # (vectors, axes, drops)
    np.add(vx * right[:, 0], vz * right[:, 2], out=local[:, 0])
    local[:, 1] = vecs[..., 1]
    np.add(vx * forward[:, 0], vz * forward[:, 2], out=local[:, 2])
    np.negative(local[:, 2], out=local[:, 2])
    P, U, D = local
    box = box_params.T  # (8, n)
    # Per axis (x, y, z) the faces: |x| < half width, floor < y < height, |z| < half length.
    upper = box[[0, 3, 1]]
    lower = np.negative(upper)
    lower[1] = box[2]
    tau_ = np.asarray(tau, dtype=np.float64)
    # Beyond the body for good: past the face each coordinate moves away from, from t_out on, where the
    # coordinate's linear bound crosses that face (U = 0: never).
    lo_b = P + np.minimum(D, 0.0) * tau_  # coordinate ≥ lo_b + U·t when U ≥ 0
    hi_b = P + np.maximum(D, 0.0) * tau_  # ≤ hi_b + U·t when U ≤ 0
    rising = U > 0.0
    exit_t = np.where(rising, upper, lower)
    exit_t -= np.where(rising, lo_b, hi_b)
    np.divide(exit_t, U, out=exit_t, where=U != 0.0)
    exit_t[U == 0.0] = np.inf
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
    P, U, D = (a[:, rows].astype(f32) for a in (P, U, D))
    tau_r = tau_[rows].astype(f32)
    rate = -1.0 / tau_r
    bx = box[:, rows].astype(f32)

    one = f32(1.0)

    def inside(t, coarse=False):  # (m, k) ages → (m, k) inside the body
        if coarse:
            # The first, coarse pass: 1 − e^(−t/τ) with exp, not expm1 (NumPy's float32 exp is vectorised, ~20×
            # faster than its expm1, a scalar loop). The cancellation moves a point ≲ 1e-7·τ·|D| (≪ 1 mm): it
            # only picks the interval the zoom then searches with expm1.
            rel = tau_r * (one - np.exp(t * rate))
        else:
            rel = tau_r * -np.expm1(t * rate)
        return _inside(P[0] + U[0] * t + D[0] * rel, P[1] + U[1] * t + D[1] * rel, P[2] + U[2] * t + D[2] * rel,
                       bx)

    steps = _steps(samples)
    end = t_end[rows].astype(f32)
    ts = end * steps
    hit = inside(ts, coarse=True)
    any_hit = hit.any(axis=0)
    if not any_hit.any():
        return result
    keep = any_hit.nonzero()[0]
    first = hit[:, keep].argmax(axis=0)
    hi = ts[first, keep]
    lo = np.where(first > 0, ts[np.maximum(first - 1, 0), keep], f32(0.0))
    P, U, D, bx = (a[:, keep] for a in (P, U, D, bx))
    tau_r, rate = tau_r[keep], rate[keep]
    zsteps = _steps(zoom)
    idx = np.arange(len(keep))
    for _ in range(rounds):
        ts = lo + (hi - lo) * zsteps
        ts[-1] = hi  # exactly the previous ``hi``, known inside
        first = inside(ts).argmax(axis=0)
        hi = ts[first, idx]
        lo = np.where(first > 0, ts[np.maximum(first - 1, 0), idx], lo)
    result[rows[keep]] = lo
    return result
