"""The spray emitter: turns the wheels' water into parcels in two rings (droplets, mist) — the CPU side of the
effect, no GL."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rain_core import layout, physics
from rain_core.effects.spray.body import body_hit_time
from rain_core.effects.spray.flight import drag_time_constant, flight_position, flight_velocity, ground_time
from rain_core.effects.spray.launch import (
    MIST_LIFE_S,
    MIST_SIGMA_MAX,
    WAKE_TAU_S,
    WheelGeometry,
    launch_droplets,
    launch_mist,
)
from rain_core.effects.spray.optics import extinction_area_m2
from rain_core.effects.spray.parcels import (
    FATE_AIR,
    FATE_BODY,
    FATE_ROAD,
    KIND_DROPLET,
    KIND_FADE,
    KIND_MIST,
    PARTICLE_DTYPE,
    ParcelRing,
    parcel_state,
)
from rain_core.effects.spray.water import BUCKETS, SPLASH_MIN_MM, STANDING_WATER_MM
from rain_core.effects.spray.wheels import WheelWater, road_film_depth_fn, wheel_water
from rain_core.water_film import WET_FILM_MM

MAX_INTERVAL_S = 0.25  # s; a longer gap between frames emits only this much (no backlog bursts)
MIST_BUDGET_SHARE = 32  # mist ring = budget // this (at least MIN_MIST_CAPACITY): puffs are big and overlap
MIN_MIST_CAPACITY = 64


@dataclass
class SpawnStats:
    """Totals since the emitter started (kg, counts) and of the last frame."""

    thrown_kg: float = 0.0  # ∫ thrown mass dt (after strength), what the parcels must carry
    emitted_kg: float = 0.0  # Σ parcel masses spawned
    available_kg: float = 0.0  # ∫ M_w dt
    parcels: int = 0
    mist_puffs: int = 0
    fates: np.ndarray = field(default_factory=lambda: np.zeros(3))  # kg by fate: road, body, air
    last_parcels: int = 0
    last_mist: int = 0


class SprayEmitter:
    """Turns the wheels' water into parcels in two rings (droplets, mist) — all the CPU side of the effect.

    seed: the generator for every random choice (same seed + same frames → the same parcels). budget: droplet
    parcels alive at most (the mist ring gets budget // MIST_BUDGET_SHARE, at least
    MIN_MIST_CAPACITY). film_depth_fn(x, z) → mm overrides the road's film
    (tests use analytic fields); then the weather's wetness film is still added on the asphalt.
    """

    def __init__(self, seed: int = 0, budget: int = 12_000, film_depth_fn=None):
        self.rng = np.random.default_rng(seed)
        self.film_depth_fn = film_depth_fn
        self.strength = 1.0
        self.epoch: float | None = None
        self._last_time: float | None = None
        self._acc: dict[int, np.ndarray] = {}  # id(vehicle) → (4, 6) kg not yet emitted
        self._life_q90 = [1.0, MIST_LIFE_S[1]]  # s, running 90th percentile of parcel lives per ring
        self._pending = np.zeros((0, 4))  # landings still in flight: (time, x, z, momentum)
        self._landed = np.zeros((0, 3))
        self.wheels: list[WheelWater] = []
        self._wheels_time: float | None = None
        self.stats = SpawnStats()
        self._depth_key: tuple | None = None
        self._depth_fn = None
        self.set_budget(budget)

    # --- configuration ------------------------------------------------------------------------------------
    def set_budget(self, budget: int) -> None:
        """Resize the rings (clears them) when the budget (droplet parcels) changes."""
        budget = int(budget)
        if getattr(self, "budget", None) == budget:
            return
        self.budget = budget
        mist = max(MIN_MIST_CAPACITY, budget // MIST_BUDGET_SHARE) if budget > 0 else 0
        self.rings = [ParcelRing(budget), ParcelRing(mist)]
        self.dirty: list[list[tuple[int, int]]] = [[(0, budget)] if budget else [], [(0, mist)] if mist else []]

    def clear(self) -> None:
        """Forget every parcel in flight (the effect was switched off)."""
        budget, self.budget = self.budget, -1
        self.set_budget(budget)
        self._pending = np.zeros((0, 4))
        self._last_time = None

    def pause(self) -> None:
        """The effect is off this frame: drop the parcels in flight (if any) and the last time seen, so switching
        it on again does not replay the gap."""
        if self.alive_until() > -math.inf:
            self.clear()
        self._last_time = None

    # --- per frame ----------------------------------------------------------------------------------------
    def depth_function(self, frame):
        """(x, z) → film depth in mm for this frame (the override, plus the wet film, or the road's)."""
        if self.film_depth_fn is None:
            return road_film_depth_fn(frame)
        wetness = float(getattr(getattr(frame, "weather", None), "wetness", 0.0) or 0.0)
        fn = self.film_depth_fn

        def depth(x, z):
            x, z = np.broadcast_arrays(np.asarray(x, np.float64), np.asarray(z, np.float64))
            film = np.where(np.abs(x) <= layout.ROAD_HALF_WIDTH_M, WET_FILM_MM * wetness, 0.0)
            return np.maximum(np.asarray(fn(x, z), dtype=np.float64), film)

        return depth

    def observe(self, frame) -> list[WheelWater]:
        """Evaluate the water model at every vehicle's wheels (cached per frame time)."""
        if self._wheels_time != frame.time_s or len(self.wheels) != len(frame.vehicles):
            fn = self.depth_function(frame)
            self.wheels = [wheel_water(v, fn) for v in frame.vehicles]
            self._wheels_time = frame.time_s
        return self.wheels

    def throwing(self) -> bool:
        """Whether any wheel of the last observed frame throws water."""
        return any(float(w.budget.thrown.sum()) > 0.0 for w in self.wheels)

    def alive_until(self) -> float:
        """Effect-clock time (s since epoch) when the last parcel in flight dies."""
        return max((r.last_death() for r in self.rings), default=-math.inf)

    def clock(self, time_s: float) -> float:
        """Frame time (s) → the effect clock (s since the first frame), what the shader's u_clock holds."""
        return time_s - (self.epoch if self.epoch is not None else time_s)

    def alive_counts(self, time_s: float) -> tuple[int, int]:
        now = self.clock(time_s)
        return self.rings[0].alive(now), self.rings[1].alive(now)

    def landed_in_water(self) -> list[tuple[float, float, float]]:
        """Parcels that landed in standing water (film ≥ STANDING_WATER_MM) during the last emitted frame:
        (x m, z m world, downward momentum kg·m/s), for the ripple solver's impulses."""
        return [(float(x), float(z), float(p)) for x, z, p in self._landed]

    def landed_impacts(self) -> np.ndarray:
        """The same landings as an (N, 3) float64 array (x m, z m world, downward momentum kg·m/s): what the
        effect publishes as ``rc.shared.droplet_impacts``."""
        return np.array(self._landed, dtype=np.float64).reshape(-1, 3)

    def emit(self, frame) -> None:
        """Spawn the parcels thrown since the last call (at most MAX_INTERVAL_S of them) into the rings."""
        t = float(frame.time_s)
        if self.epoch is None:
            self.epoch = t
        if self._last_time is None or t < self._last_time:
            self._last_time = t
        elapsed = min(t - self._last_time, MAX_INTERVAL_S)
        self._last_time = t
        now = self.clock(t)
        self._landed = np.zeros((0, 3))
        wheels = self.observe(frame)
        live_ids = {id(w.vehicle) for w in wheels}
        self._acc = {k: a for k, a in self._acc.items() if k in live_ids}
        self.stats.last_parcels = self.stats.last_mist = 0
        if elapsed > 0.0 and self.budget > 0 and wheels:
            self._spawn(frame, wheels, elapsed, now)
        self._pop_landings(now)

    def _pop_landings(self, now: float) -> None:
        if len(self._pending):
            done = self._pending[:, 0] <= now
            self._landed = np.concatenate([self._landed, self._pending[done, 1:]])
            self._pending = self._pending[~done]

    # --- spawning -----------------------------------------------------------------------------------------
    def _spawn(self, frame, wheels: list[WheelWater], elapsed: float, now: float) -> None:
        rng = self.rng
        rates = np.stack([w.budget.buckets for w in wheels]) * self.strength  # (V, 4, 6) kg/s
        self.stats.available_kg += float(sum(w.budget.available.sum() for w in wheels)) * elapsed
        self.stats.thrown_kg += float(rates.sum()) * elapsed
        acc = np.stack([self._acc.get(id(w.vehicle), np.zeros((4, len(BUCKETS)))) for w in wheels])
        acc = acc + rates * elapsed
        counts = np.zeros(acc.shape, dtype=np.int64)
        for ring, buckets in ((0, slice(0, 5)), (1, slice(5, 6))):
            mass = acc[..., buckets]
            total = float(mass.sum())
            if total <= 0.0 or self.rings[ring].capacity == 0:
                continue
            rate = self.rings[ring].capacity / max(self._life_q90[ring], 0.05)  # parcels per second
            expected = rate * elapsed * mass / total
            whole = np.floor(expected)
            counts[..., buckets] = (whole + (rng.random(expected.shape) < expected - whole)).astype(np.int64)
        emitted = counts > 0
        parcel_mass = np.where(emitted, acc / np.maximum(counts, 1), 0.0)
        acc = np.where(emitted, 0.0, acc)
        for w, a in zip(wheels, acc, strict=True):
            self._acc[id(w.vehicle)] = a
        if not emitted.any():
            return
        # One row per parcel: which vehicle, wheel and bucket, and its mass.
        vi, wi, bi = np.nonzero(counts)
        reps = counts[vi, wi, bi]
        vi, wi, bi = np.repeat(vi, reps), np.repeat(wi, reps), np.repeat(bi, reps)
        mass = parcel_mass[vi, wi, bi]
        self.stats.emitted_kg += float(mass.sum())
        geo = WheelGeometry(wheels)
        age_now = elapsed * rng.random(len(vi))  # how long before now each parcel left the tyre
        birth = now - age_now
        mist = bi == 5
        for ring, sel in ((0, ~mist), (1, mist)):
            if sel.any():
                self._spawn_ring(frame, ring, geo, vi[sel], wi[sel], bi[sel], mass[sel], birth[sel],
                                 age_now[sel], now)

    def _spawn_ring(self, frame, ring: int, geo, vi, wi, bi, mass, birth, age_now, now) -> None:
        rng = self.rng
        n = len(vi)
        w = vi * 4 + wi  # flat wheel index
        wind = np.asarray(getattr(getattr(getattr(frame, "weather", None), "wind", None), "velocity_m_s",
                                  (0.0, 0.0, 0.0)), dtype=np.float64)
        launch = launch_mist if ring == 1 else launch_droplets
        p0, v0, d_mm, sigma0, growth_k, air, updraught = launch(rng, geo, w, bi, age_now)
        sigma_max = MIST_SIGMA_MAX * geo.height[vi]
        vt = np.asarray(physics.terminal_velocity(d_mm), dtype=np.float64)
        u = wind + air
        u[:, 1] -= vt * (1.0 - updraught)
        if ring == 1:
            tau = np.full(n, WAKE_TAU_S)
        else:
            tau = drag_time_constant(d_mm, np.linalg.norm(v0 - u, axis=1))
        t_ground = ground_time(p0, v0, u, tau)
        fate = np.full(n, FATE_ROAD)
        if ring == 0:
            veh_origin = geo.position[vi] - geo.velocity[vi] * age_now[:, None]
            t_body = body_hit_time(p0, v0, u, tau, t_ground, veh_origin, geo.velocity[vi], geo.right[vi],
                                   geo.forward[vi], geo.boxes, geo.box_index[vi])
            fate = np.where(t_body < t_ground, FATE_BODY, FATE_ROAD)
            life = np.minimum(t_body, t_ground)
            growth = growth_k * np.linalg.norm(v0 - u, axis=1)
        else:
            cap = rng.uniform(*MIST_LIFE_S, n)
            fate = np.where(cap < t_ground, FATE_AIR, FATE_ROAD)
            life = np.minimum(cap, t_ground)
            growth = growth_k
        # Drawn up to 1 ms before the surface so float32 never shows it past the road or the body.
        life = np.maximum(life - 1e-3, 0.0)
        q90 = float(np.quantile(life, 0.9))
        self._life_q90[ring] = 0.9 * self._life_q90[ring] + 0.1 * max(q90, 0.05)
        # The ring is refilled every q90 seconds (that is how the emission rate was set): a parcel living longer
        # would be overwritten in flight, so it fades out at that age instead.
        horizon = max(self._life_q90[ring], 0.05)
        cut = life > horizon
        fate = np.where(cut, FATE_AIR, fate)
        life = np.minimum(life, horizon)
        for f in range(3):
            self.stats.fates[f] += float(mass[fate == f].sum())
        # Landings in standing water, for the ripples.
        road = fate == FATE_ROAD
        if road.any() and ring == 0:
            land_p = flight_position(p0[road], v0[road], u[road], tau[road], life[road])
            depth = np.asarray(self._depth_fn_cache(frame)(land_p[:, 0], land_p[:, 2]), dtype=np.float64)
            wet = depth >= STANDING_WATER_MM
            if wet.any():
                vel = flight_velocity(v0[road][wet], u[road][wet], tau[road][wet], life[road][wet])
                momentum = mass[road][wet] * np.maximum(-vel[:, 1], 0.0)
                rows = np.column_stack([birth[road][wet] + life[road][wet], land_p[wet][:, 0], land_p[wet][:, 2],
                                        momentum])
                self._pending = np.concatenate([self._pending, rows])
        area = extinction_area_m2(mass, d_mm)
        keep = birth + life > now  # parcels that already died within this frame are not drawn
        rec = np.zeros(int(keep.sum()), PARTICLE_DTYPE)
        if len(rec):
            period = np.floor(p0[keep, 2] / layout.PERIOD_M)
            p = p0[keep].copy()
            p[:, 2] -= period * layout.PERIOD_M
            rec["p0"], rec["period"] = p, period
            rec["v0"], rec["tau"] = v0[keep], tau[keep]
            rec["u"], rec["birth"] = u[keep], birth[keep]
            rec["life"], rec["sigma0"], rec["growth"], rec["area"] = life[keep], sigma0[keep], growth[keep], \
                area[keep]
            kind = np.full(len(rec), KIND_MIST if ring == 1 else KIND_DROPLET, np.float32)
            kind += np.where(fate[keep] == FATE_AIR, KIND_FADE, 0)
            rec["kind"], rec["d_mm"] = kind, d_mm[keep]
            rec["rand"] = rng.random(len(rec))
            splash = d_mm[keep] >= SPLASH_MIN_MM
            rec["glint"] = sigma_max[keep] if ring == 1 else np.where(splash, 1.0, 0.5)
            ranges = self.rings[ring].push(rec, birth[keep], (birth + life)[keep])
            self.dirty[ring].extend(ranges)
        if ring == 0:
            self.stats.parcels += n
            self.stats.last_parcels += n
        else:
            self.stats.mist_puffs += n
            self.stats.last_mist += n

    def _depth_fn_cache(self, frame):
        key = (frame.time_s, id(frame))
        if self._depth_key != key:
            self._depth_key = key
            self._depth_fn = self.depth_function(frame)
        return self._depth_fn

    def take_dirty(self) -> list[list[tuple[int, int]]]:
        """The slot ranges written since the last call, per ring (the GPU upload list)."""
        dirty, self.dirty = self.dirty, [[], []]
        return dirty


def line_of_sight_optical_depth(emitter: SprayEmitter, time_s: float, eye, target) -> float:
    """Optical depth of the spray along the segment eye → target (world m) at frame time ``time_s``: the sum
    over parcels between the two points of A/(2π·σ_h·σ_v)·exp(−d_h²/(2σ_h²) − d_v²/(2σ_v²)), d_h and d_v the
    horizontal and vertical parts of the parcel's distance from the line: the line integral of a Gaussian puff
    along a near-horizontal ray. exp(−τ) is the share of the target's light that gets through — the
    visibility loss of whoever follows."""
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    axis = target - eye
    length = float(np.linalg.norm(axis))
    axis /= max(length, 1e-9)
    total = 0.0
    for ring in emitter.rings:
        if ring.capacity == 0:
            continue
        pos, sigma_h, sigma_v, alive = parcel_state(ring.data, emitter.clock(time_s))
        rel = pos - eye
        along = rel @ axis
        keep = alive & (along > 0.0) & (along < length)
        perp = rel[keep] - along[keep, None] * axis
        dv2 = perp[:, 1] ** 2
        dh2 = np.sum(perp**2, axis=1) - dv2
        sh, sv = sigma_h[keep], sigma_v[keep]
        total += float(np.sum(ring.data["area"][keep] / (2.0 * math.pi * sh * sv)
                              * np.exp(-0.5 * (dh2 / sh**2 + dv2 / sv**2))))
    return total

