"""Parcels: the drawn particles (GPU record layout), the fixed rings that hold them, and what the shader computes
from a record (position and size).

What is drawn are *parcels*: each stands for many drops of one size thrown together, carries its mass (kg) and
so its extinction cross-section A = Q·(3/2)·m/(ρ_w·D) (Q = 2), and spreads as it flies. The number of parcels
alive is the budget; their masses add up to the mass the model throws (undone remainders carry over to the
next frame), so the picture does not depend on the budget except for its graininess. Two fixed ring buffers
(droplets, mist puffs) on the GPU receive only the newly spawned parcels each frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rain_core import jit, layout
from rain_core.effects.spray import kernels
from rain_core.effects.spray.flight import flight_position, relax

# Kinds of parcel (the shader's in_misc.x; +2 = fades out at the end of its life instead of hitting something).
KIND_DROPLET, KIND_MIST, KIND_FADE = 0, 1, 2
FATE_ROAD, FATE_BODY, FATE_AIR = 0, 1, 2

PARTICLE_DTYPE = np.dtype([
    ("p0", "<f4", 3), ("period", "<f4"),  # m (z relative to period·PERIOD_M); period index
    ("v0", "<f4", 3), ("tau", "<f4"),  # m/s launch velocity; s drag time constant (mist: spread rate)
    ("u", "<f4", 3), ("birth", "<f4"),  # m/s drift velocity; s since the effect's epoch
    ("life", "<f4"), ("sigma0", "<f4"), ("growth", "<f4"), ("area", "<f4"),  # s, m, m/s or m²/s, m²
    ("kind", "<f4"), ("d_mm", "<f4"), ("rand", "<f4"), ("glint", "<f4"),  # glint: mist puffs hold σ_max (m)
])
PARTICLE_FORMAT = "4f 4f 4f 4f 4f/i"
PARTICLE_FLOATS = PARTICLE_DTYPE.itemsize // 4  # every field is float32: a record is this many floats


def as_floats(records: np.ndarray) -> np.ndarray:
    """Contiguous records as an (n, PARTICLE_FLOATS) float32 view: NumPy copies and gathers plain rows ~10×
    faster than structured ones (it moves those field by field)."""
    return records.view(np.float32).reshape(len(records), PARTICLE_FLOATS)
PARTICLE_ATTRIBUTES = ("in_p0", "in_v0", "in_u", "in_life", "in_misc")


@dataclass
class ParcelRing:
    """A fixed ring of parcels (GPU layout) with their birth/death times (float64, effect clock).

    Only what is new is touched: :meth:`push` writes the newest records over the oldest (one or two slot
    ranges, the GPU upload list); dead slots cost nothing (the shader skips a slot whose age is past its life).
    """

    capacity: int
    data: np.ndarray = field(init=False)
    death: np.ndarray = field(init=False)
    birth: np.ndarray = field(init=False)
    head: int = 0

    def __post_init__(self):
        self.data = np.zeros(self.capacity, PARTICLE_DTYPE)
        self.data["life"] = -1.0  # never drawn
        self._floats = as_floats(self.data)
        self.death = np.full(self.capacity, -np.inf)
        self.birth = np.full(self.capacity, np.inf)
        self._scratch = np.zeros(0, PARTICLE_DTYPE)
        self._last_death = -math.inf
        self._ranges = np.zeros((2, 2), dtype=np.int64)  # push_rows' slot ranges

    @property
    def floats(self) -> np.ndarray:
        """The slots as a (capacity, PARTICLE_FLOATS) float32 view of ``data``: the same bytes, for uploads (a
        memoryview of plain float rows is made ~4× faster than one of the structured records)."""
        return self._floats

    def scratch(self, n: int) -> np.ndarray:
        """A reusable record array of length n (grown when needed, never shrunk): where a frame's new records
        are assembled before :meth:`push`, without allocating one per frame. Every field must be written."""
        if len(self._scratch) < n:
            self._scratch = np.zeros(max(n, 2 * len(self._scratch)), PARTICLE_DTYPE)
        return self._scratch[:n]

    def push(self, records: np.ndarray, birth: np.ndarray, death: np.ndarray) -> list[tuple[int, int]]:
        """Write the newest records over the oldest; returns the (start, count) slot ranges written (one, or two
        where the ring wraps)."""
        n = len(records)
        if n == 0 or self.capacity == 0:
            return []
        if n > self.capacity:
            records, birth, death = records[-self.capacity:], birth[-self.capacity:], death[-self.capacity:]
            n = self.capacity
        plain = records.dtype == PARTICLE_DTYPE and records.flags.c_contiguous
        if plain and jit.active():  # the copies and the max in one call (kernels.push_rows), the same values
            out = self._ranges
            self.head, used, top = kernels.push_rows(as_floats(records), birth, death, self._floats, self.birth,
                                                     self.death, self.head, out)
            self._last_death = max(self._last_death, top)
            return [(start, count) for start, count in out[:used].tolist()]
        self._last_death = max(self._last_death, float(death.max()))
        ranges = []
        start, done = self.head, 0
        src, dst = (as_floats(records), self._floats) if plain else (records, self.data)
        while done < n:
            count = min(n - done, self.capacity - start)
            dst[start:start + count] = src[done:done + count]
            self.birth[start:start + count] = birth[done:done + count]
            self.death[start:start + count] = death[done:done + count]
            ranges.append((start, count))
            done += count
            start = (start + count) % self.capacity
        self.head = start
        return ranges

    def alive(self, now: float) -> int:
        return int(np.count_nonzero((self.birth <= now) & (self.death > now)))

    def last_death(self) -> float:
        """When the last parcel written dies (effect clock, s; −inf if none): a running maximum, O(1) per frame.
        It may be a parcel already overwritten — then the effect just runs (and draws nothing) a little longer."""
        return self._last_death if self.capacity else -math.inf

    def reset_last_death(self) -> None:
        """Recompute :meth:`last_death` from the slots (after times were shifted)."""
        self._last_death = float(self.death.max()) if self.capacity else -math.inf


def parcel_state(records: np.ndarray, clock_s: float, shift_periods: float = 0.0):
    """Centres (n, 3) m (world z, or wrapped when ``shift_periods`` is the renderer's shift_z/PERIOD_M),
    horizontal and vertical Gaussian sizes σ_h, σ_v (n,) m and an alive mask of ring records at the effect
    clock ``clock_s`` (s), computed as shaders/spray/spray.vert does (float64)."""
    rec = records
    age = clock_s - rec["birth"].astype(np.float64)
    alive = (age >= 0.0) & (age < rec["life"])
    age = np.where(alive, age, 0.0)
    tau = np.where(alive, rec["tau"], 1.0).astype(np.float64)  # slots never written hold τ = 0
    pos = flight_position(rec["p0"], rec["v0"], rec["u"], tau, age)
    pos[:, 2] += (rec["period"] - shift_periods) * layout.PERIOD_M
    mist = (np.mod(rec["kind"], 2.0) > 0.5)
    sigma = np.where(mist, rec["sigma0"] + np.sqrt(rec["growth"] * age),
                     rec["sigma0"] + rec["growth"] * relax(age, tau) + 0.02 * age)
    sigma_v = np.where(mist, np.minimum(sigma, rec["glint"]), sigma)
    return pos, sigma, sigma_v, alive
