"""The drop slots: a fixed-size pool with a free list, and a calendar of when each live slot is due for a check."""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.rainfall.constants import CALENDAR_BUCKET_S, CALENDAR_BUCKETS


class DropPool:
    """A fixed-size buffer of drop slots with a free list, and a calendar of when each live slot is due.

    ``allocate(n)`` pops up to n free slots (lowest first at the start), ``release(slots)`` returns them,
    ``schedule(slots, due_s)`` files live slots under their due time, ``pop_due(t)`` returns the live slots due
    by time t (each once per schedule). Invariant (``check``): live + free = capacity, no slot twice."""

    def __init__(self, capacity: int):
        if capacity < 0:
            raise ValueError(f"capacity must be ≥ 0, got {capacity}")
        self.capacity = int(capacity)
        self.alive = np.zeros(self.capacity, dtype=bool)
        self._free = np.arange(self.capacity, dtype=np.int64)[::-1].copy()
        self._n_free = self.capacity
        self._due = np.full(self.capacity, -1, dtype=np.int64)
        self._buckets: list[list[tuple[np.ndarray, int]]] = [[] for _ in range(CALENDAR_BUCKETS)]
        self._last_bucket: int | None = None
        self.high_water = 0  # one past the highest slot ever allocated (the GPU draws this many)
        self.overflow = 0  # spawns refused because the buffer was full (cumulative)

    @property
    def live(self) -> int:
        return self.capacity - self._n_free

    @property
    def n_free(self) -> int:
        return self._n_free

    def free_slots(self) -> np.ndarray:
        return self._free[: self._n_free].copy()

    def allocate(self, n: int) -> np.ndarray:
        n = int(min(max(n, 0), self._n_free))
        slots = self._free[self._n_free - n: self._n_free][::-1].copy()
        self._n_free -= n
        self.alive[slots] = True
        if n:
            self.high_water = max(self.high_water, int(slots.max()) + 1)
        return slots

    def release(self, slots: np.ndarray) -> None:
        slots = np.asarray(slots, dtype=np.int64)
        if slots.size == 0:
            return
        if not self.alive[slots].all() or np.unique(slots).size != slots.size:
            raise RuntimeError("DropPool.release: a slot is not live or appears twice")
        self.alive[slots] = False
        self._due[slots] = -1
        self._free[self._n_free: self._n_free + slots.size] = slots[::-1]
        self._n_free += slots.size

    def _bucket(self, t: float) -> int:
        return int(math.floor(t / CALENDAR_BUCKET_S))

    def schedule(self, slots: np.ndarray, due_s: np.ndarray, now_s: float) -> None:
        slots = np.asarray(slots, dtype=np.int64)
        if slots.size == 0:
            return
        now = self._bucket(now_s)
        if self._last_bucket is None:
            self._last_bucket = now
        b = np.ceil(np.asarray(due_s, dtype=np.float64) * (1.0 / CALENDAR_BUCKET_S))  # inf: the horizon
        b = np.maximum(np.minimum(b, now + CALENDAR_BUCKETS - 1), max(now, self._last_bucket) + 1).astype(np.int64)
        self._due[slots] = b
        if b.size == 1 or b[0] == b[-1] and (b == b[0]).all():
            self._buckets[int(b[0]) % CALENDAR_BUCKETS].append((slots.copy(), int(b[0])))
            return
        order = np.argsort(b, kind="stable")
        bs, ss = b[order], slots[order]
        edges = np.concatenate([[0], np.flatnonzero(np.diff(bs)) + 1, [bs.size]]).tolist()
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            when = int(bs[lo])
            self._buckets[when % CALENDAR_BUCKETS].append((ss[lo:hi], when))

    def pop_due(self, now_s: float) -> np.ndarray:
        now = self._bucket(now_s)
        if self._last_bucket is None:
            self._last_bucket = now
            return np.zeros(0, dtype=np.int64)
        if now <= self._last_bucket:
            return np.zeros(0, dtype=np.int64)
        out = []
        first = max(self._last_bucket + 1, now - CALENDAR_BUCKETS + 1)
        for b in range(first, now + 1):
            entries = self._buckets[b % CALENDAR_BUCKETS]
            if not entries:
                continue
            self._buckets[b % CALENDAR_BUCKETS] = []
            for slots, when in entries:
                valid = slots[self.alive[slots] & (self._due[slots] == when)]
                if valid.size:
                    self._due[valid] = -1
                    out.append(valid)
        self._last_bucket = now
        return np.concatenate(out) if out else np.zeros(0, dtype=np.int64)

    def check(self) -> None:
        """Raise AssertionError if the free list and the live flags disagree (a leak or a double use)."""
        free = self._free[: self._n_free]
        assert 0 <= self._n_free <= self.capacity
        assert np.unique(free).size == free.size, "a free slot is listed twice"
        assert not self.alive[free].any(), "a live slot is on the free list"
        assert int(self.alive.sum()) + self._n_free == self.capacity, "slots leaked"
        live = np.flatnonzero(self.alive)
        assert (self._due[live] >= 0).all(), "a live slot is not scheduled"
