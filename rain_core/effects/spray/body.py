"""Vehicle bodies for the spray's collision test: a box with open wheel wells, moving with its vehicle."""

from __future__ import annotations

from dataclasses import dataclass

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

