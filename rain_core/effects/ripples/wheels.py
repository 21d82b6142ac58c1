"""What the wheels hand the ripple field each frame: their contact paths (``WheelSweep`` one by one, or
``WheelBatch`` as arrays), validated at this boundary.

NumPy only.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from rain_core import checks


@dataclass(frozen=True)
class WheelSweep:
    """One wheel's contact path over a frame: world (x, z) in m at the previous and the current frame, its
    speed in m/s, tyre width in m, and the water film depth under it in mm (None: ask film_depth_fn)."""

    p0_xz: tuple[float, float]
    p1_xz: tuple[float, float]
    speed_m_s: float
    tire_width_m: float
    film_depth_mm: float | None = None


FilmDepthFn = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class WheelBatch:
    """Many wheels' contact paths over a frame, as arrays: ``p0_xz`` and ``p1_xz`` (W, 2) world m, ``speed_m_s``
    (W,) ≥ 0, ``tire_width_m`` (W,), ``film_depth_mm`` (W,) or None (ask the film-depth function, once for all
    wheels, at the middle of each path). ``WheelBatch.of(wheels)`` also takes ``WheelSweep``s or 5-tuples."""

    p0_xz: np.ndarray
    p1_xz: np.ndarray
    speed_m_s: np.ndarray
    tire_width_m: np.ndarray
    film_depth_mm: np.ndarray | None = None
    # Checked when made (``from_rows``): ``of`` returns it as it is.
    _checked: bool = field(default=False, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return len(self.speed_m_s)

    @property
    def needs_depth(self) -> bool:
        return len(self) > 0 and (self.film_depth_mm is None or bool(np.isnan(self.film_depth_mm).any()))

    @classmethod
    def of(cls, wheels) -> WheelBatch:
        """A validated batch (ValueError naming the bad field): a WheelBatch, or an iterable of ``WheelSweep``
        or (p0, p1, speed, film depth mm or None, tyre width) tuples."""
        if isinstance(wheels, WheelBatch):
            if wheels._checked or wheels._valid():  # a batch checked before: no copies
                return wheels
            p0, p1, speed, width, depth = (wheels.p0_xz, wheels.p1_xz, wheels.speed_m_s, wheels.tire_width_m,
                                           wheels.film_depth_mm)
        else:
            rows = [(w.p0_xz, w.p1_xz, w.speed_m_s, w.film_depth_mm, w.tire_width_m) if isinstance(w, WheelSweep)
                    else tuple(w) for w in wheels]
            if not rows:
                return _NO_WHEELS
            if any(len(r) != 5 for r in rows):
                raise ValueError("each wheel must be a WheelSweep or (p0, p1, speed, film depth mm, tyre width)")
            p0, p1, speed, depth, width = zip(*rows, strict=True)
            depth = [math.nan if d is None else d for d in depth]
        p0 = checks.finite_array("p0_xz", p0).reshape(-1, 2)
        p1 = checks.finite_array("p1_xz", p1).reshape(-1, 2)
        speed = checks.array("speed_m_s", speed, 0.0, 1e3, "m/s").reshape(-1)
        width = checks.array("tire_width_m", width, 1e-3, 10.0, "m").reshape(-1)
        if depth is not None:
            depth = np.asarray(depth, dtype=np.float64).reshape(-1)
            known = ~np.isnan(depth)
            checks.array("film_depth_mm", depth[known], 0.0, 1e3, "mm")
        if not (len(p0) == len(p1) == len(speed) == len(width)) or (depth is not None and len(depth) != len(speed)):
            raise ValueError("the wheel arrays must have one entry per wheel")
        return cls(p0, p1, speed, width, depth)

    @classmethod
    def from_rows(cls, rows) -> WheelBatch:
        """A checked batch (ValueError naming the bad field, as ``of``) from rows (x0, z0, x1, z1 world m, speed
        m/s, tyre width m), ``wheel_rows``'s, film depths left to the function: the effect's batch every frame,
        checked here in one pass over one (W, 6) array, so ``update``'s ``of`` returns it as it is. Its arrays
        are views of that array: treat them as read-only."""
        a = np.array(rows, dtype=np.float64)
        if a.size == 0:
            return _NO_WHEELS
        if a.ndim != 2 or a.shape[1] != 6:
            raise ValueError(f"wheel rows must be (W, 6): x0, z0, x1, z1, speed, tyre width; got shape {a.shape}")
        batch = cls(a[:, 0:2], a[:, 2:4], a[:, 4], a[:, 5])
        # Positions finite, speed and width in range (NaN fails every comparison): a few dozen Python floats,
        # cheaper than NumPy's calls between the frame's GL work.
        big = _BIG
        for x0, z0, x1, z1, speed, width in a.tolist():
            if not (-big <= x0 <= big and -big <= z0 <= big and -big <= x1 <= big and -big <= z1 <= big
                    and 0.0 <= speed <= 1e3 and 1e-3 <= width <= 10.0):
                return cls.of(batch)  # the long way, which names what is wrong
        object.__setattr__(batch, "_checked", True)
        return batch

    def depth_points(self) -> np.ndarray:
        """(k, 2) world (x, z) in m where the unknown film depths are asked: the middle of each such path."""
        unknown = slice(None) if self.film_depth_mm is None else np.isnan(self.film_depth_mm)
        return 0.5 * (self.p0_xz[unknown] + self.p1_xz[unknown])

    def _valid(self) -> bool:
        """Whether ``of`` would return this batch unchanged: float64 arrays of matching shapes, every value in
        range (False sends ``of`` the long way, which names what is wrong)."""
        arrays = (self.p0_xz, self.p1_xz, self.speed_m_s, self.tire_width_m)
        if not all(type(a) is np.ndarray and a.dtype == np.float64 for a in arrays):
            return False
        w = len(self.speed_m_s)
        if self.speed_m_s.shape != (w,) or self.tire_width_m.shape != (w,) or self.p0_xz.shape != (w, 2) \
                or self.p1_xz.shape != (w, 2) or w == 0:
            return False
        depth = self.film_depth_mm
        if depth is not None:
            if type(depth) is not np.ndarray or depth.dtype != np.float64 or depth.shape != (w,):
                return False
            known = depth[~np.isnan(depth)]
            if known.size and not (known.min() >= 0.0 and known.max() <= 1e3):
                return False
        # Every value against its range in one pass (positions within ±the largest float: finite); NaN fails
        # every comparison, so it takes the long way too.
        lo, hi = _bounds(w)
        values = np.concatenate((self.p0_xz.reshape(-1), self.p1_xz.reshape(-1), self.speed_m_s, self.tire_width_m))
        return bool(((values >= lo) & (values <= hi)).all())

    def rows(self, film_depth_fn: FilmDepthFn | None, asked: np.ndarray | None = None) -> np.ndarray:
        """(W, 7): x0, z0, x1, z1, speed, film depth mm, tyre width; unknown depths asked in one call (or given:
        ``asked``, what film_depth_fn returned at ``depth_points()``)."""
        out = np.empty((len(self), 7))
        out[:, 0:2] = self.p0_xz
        out[:, 2:4] = self.p1_xz
        out[:, 4] = self.speed_m_s
        out[:, 6] = self.tire_width_m
        depth = out[:, 5]
        if self.film_depth_mm is None:  # every depth unknown (the effect's batch): no NaN scan
            unknown = slice(None)
        else:
            depth[:] = self.film_depth_mm
            unknown = np.isnan(depth)
            if not unknown.any():
                return out
        if asked is None:
            mid = self.depth_points()
            asked = np.broadcast_to(np.asarray(film_depth_fn(mid[:, 0], mid[:, 1]), dtype=np.float64),
                                    mid[:, 0].shape)
        # NaN → 0, the rest clamped to [0, 1e3] mm (np.clip(np.nan_to_num(…)) without their wrappers)
        depth[unknown] = np.minimum(np.maximum(np.where(np.isnan(asked), 0.0, asked), 0.0), 1e3)
        return out


@lru_cache(maxsize=8)
def _bounds(w: int) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of a valid batch of w wheels' values in ``_valid``'s order: p0, p1 (finite), speed, width."""
    big = np.finfo(np.float64).max
    lo = np.concatenate([np.full(4 * w, -big), np.zeros(w), np.full(w, 1e-3)])
    hi = np.concatenate([np.full(4 * w, big), np.full(w, 1e3), np.full(w, 10.0)])
    return lo, hi


