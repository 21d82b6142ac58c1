"""The spray emitter: turns the wheels' water into parcels in two rings (droplets, mist) — the CPU side of the
effect, no GL."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rain_core import checks, jit, layout, physics
from rain_core.effects.spray import kernels
from rain_core.effects.spray.body import body_hit_time, body_hit_time_fast
from rain_core.effects.spray.flight import (
    flight_position,
    flight_velocity,
    ground_time,
)
from rain_core.effects.spray.launch import (
    MIST_LIFE_S,
    MIST_SIGMA_MAX,
    WheelGeometry,
    carrier_air_and_tau,
    launch_droplets,
    launch_droplets_reference,
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
    ParcelRing,
    parcel_state,
)
from rain_core.effects.spray.spawn import SpawnBuffers, quantile_90, spawn_parcels_fast
from rain_core.effects.spray.water import BUCKETS, MIST_D_MM, SPLASH_MIN_MM, STANDING_WATER_MM
from rain_core.effects.spray.wheels import (
    MAX_FILM_DEPTH_MM,
    MAX_VEHICLE_SPEED_M_S,
    WheelWater,
    check_vehicles,
    gather_wheels,
    road_film_depth_fn,
    wheel_list,
    wheel_water,
)
from rain_core.water_film import WET_FILM_MM

MAX_INTERVAL_S = 0.25  # s; a longer gap between frames emits only this much (no backlog bursts)
MIST_BUDGET_SHARE = 32  # mist ring = budget // this (at least MIN_MIST_CAPACITY): puffs are big and overlap
MIN_MIST_CAPACITY = 64
MAX_BUDGET = 200_000  # droplet parcels (settings.spray.budget's range): the rings' size, so the work per step
MAX_STRENGTH = 100.0  # × the physical flux (settings allow 4)
_MIST_VT_M_S = physics.terminal_velocity(MIST_D_MM)  # m/s, every mist puff's drops are MIST_D_MM
_NO_DRAWS = np.zeros((0, 4, 1))  # a ring that spawns nothing this step: no draws (kernels.tally)
REBASE_S = 1000.0  # s of effect clock: then the clock restarts at 0 so float32 births keep 0.1 ms resolution


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
    # Per vehicle (id(vehicle) → (4,) kg, wheels FL, FR, RL, RR): ∫ thrown dt and Σ parcel masses spawned.
    wheel_thrown_kg: dict = field(default_factory=dict)
    wheel_emitted_kg: dict = field(default_factory=dict)


def _frame_wind(frame) -> np.ndarray:
    """The frame's wind (m/s, (3,)), checked: ValueError naming it if not finite or beyond
    ±MAX_VEHICLE_SPEED_M_S per component."""
    wind = getattr(getattr(getattr(frame, "weather", None), "wind", None), "velocity_m_s", None)
    if wind is None:
        return np.zeros(3)
    if type(wind) is tuple and len(wind) == 3 and all(type(c) is float for c in wind):
        # WindState's own form, checked in Python scalars (the NumPy checks below cost ~10 µs a frame).
        if all(abs(c) <= MAX_VEHICLE_SPEED_M_S for c in wind):  # NaN compares False
            return np.array(wind)
    w = np.asarray(wind, dtype=np.float64).reshape(-1)
    if w.shape != (3,) or not (np.isfinite(w).all() and np.abs(w).max() <= MAX_VEHICLE_SPEED_M_S):
        raise ValueError(f"spray: frame.weather.wind.velocity_m_s must be 3 finite components within "
                         f"±{MAX_VEHICLE_SPEED_M_S:g} m/s, got {checks.quote(wind)}")
    return w


class SprayEmitter:
    """Turns the wheels' water into parcels in two rings (droplets, mist) — all the CPU side of the effect.

    seed: the generator for every random choice (same seed + same frames → the same parcels). budget: droplet
    parcels alive at most (the mist ring gets budget // MIST_BUDGET_SHARE, at least
    MIN_MIST_CAPACITY). film_depth_fn(x, z) → mm overrides the road's film
    (tests use analytic fields); then the weather's wetness film is still added on the asphalt.
    """

    def __init__(self, seed: int = 0, budget: int = 12_000, film_depth_fn=None, reference: bool = False):
        self.rng = np.random.default_rng(seed)
        self.film_depth_fn = film_depth_fn
        self.reference = bool(reference)  # the float64 reference path (per vehicle, bisection, per box)
        self.strength = 1.0
        self.epoch: float | None = None
        self._last_time: float | None = None
        self._acc: dict[int, np.ndarray] = {}  # id(vehicle) → (4, 6) kg not yet emitted
        self._life_q90 = [1.0, MIST_LIFE_S[1]]  # s, running 90th percentile of parcel lives per ring
        self._pending = np.zeros((0, 4))  # landings in standing water still in flight: (time, x, z, momentum)
        # Fast path: the last frame's road landings (same columns) whose water depth the next frame's one film
        # lookup (with the wheels', in observe) decides.
        self._candidates = np.zeros((0, 4))
        self._landed = np.zeros((0, 3))
        self._wheels: list[WheelWater] | None = []  # None: made from the geometry when asked (wheels)
        self._vehicles: list = []  # the last observed frame's
        self.geometry: WheelGeometry | None = None
        self._wheels_time: float | None = None
        self.stats = SpawnStats()
        self._depth_key: tuple | None = None
        self._depth_fn = None
        self._book_key: tuple | None = None  # see _book
        self._book_arrays: tuple = ()
        self._spawn_buffers = SpawnBuffers()
        self.set_budget(budget)

    @property
    def strength(self) -> float:
        """Thrown water relative to the physical flux (×, in [0, MAX_STRENGTH])."""
        return self._strength

    @strength.setter
    def strength(self, value) -> None:
        self._strength = checks.number("spray strength", value, 0.0, MAX_STRENGTH, "×")

    # --- configuration ------------------------------------------------------------------------------------
    def set_budget(self, budget: int) -> None:
        """Resize the rings (clears them) when the budget (droplet parcels, 0…MAX_BUDGET) changes."""
        if getattr(self, "budget", None) == budget:
            return
        budget = int(checks.number("spray budget", budget, 0, MAX_BUDGET, "parcels"))
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
        self._candidates = np.zeros((0, 4))
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
            # A user's override may return anything: NaN counts as dry, depths are capped.
            own = np.nan_to_num(np.asarray(fn(x, z), dtype=np.float64), nan=0.0, posinf=MAX_FILM_DEPTH_MM)
            return np.clip(np.maximum(own, film), 0.0, MAX_FILM_DEPTH_MM)

        return depth

    @property
    def wheels(self) -> list[WheelWater]:
        """The last observed frame's WheelWater per vehicle (the fast path makes them on first use: the emitter
        itself reads the geometry's arrays)."""
        if self._wheels is None:
            self._wheels = wheel_list(self.geometry)
        return self._wheels

    def observe(self, frame) -> list[WheelWater]:
        """Evaluate the water model at every vehicle's wheels (cached per frame time). The vehicles' state is
        checked here, the frame's boundary: ValueError naming the vehicle and field if it is not finite."""
        self.observe_only(frame)
        return self.wheels

    def observe_only(self, frame) -> None:
        """:meth:`observe` without making the per-vehicle list (the effect's per-frame call)."""
        if self._wheels_time != frame.time_s or len(self._vehicles) != len(frame.vehicles):
            fn = self.depth_function(frame)
            vehicles = list(frame.vehicles)
            state = check_vehicles(vehicles)
            if self.reference:
                self._wheels = [wheel_water(v, fn) for v in vehicles]
                self.geometry = WheelGeometry(self._wheels) if vehicles else None
            else:
                # One film lookup for the wheels and the last frame's road landings (see _spawn_parcels).
                cand, self._candidates = self._candidates, np.zeros((0, 4))
                self._wheels, self.geometry = gather_wheels(vehicles, fn, state, extra_xz=cand[:, 1:3],
                                                            build_wheels=False)
                if jit.active():
                    if len(cand):
                        depth = np.ascontiguousarray(self.geometry.extra_depth_mm, dtype=np.float64)
                        self._pending = kernels.add_wet_landings(self._pending, cand, depth, STANDING_WATER_MM)
                else:
                    wet = self.geometry.extra_depth_mm >= STANDING_WATER_MM
                    if wet.any():
                        self._pending = np.concatenate([self._pending, cand[wet]])
            self._vehicles = vehicles
            self._wheels_time = frame.time_s

    def throwing(self) -> bool:
        """Whether any wheel of the last observed frame throws water."""
        flag = getattr(self.geometry, "throwing", None) if self._vehicles else False  # gather_wheels' answer
        if flag is not None:
            return flag
        return any(float(w.budget.thrown.sum()) > 0.0 for w in self.wheels)

    def alive_until(self) -> float:
        """Effect-clock time (s since epoch) when the last parcel in flight dies."""
        drops, mist = self.rings  # (always two; no generator for the per-frame asks)
        return max(drops.last_death(), mist.last_death())

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
        """Spawn the parcels thrown since the last call (at most MAX_INTERVAL_S of them) into the rings.

        The frame is checked here (ValueError naming the field): its time and wind must be finite (|wind| ≤
        MAX_VEHICLE_SPEED_M_S per component), its vehicles' state too (:meth:`observe`)."""
        t = checks.number("frame.time_s", frame.time_s, unit="s")
        wind = _frame_wind(frame)
        if self.epoch is None:
            self.epoch = t
        if self._last_time is None or t < self._last_time:
            self._last_time = t
        elapsed = min(t - self._last_time, MAX_INTERVAL_S)
        self._last_time = t
        if self.clock(t) > REBASE_S:
            self._rebase(t)
        now = self.clock(t)
        self._landed = np.zeros((0, 3))
        self.observe_only(frame)
        vehicles = self._vehicles
        live_ids = {id(v) for v in vehicles}
        if len(self._acc) != len(live_ids) or not live_ids.issuperset(self._acc):
            self._acc = {k: a for k, a in self._acc.items() if k in live_ids}
            st = self.stats  # vehicles gone: their wheels' totals go too (ids are reused)
            st.wheel_thrown_kg = {k: a for k, a in st.wheel_thrown_kg.items() if k in live_ids}
            st.wheel_emitted_kg = {k: a for k, a in st.wheel_emitted_kg.items() if k in live_ids}
        self.stats.last_parcels = self.stats.last_mist = 0
        if elapsed > 0.0 and self.budget > 0 and vehicles:
            self._spawn(frame, vehicles, elapsed, now, wind)
        self._pop_landings(now)

    def _rebase(self, t: float) -> None:
        """Restart the effect clock at 0 (shift every birth and death back by the clock's value), so the float32
        births stay precise however long the app runs or however far time jumps. Parcels already dead are
        emptied; the rings are uploaded whole once."""
        shift = self.clock(t)
        self.epoch = t
        for ring in self.rings:
            if ring.capacity == 0:
                continue
            dead = ring.death <= shift
            ring.birth -= shift
            ring.death -= shift
            ring.birth[dead], ring.death[dead] = np.inf, -np.inf
            ring.data["birth"] = np.where(dead, 0.0, ring.birth)
            ring.data["life"][dead] = -1.0  # never drawn
            ring.reset_last_death()
        self._pending[:, 0] -= shift
        self._candidates[:, 0] -= shift
        self.dirty = [[(0, r.capacity)] if r.capacity else [] for r in self.rings]

    def _pop_landings(self, now: float) -> None:
        if len(self._pending) and jit.active():
            self._landed, self._pending = kernels.due_landings(self._pending, now)
        elif len(self._pending):
            done = self._pending[:, 0] <= now
            self._landed = self._pending[done, 1:]  # (emit emptied _landed; this is the frame's only source)
            self._pending = self._pending[~done]

    # --- spawning -----------------------------------------------------------------------------------------
    def _spawn(self, frame, vehicles: list, elapsed: float, now: float, wind: np.ndarray) -> None:
        rng = self.rng
        geo = self.geometry
        st = self.stats
        rates = geo.buckets.reshape(len(vehicles), 4, len(BUCKETS)) * self.strength  # (V, 4, 6) kg/s
        st.available_kg += float(geo.available.sum()) * elapsed
        st.thrown_kg += float(rates.sum()) * elapsed
        acc, wheel_thrown_kg, wheel_emitted_kg = self._book(vehicles)
        acc += rates * elapsed
        if jit.active() and not self.reference:
            self._spawn_compiled(frame, geo, acc, rates, wheel_thrown_kg, wheel_emitted_kg, elapsed, now, wind)
            return
        counts = np.zeros(acc.shape, dtype=np.int64)
        for ring, buckets in ((0, slice(0, 5)), (1, slice(5, 6))):
            mass = acc[..., buckets]
            total = float(mass.sum())
            capacity = self.rings[ring].capacity
            if total <= 0.0 or capacity == 0:
                continue
            rate = capacity / max(self._life_q90[ring], 0.05)  # parcels per second
            # At most one ring's worth per step, whatever the interval (bounds the work; never hit at 30 Hz).
            expected = min(rate * elapsed, float(capacity)) * (mass / total)
            whole = np.floor(expected)
            counts[..., buckets] = whole + (rng.random(expected.shape) < expected - whole)
        emitted = counts > 0
        parcel_mass = np.where(emitted, acc / np.maximum(counts, 1), 0.0)
        wheel_emitted_kg += np.where(emitted, acc, 0.0).sum(axis=-1)  # (V, 4) kg
        wheel_thrown_kg += rates.sum(axis=-1) * elapsed
        acc[emitted] = 0.0
        if not emitted.any():
            return
        # One row per parcel: which vehicle, wheel and bucket, and its mass (repeat over the counts: no loop).
        # Bucket-major order: the droplets (buckets 0–4) first, the mist puffs (bucket 5) after them.
        bi, vi, wi = counts.transpose(2, 0, 1).nonzero()
        reps = counts[vi, wi, bi]
        mass_per = parcel_mass[vi, wi, bi]
        st.emitted_kg += float(mass_per @ reps)
        mass = mass_per.repeat(reps)
        age_now = elapsed * rng.random(len(mass))  # how long before now each parcel left the tyre
        if self.reference:
            n_drop = int(reps[bi < 5].sum())
            vi, wi, bi = np.repeat(vi, reps), np.repeat(wi, reps), np.repeat(bi, reps)
            self._spawn_parcels(frame, geo, n_drop, vi, wi, bi, mass, now - age_now, age_now, now, wind)
        else:
            bounds = np.zeros(7, dtype=np.int64)
            counts.sum(axis=(0, 1)).cumsum(out=bounds[1:])  # bucket k is rows bounds[k]:bounds[k + 1]
            spawn_parcels_fast(self, frame, geo, int(bounds[5]), (vi * 4 + wi).repeat(reps), bounds, mass,
                               now - age_now, age_now, now, wind, body_hit_time_fast)

    def _spawn_compiled(self, frame, geo, acc, rates, wheel_thrown_kg, wheel_emitted_kg, elapsed: float, now: float,
                        wind: np.ndarray) -> None:
        """:meth:`_spawn`'s counts, accounts and rows by ``kernels.tally`` (the twin's sums of each ring's mass,
        draws and emitted mass stay NumPy's calls, in its order), then the fast path's spawn."""
        rng = self.rng
        ring_args = []
        for ring, buckets in ((0, slice(0, 5)), (1, slice(5, 6))):
            mass = acc[..., buckets]
            total = float(mass.sum())
            capacity = self.rings[ring].capacity
            if total <= 0.0 or capacity == 0:
                ring_args += [False, 0.0, 1.0, _NO_DRAWS]
                continue
            rate = capacity / max(self._life_q90[ring], 0.05)  # parcels per second
            ring_args += [True, min(rate * elapsed, float(capacity)), total, rng.random(mass.shape)]
        cell_mass, cell_reps, w, mass, bounds = kernels.tally(acc, rates, elapsed, *ring_args, wheel_thrown_kg,
                                                              wheel_emitted_kg)
        if not len(mass):
            return
        self.stats.emitted_kg += float(cell_mass @ cell_reps)
        age_now = elapsed * rng.random(len(mass))  # how long before now each parcel left the tyre
        spawn_parcels_fast(self, frame, geo, int(bounds[5]), w, bounds, mass, now - age_now, age_now, now, wind,
                           body_hit_time_fast)

    def _book(self, vehicles: list):
        """The per-wheel accounts of this frame's vehicles, (V, 4, 6) kg not yet emitted and (V, 4) kg thrown and
        emitted in total, as arrays updated in place: ``_acc`` and the stats' per-vehicle dicts hold views of
        their rows. Rebuilt from those dicts only when the vehicles (or the stats object) change."""
        keys = tuple(id(v) for v in vehicles)
        st = self.stats
        if (self._book_key is None or self._book_key[0] != keys or self._book_key[1] is not st
                or self._book_key[2] is not st.wheel_thrown_kg or self._book_key[3] is not st.wheel_emitted_kg
                or self._book_key[4] is not self._acc):
            zero = np.zeros((4, len(BUCKETS)))
            acc = np.array([self._acc.get(k, zero) for k in keys], dtype=np.float64).reshape(-1, 4, len(BUCKETS))
            thrown = np.zeros((len(keys), 4))
            emitted = np.zeros((len(keys), 4))
            for i, k in enumerate(keys):
                thrown[i] += st.wheel_thrown_kg.get(k, 0.0)
                emitted[i] += st.wheel_emitted_kg.get(k, 0.0)
            for i, k in enumerate(keys):
                self._acc[k], st.wheel_thrown_kg[k], st.wheel_emitted_kg[k] = acc[i], thrown[i], emitted[i]
            self._book_arrays = (acc, thrown, emitted)
            self._book_key = (keys, st, st.wheel_thrown_kg, st.wheel_emitted_kg, self._acc)
        return self._book_arrays

    def _spawn_parcels(self, frame, geo, nd: int, vi, wi, bi, mass, birth, age_now, now, wind) -> None:
        """Launch, fly and file the frame's parcels: rows [:nd] droplets (ring 0), [nd:] mist puffs (ring 1),
        in one pass (each parcel's fate — road, kerb, body or the air — and so its lifetime, decided here)."""
        rng = self.rng
        ref = self.reference
        n = len(vi)
        nm = n - nd
        w = vi * 4 + wi  # flat wheel index
        launch = launch_droplets_reference if ref else launch_droplets
        out = launch(rng, geo, w[:nd], bi[:nd], age_now[:nd]) if nd else None
        if nm:
            mist_out = launch_mist(rng, geo, w[nd:], bi[nd:], age_now[nd:])
            out = mist_out if out is None else [np.concatenate(pair) for pair in zip(out, mist_out, strict=True)]
        p0, v0, d_mm, sigma0, growth_k, air, updraught = out
        vt = np.empty(n)
        vt[:nd] = physics.terminal_velocity(d_mm[:nd]) if nd else 0.0
        vt[nd:] = _MIST_VT_M_S
        u, speed, tau = carrier_air_and_tau(wind, air, updraught, v0, d_mm, vt, nd)
        t_ground = ground_time(p0, v0, u, tau, reference=ref)
        fate = np.full(n, FATE_ROAD)
        life = np.empty(n)
        growth = growth_k.copy()
        if nd:
            d = slice(0, nd)
            veh_origin = geo.position[vi[d]] - geo.velocity[vi[d]] * age_now[d, None]
            args = (p0[d], v0[d], u[d], tau[d], t_ground[d], veh_origin, geo.velocity[vi[d]], geo.right[vi[d]],
                    geo.forward[vi[d]])
            if ref:
                t_body = body_hit_time(*args, geo.boxes, geo.box_index[vi[d]])
            else:
                t_body = body_hit_time_fast(*args, geo.box_params[vi[d]])
            fate[d] = np.where(t_body < t_ground[d], FATE_BODY, FATE_ROAD)
            life[d] = np.minimum(t_body, t_ground[d])
            growth[d] *= speed[d]
        if nm:
            cap = rng.uniform(*MIST_LIFE_S, nm)
            fate[nd:] = np.where(cap < t_ground[nd:], FATE_AIR, FATE_ROAD)
            life[nd:] = np.minimum(cap, t_ground[nd:])
        # Drawn up to 1 ms before the surface so float32 never shows it past the road or the body.
        life = np.maximum(life - 1e-3, 0.0)
        horizon = np.empty(n)
        for ring, sl in ((0, slice(0, nd)), (1, slice(nd, n))):
            if sl.stop > sl.start:
                part = life[sl]
                q90 = float(np.quantile(part, 0.9)) if ref else quantile_90(part)
                self._life_q90[ring] = 0.9 * self._life_q90[ring] + 0.1 * max(q90, 0.05)
                horizon[sl] = max(self._life_q90[ring], 0.05)
        # The ring is refilled every q90 seconds (that is how the emission rate was set): a parcel living longer
        # would be overwritten in flight, so it fades out at that age instead.
        fate = np.where(life > horizon, FATE_AIR, fate)
        life = np.minimum(life, horizon)
        self.stats.fates += np.bincount(fate, weights=mass, minlength=3)
        # Landings in standing water, for the ripples.
        road = fate[:nd] == FATE_ROAD
        if nd and road.any() and self._standing_water_possible(frame):
            p0r, v0r, ur, taur, lifer = p0[:nd][road], v0[:nd][road], u[:nd][road], tau[:nd][road], life[:nd][road]
            land_p = flight_position(p0r, v0r, ur, taur, lifer)
            vel_y = flight_velocity(v0r, ur, taur, lifer)[:, 1]
            rows = np.column_stack([birth[:nd][road] + lifer, land_p[:, 0], land_p[:, 2],
                                    mass[:nd][road] * np.maximum(-vel_y, 0.0)])
            if ref:
                depth = np.asarray(self._depth_fn_cache(frame)(land_p[:, 0], land_p[:, 2]), dtype=np.float64)
                self._pending = np.concatenate([self._pending, rows[depth >= STANDING_WATER_MM]])
            else:
                # The depth under them is looked up with the next frame's wheels (one film lookup per frame);
                # a parcel that lands within this frame reaches the ripples one frame later.
                self._candidates = np.concatenate([self._candidates, rows])
        area = extinction_area_m2(mass, d_mm)
        death = birth + life
        period = np.floor(p0[:, 2] / layout.PERIOD_M)
        p0[:, 2] -= period * layout.PERIOD_M  # z within its period, so float32 keeps mm
        kind = np.where(fate == FATE_AIR, KIND_DROPLET + KIND_FADE, KIND_DROPLET)
        kind[nd:] += KIND_MIST - KIND_DROPLET
        glint = np.where(d_mm >= SPLASH_MIN_MM, 1.0, 0.5)
        glint[nd:] = MIST_SIGMA_MAX * geo.height[vi[nd:]]  # mist puffs hold σ_max (m)
        for ring, sl in ((0, slice(0, nd)), (1, slice(nd, n))):
            if sl.stop > sl.start:
                self._file(ring, sl, now, p0, period, v0, tau, u, birth, life, death, sigma0, growth, area, kind,
                           d_mm, glint)
        self.stats.parcels += nd
        self.stats.last_parcels += nd
        self.stats.mist_puffs += nm
        self.stats.last_mist += nm

    def _file(self, ring, sl, now, p0, period, v0, tau, u, birth, life, death, sigma0, growth, area, kind, d_mm,
              glint) -> None:
        """Write ring ``ring``'s new records (rows ``sl``) into it: only those still alive at ``now`` (parcels
        that already died within this frame are not drawn), through the ring's reusable scratch records."""
        keep = death[sl] > now
        k = int(np.count_nonzero(keep))
        if k == 0:
            return
        if k == sl.stop - sl.start:
            def pick(a):
                return a[sl]
        else:
            idx = np.nonzero(keep)[0] + sl.start

            def pick(a):
                return a[idx]
        rec = self.rings[ring].scratch(k)
        rec["p0"], rec["period"] = pick(p0), pick(period)
        rec["v0"], rec["tau"] = pick(v0), pick(tau)
        rec["u"], rec["birth"] = pick(u), pick(birth)
        rec["life"], rec["sigma0"], rec["growth"], rec["area"] = pick(life), pick(sigma0), pick(growth), pick(area)
        rec["kind"], rec["d_mm"], rec["glint"] = pick(kind), pick(d_mm), pick(glint)
        rec["rand"] = self.rng.random(k)
        ranges = self.rings[ring].push(rec, pick(birth), pick(death))
        self.dirty[ring].extend(ranges)

    def _standing_water_possible(self, frame) -> bool:
        """Whether any road point can hold STANDING_WATER_MM: with the road's own film only when the weather's
        cracks or puddles hold water (the wet film alone is WET_FILM_MM deep); an override may hold any."""
        if self.film_depth_fn is not None or self.reference:
            return True
        weather = getattr(frame, "weather", None)
        if WET_FILM_MM >= STANDING_WATER_MM:
            return True
        return bool(getattr(weather, "cracks", 0.0) or getattr(weather, "puddles", 0.0))

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