_BIG = float(np.finfo(np.float64).max)  # finite positions lie within ±_BIG
_NO_WHEELS = WheelBatch(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0))


def wheel_rows(vehicle) -> list[tuple[float, float, float, float, float, float]]:
    """A vehicle's wheels as rows (x0, z0, x1, z1 world m, |speed| m/s, tyre width m), order FL, FR, RL, RR: the
    contact paths from ``previous_wheel_contacts`` (if any; else the current contacts) to ``wheel_contacts()``,
    and ``wheel_speeds()``'s magnitudes, in Python floats with its operations in its order (the same bits, for a
    fraction of the NumPy calls: ``RipplesEffect.wheel_batch`` asks every frame for every vehicle in the window)."""
    now = vehicle.wheel_contacts().tolist()
    before = getattr(vehicle, "previous_wheel_contacts", None)
    before = now if before is None else before.tolist()
    # Vehicle._point_velocity at each contact: v = forward·speed + ω ŷ × (p − rear axle), rear axle = position −
    # forward·wheelbase/2, forward = (−sin yaw, 0, −cos yaw); |v|² summed left to right (np.add.reduce's order).
    fx, fy, fz = -math.sin(vehicle.yaw), 0.0, -math.cos(vehicle.yaw)
    half = vehicle.spec.wheelbase_m / 2.0
    px, _, pz = vehicle.position.tolist()
    rear_x, rear_z = px - fx * half, pz - fz * half
    speed, w = vehicle.speed_m_s, vehicle.yaw_rate_rad_s
    vx, vy, vz = fx * speed, fy * speed, fz * speed
    width = float(vehicle.spec.tire_width_m)
    rows = []
    for (bx, _, bz), (cx, _, cz) in zip(before, now, strict=True):
        ux = vx + w * (cz - rear_z)
        uz = vz - w * (cx - rear_x)
        rows.append((bx, bz, cx, cz, abs(math.sqrt(ux * ux + vy * vy + uz * uz)), width))
    return rows
