"""The rainfall simulation (CPU, NumPy only): keeps the container filled with drops whose fate is settled when they
spawn, retires them when due, and spawns splashes. ``RainfallSim.advance(RainInput) -> RainUpdate``."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from rain_core import layout, physics
from rain_core.effects.rainfall.boxes import Boxes, layer_boxes, wrap_near
from rain_core.effects.rainfall.constants import (
    BUDGET_FULL_AT_MM_H,
    FATE_CHUNK,
    GROUND_Y_M,
    HEADROOM,
    MIN_RECHECK_S,
    OPEN_PROBE_BLEND,
    OPEN_PROBE_EVERY,
    OPEN_PROBES,
    OPEN_PROBES_FIRST,
    PERIOD_M,
    RATE_OFF_MM_H,
    RATE_RAMP_S,
    SPLASH_CAPACITY_MAX,
    SPLASH_CAPACITY_MIN,
    SPLASH_D_MIN_MM,
    SPLASH_LAYER,
    SPLASH_LIFE_S,
    TIME_PERIOD_S,
    TURBULENCE,
    TYPE_FILM_CROWN,
    TYPE_PROMPT,
    TYPE_PUDDLE_CROWN,
)
from rain_core.effects.rainfall.occluders import OccluderField
from rain_core.effects.rainfall.pool import DropPool
from rain_core.effects.rainfall.rates import drawn_share, sample_truncated_exp, splash_flux_per_m2_s, splash_life_s
from rain_core.effects.rainfall.vehicle_fate import near_boxes, vehicle_fate


@dataclass
class RainInput:
    """What the rain simulation needs from one frame. Positions and velocities in the world frame (m, m/s)."""

    time_s: float
    camera_position: np.ndarray
    camera_forward: np.ndarray
    camera_velocity: np.ndarray
    rate_mm_h: float
    wind_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    container_m: float = 40.0
    density_scale: float = 1.0
    splashes: bool = True
    wetness: float = 0.0
    puddles: float = 0.0
    vehicles: tuple = ()


@dataclass
class RainUpdate:
    """What changed in one ``advance``: GPU writes and statistics."""

    spawn_slots: np.ndarray
    spawn_texels: np.ndarray  # (n, 3, 4) float32, the GPU layout of the new drops
    kill_slots: np.ndarray  # slots freed this frame (cleared on the GPU)
    splash_slots: np.ndarray
    splash_data: np.ndarray  # (m, 8) float32
    candidates: int = 0  # drops sampled in the new region (before occlusion and the budget)
    rejected: int = 0  # of those, under a roof, in a rain shadow or inside a vehicle
    overflow: int = 0  # refused because the buffer was full
    cpu_ms: float = 0.0


def _empty_update() -> RainUpdate:
    return RainUpdate(np.zeros(0, np.int64), np.zeros((0, 3, 4), np.float32), np.zeros(0, np.int64),
                      np.zeros(0, np.int64), np.zeros((0, 8), np.float32))


class RainfallSim:
    """The CPU side of the rainfall: the drop pool, the container, spawning with settled fates, and splashes.

    capacity: the particle budget (drops); seed: seeds every random draw (same seed and inputs → same drops);
    world: a rain_core.world.World (its roof map) or None for open ground everywhere.
    ``advance(RainInput) -> RainUpdate``; the per-slot arrays (``pos0``, ``vel``, ``t0``, ``t_hit``,
    ``diameter``, ``weight``, ``layer``) describe the live drops (``pool.alive``)."""

    def __init__(self, capacity: int, seed: int = 0, world=None):
        self.capacity = int(capacity)
        self.seed = int(seed)
        self.world = world
        self.occluders = OccluderField(world) if world is not None and hasattr(world, "occluder_map") else None
        self.splash_capacity = int(np.clip(self.capacity // 16, SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX))
        self.reset()

    def reset(self) -> None:
        """Forget every drop and splash (the next ``advance`` fills the container at once)."""
        c = self.capacity
        self.rng = np.random.default_rng(self.seed)
        self.pool = DropPool(c)
        self.pos0 = np.zeros((c, 3))
        self.vel = np.zeros((c, 3))
        self.t0 = np.zeros(c)
        self.t_hit = np.zeros(c)
        self.diameter = np.zeros(c)
        self.weight = np.zeros(c)
        self.layer = np.zeros(c, dtype=np.int64)
        self.rate_eff = 0.0
        self.kappa = 0.0
        self.boxes: Boxes | None = None
        self.open_fraction: np.ndarray | None = None
        self._probe_frames = 0
        self.t_prev: float | None = None
        self.splash_head = 0
        self.splash_t0 = np.full(self.splash_capacity, -np.inf)
        self.splash_life = np.zeros(self.splash_capacity)
        self.splash_pos = np.zeros((self.splash_capacity, 3))
        self.splash_weight = np.zeros(self.splash_capacity)
        self.generation = getattr(self, "generation", -1) + 1  # tells the GPU side to clear its copy

    @property
    def live(self) -> int:
        return self.pool.live

    def splashes_live(self, time_s: float) -> int:
        return int(np.count_nonzero(self.splash_t0 + self.splash_life > time_s))

    def target_count(self, rate_mm_h: float, density_scale: float) -> float:
        """Expected live drops at rate R (mm/h): HEADROOM × budget × drawn_share(density_scale·…)."""
        return HEADROOM * self.capacity * min(1.0, density_scale * drawn_share(rate_mm_h))

    def positions(self, slots, time_s: float) -> np.ndarray:
        """World positions (m) of drops at time_s (no z wrap)."""
        slots = np.asarray(slots)
        return self.pos0[slots] + self.vel[slots] * (time_s - self.t0[slots])[:, None]

    # --- one frame ---

    def advance(self, inp: RainInput) -> RainUpdate:
        """Advance to inp.time_s: retire due drops, spawn into the new region, spawn splashes."""
        t_start = time.perf_counter()
        t = float(inp.time_s)
        if self.t_prev is not None and t < self.t_prev - 1e-9:
            self.reset()
        first = self.t_prev is None
        dt = 0.0 if first else t - self.t_prev
        target = max(float(inp.rate_mm_h), 0.0)
        if first:
            self.rate_eff = target
        else:
            self.rate_eff = target + (self.rate_eff - target) * math.exp(-dt / RATE_RAMP_S)
            if target == 0.0 and self.rate_eff < RATE_OFF_MM_H:
                self.rate_eff = 0.0
        boxes = layer_boxes(inp.camera_position, inp.camera_forward, inp.container_m)
        upd = _empty_update()
        v_cam = np.asarray(inp.camera_velocity, dtype=np.float64)
        kills = self._retire(t, boxes, v_cam)
        if self.capacity > 0 and self.rate_eff > 0.0:
            self._spawn(t, dt, boxes, None if first else self.boxes, inp, v_cam, upd)
        upd.kill_slots = kills
        if inp.splashes and (first or dt > 0):
            self._spawn_splashes(t, SPLASH_LIFE_S[1] if first else dt, boxes, inp, upd)
        self.boxes = boxes
        self.t_prev = t
        upd.cpu_ms = (time.perf_counter() - t_start) * 1e3
        return upd

    def _retire(self, t: float, boxes: Boxes, v_cam: np.ndarray) -> np.ndarray:
        due = self.pool.pop_due(t)
        if due.size == 0:
            return due
        p = self.positions(due, t)
        lay = self.layer[due]
        p[:, 2] = wrap_near(p[:, 2], 0.5 * (boxes.lo[lay, 2] + boxes.hi[lay, 2]))
        inside = np.all((p >= boxes.lo[lay]) & (p <= boxes.hi[lay]), axis=1)
        dead = (t >= self.t_hit[due] - 1e-9) | ~inside
        self.pool.release(due[dead])
        keep = due[~dead]
        self._schedule(keep, p[~dead], t, boxes, v_cam)
        return due[dead]

    def _schedule(self, slots, p, t, boxes: Boxes, v_cam) -> None:
        """File slots under min(hit time, when they would leave their box at the current relative velocity)."""
        if slots.size == 0:
            return
        lay = self.layer[slots]
        w = self.vel[slots] - v_cam
        lo, hi = boxes.lo[lay], boxes.hi[lay]
        with np.errstate(divide="ignore", invalid="ignore"):
            t_axis = np.where(w > 1e-6, (hi - p) / w, np.where(w < -1e-6, (lo - p) / w, np.inf))
        t_exit = np.min(t_axis, axis=1)
        due = np.minimum(self.t_hit[slots], t + np.maximum(t_exit, MIN_RECHECK_S))
        self.pool.schedule(slots, due, t)

    def fate(self, pos: np.ndarray, u: np.ndarray, boxes: Boxes, vehicles=()) -> tuple[np.ndarray, np.ndarray]:
        """(keep, lifetime s) of drops at pos (m) moving at u (m/s): the ground, the roofs, the nearby vehicles
        (those within FATE_CHUNK-sized batches, to bound memory)."""
        near = [v for v in vehicles if near_boxes(v, boxes)]
        keep = np.empty(len(pos), dtype=bool)
        life = np.empty(len(pos))
        for a in range(0, len(pos), FATE_CHUNK):
            p, w = pos[a: a + FATE_CHUNK], u[a: a + FATE_CHUNK]
            t = (p[:, 1] - GROUND_Y_M) / -w[:, 1]
            k = p[:, 1] > GROUND_Y_M
            if self.occluders is not None:
                k2, t = self.occluders.fate(p, w, t)
                k &= k2
            if near:
                k3, t = vehicle_fate(p, w, t, near)
                k &= k3
            keep[a: a + FATE_CHUNK] = k & (t > 0.0)
            life[a: a + FATE_CHUNK] = t
        return keep, life

    def _probe_open(self, boxes: Boxes, wind, rate: float, vehicles, first: bool) -> None:
        """Track the share of each box that rain can reach (not under roofs, not inside vehicles), so that the
        budget goes to the open air: an exponential average over random probe drops put through the same fate
        tests as the real ones."""
        n = OPEN_PROBES_FIRST if first else OPEN_PROBES
        if self.occluders is None and not vehicles:
            self.open_fraction = np.ones(len(boxes.nu))
            return
        if not first and self.open_fraction is not None and self._probe_frames > 0:
            self._probe_frames -= 1
            return
        self._probe_frames = OPEN_PROBE_EVERY - 1
        rng = np.random.default_rng(self.rng.integers(2**63))  # its own stream: probes never shift the drops
        frac = np.empty(len(boxes.nu))
        for k in range(len(boxes.nu)):
            p = boxes.lo[k] + rng.random((n, 3)) * (boxes.hi[k] - boxes.lo[k])
            u = np.zeros((n, 3))
            u[:, [0, 2]] = wind[[0, 2]]
            u[:, 1] = -physics.terminal_velocity(physics.sample_drop_diameters(rate, n, rng))
            frac[k] = max(self.fate(p, u, boxes, vehicles)[0].mean(), 0.05)
        if first or self.open_fraction is None:
            self.open_fraction = frac
        else:
            self.open_fraction += OPEN_PROBE_BLEND * (frac - self.open_fraction)

    def _new_region(self, k: int, boxes: Boxes, prev: Boxes | None, wind_xz, dt: float, density: float,
                    rate: float) -> tuple[np.ndarray, np.ndarray]:
        """Sample the drops (positions m, diameters mm) in layer k's box that were not in its previous box."""
        rng = self.rng
        lo, hi = boxes.lo[k], boxes.hi[k]
        ext = hi - lo
        if prev is None:
            n = int(rng.poisson(density * float(np.prod(ext))))
            pos = lo + rng.random((n, 3)) * ext
            return pos, physics.sample_drop_diameters(rate, n, rng)
        lo_p, hi_p = prev.lo[k], prev.hi[k]
        v_max = float(physics.terminal_velocity(physics.D_MAX_MM))
        shift_h = {0: wind_xz[0] * dt, 2: wind_xz[1] * dt}

        def prev_interval(axis, v):
            s = -v * dt if axis == 1 else shift_h[axis]
            return lo_p[axis] + s, hi_p[axis] + s

        def in_slab(axis, side, p_axis, v):
            a, b = prev_interval(axis, v)
            if side == 0:
                return p_axis < np.minimum(a, hi[axis])
            return p_axis > np.maximum(b, lo[axis])

        slabs = [(axis, side) for axis in (0, 2, 1) for side in (0, 1)]
        out_p, out_d = [], []
        for i, (axis, side) in enumerate(slabs):
            vs = (0.0, v_max) if axis == 1 else (0.0,)
            thick = 0.0
            for v in vs:
                a, b = prev_interval(axis, v)
                th = (min(a, hi[axis]) - lo[axis]) if side == 0 else (hi[axis] - max(b, lo[axis]))
                thick = max(thick, min(max(th, 0.0), ext[axis]))
            if thick <= 0.0:
                continue
            others = [j for j in range(3) if j != axis]
            n = int(rng.poisson(density * thick * ext[others[0]] * ext[others[1]]))
            if n == 0:
                continue
            pos = lo + rng.random((n, 3)) * ext
            r = rng.random(n) * thick
            pos[:, axis] = lo[axis] + r if side == 0 else hi[axis] - r
            d = physics.sample_drop_diameters(rate, n, rng)
            v = physics.terminal_velocity(d)
            ok = in_slab(axis, side, pos[:, axis], v)
            for axis_j, side_j in slabs[:i]:
                ok &= ~in_slab(axis_j, side_j, pos[:, axis_j], v)
            out_p.append(pos[ok])
            out_d.append(d[ok])
        if not out_p:
            return np.zeros((0, 3)), np.zeros(0)
        return np.concatenate(out_p), np.concatenate(out_d)

    def _spawn(self, t, dt, boxes: Boxes, prev: Boxes | None, inp: RainInput, v_cam, upd: RainUpdate) -> None:
        rate = self.rate_eff
        n_eff = inp.density_scale * physics.number_density_per_m3(rate)
        if n_eff <= 0.0:
            return
        target = self.target_count(rate, inp.density_scale)
        wind = np.asarray(inp.wind_m_s, dtype=np.float64)
        self._probe_open(boxes, wind, rate, inp.vehicles, first=prev is None)
        open_volume = float(np.sum(boxes.nu * boxes.volumes * self.open_fraction))
        kappa = min(target / max(open_volume, 1e-9), n_eff / float(np.sum(boxes.nu)))
        if kappa <= 0.0:
            return
        self.kappa = kappa
        if prev is not None:
            # The previous boxes in the current period image (the camera may have crossed a tile boundary).
            dz = wrap_near(prev.lo[0, 2] - boxes.lo[0, 2], 0.0) - (prev.lo[0, 2] - boxes.lo[0, 2])
            prev = Boxes(prev.lo + [0.0, 0.0, dz], prev.hi + [0.0, 0.0, dz], prev.fade, prev.nu)
        pos_l, d_l, lay_l = [], [], []
        for k in range(len(boxes.nu)):
            pos, d = self._new_region(k, boxes, prev, wind[[0, 2]], dt, kappa * boxes.nu[k], rate)
            pos_l.append(pos)
            d_l.append(d)
            lay_l.append(np.full(len(d), k, dtype=np.int64))
        pos, d, lay = np.concatenate(pos_l), np.concatenate(d_l), np.concatenate(lay_l)
        n = len(d)
        upd.candidates = n
        if n == 0:
            return
        speed_w = float(np.hypot(wind[0], wind[2]))
        u = np.zeros((n, 3))
        u[:, 0] = wind[0]
        u[:, 2] = wind[2]
        if speed_w > 0:
            u[:, [0, 2]] += self.rng.normal(0.0, TURBULENCE * speed_w, (n, 2))
        u[:, 1] = -physics.terminal_velocity(d)
        keep, life = self.fate(pos, u, boxes, inp.vehicles)
        upd.rejected = int(n - keep.sum())
        idx = np.flatnonzero(keep)
        if idx.size > self.pool.n_free:
            upd.overflow = int(idx.size - self.pool.n_free)
            self.pool.overflow += upd.overflow
            idx = np.sort(self.rng.permutation(idx)[: self.pool.n_free])
        slots = self.pool.allocate(idx.size)
        if slots.size == 0:
            return
        self.pos0[slots] = pos[idx]
        self.vel[slots] = u[idx]
        self.t0[slots] = t
        self.t_hit[slots] = t + life[idx]
        self.diameter[slots] = d[idx]
        self.weight[slots] = n_eff / kappa
        self.layer[slots] = lay[idx]
        self._schedule(slots, pos[idx], t, boxes, v_cam)
        upd.spawn_slots = slots
        upd.spawn_texels = self._pack(pos[idx], u[idx], t, life[idx], d[idx], n_eff / kappa, lay[idx])

    def texels(self, slots) -> np.ndarray:
        """The GPU record (n, 3, 4) float32 of slots: (x, y, z mod PERIOD_M, t0 mod TIME_PERIOD_S),
        (u_x, u_y, u_z, lifetime), (D mm, weight, layer, 0)."""
        slots = np.asarray(slots)
        return self._pack(self.pos0[slots], self.vel[slots], self.t0[slots], self.t_hit[slots] - self.t0[slots],
                          self.diameter[slots], self.weight[slots], self.layer[slots])

    @staticmethod
    def _pack(pos, vel, t0, life, d, weight, layer) -> np.ndarray:
        out = np.zeros((len(pos), 3, 4), dtype=np.float32)
        out[:, 0, 0:2] = pos[:, 0:2]
        out[:, 0, 2] = np.mod(pos[:, 2], PERIOD_M)
        out[:, 0, 3] = np.mod(t0, TIME_PERIOD_S)
        out[:, 1, 0:3] = vel
        out[:, 1, 3] = life
        out[:, 2, 0] = d
        out[:, 2, 1] = weight
        out[:, 2, 2] = layer
        return out

    # --- splashes ---

    def splash_rate_per_s(self, rate_mm_h: float, area_m2: float, density_scale: float = 1.0) -> tuple[float, float]:
        """(splashes drawn per s, real impacts each stands for) on area_m2 of open ground at R (mm/h)."""
        phys = density_scale * splash_flux_per_m2_s(rate_mm_h) * area_m2
        cap = 0.8 * self.splash_capacity / SPLASH_LIFE_S[1]
        ref = splash_flux_per_m2_s(BUDGET_FULL_AT_MM_H) * area_m2
        drawn = min(cap, phys * min(1.0, cap / ref)) if ref > 0 else 0.0
        return drawn, (phys / drawn if drawn > 0 else 0.0)

    def _spawn_splashes(self, t, span, boxes: Boxes, inp: RainInput, upd: RainUpdate) -> None:
        """Impacts during the last ``span`` seconds on the open ground of the splash layer's box."""
        rate = self.rate_eff
        if rate <= 0.0 or self.splash_capacity == 0:
            return
        lo, hi = boxes.lo[SPLASH_LAYER], boxes.hi[SPLASH_LAYER]
        area = float((hi[0] - lo[0]) * (hi[2] - lo[2]))
        per_s, weight = self.splash_rate_per_s(rate, area, inp.density_scale)
        n = min(int(self.rng.poisson(per_s * span)), self.splash_capacity)
        if n == 0:
            return
        rng = self.rng
        x = lo[0] + rng.random(n) * (hi[0] - lo[0])
        z = lo[2] + rng.random(n) * (hi[2] - lo[2])
        t_imp = t - rng.random(n) * span
        open_ = np.ones(n, dtype=bool)
        if self.world is not None and hasattr(self.world, "occluder_height"):
            open_ &= ~np.isfinite(np.asarray(self.world.occluder_height(x, z)))
        for veh in inp.vehicles:
            c = np.asarray(veh.position, dtype=np.float64)
            rx, rz = x - c[0], wrap_near(z - c[2], 0.0)
            cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
            lx, lz = cy * rx - sy * rz, sy * rx + cy * rz
            open_ &= ~((np.abs(lx) < veh.spec.width_m / 2 + 0.05) & (np.abs(lz) < veh.spec.length_m / 2 + 0.05))
        # Splashing drops: D ≥ SPLASH_D_MIN_MM, impacts ∝ N(D)·v(D) (rejection on v).
        lam = physics.mp_slope_per_mm(rate)
        d = sample_truncated_exp(rng, lam, SPLASH_D_MIN_MM, physics.D_MAX_MM, 4 * n)
        d = d[rng.random(d.size) * physics.terminal_velocity(physics.D_MAX_MM) < physics.terminal_velocity(d)]
        if d.size < n:
            d = np.concatenate([d, np.full(n - d.size, SPLASH_D_MIN_MM)])
        d = d[:n]
        kerb = (np.abs(x) >= layout.ROAD_HALF_WIDTH_M) & (np.abs(x) <= layout.ROAD_HALF_WIDTH_M
                                                          + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M)
        y = np.where(kerb, layout.KERB_HEIGHT_M, GROUND_Y_M)
        on_road = np.abs(x) < layout.ROAD_HALF_WIDTH_M
        if self.world is not None and hasattr(self.world, "road_height01"):
            puddle = on_road & (np.asarray(self.world.road_height01(x, z)) < inp.puddles)
        else:
            puddle = np.zeros(n, dtype=bool)
        kind = np.where(puddle, TYPE_PUDDLE_CROWN, np.where(inp.wetness >= 0.3, TYPE_FILM_CROWN, TYPE_PROMPT))
        life = splash_life_s(d)
        keep = np.flatnonzero(open_)
        m = keep.size
        if m == 0:
            return
        slots = (self.splash_head + np.arange(m)) % self.splash_capacity
        self.splash_head = int((self.splash_head + m) % self.splash_capacity)
        self.splash_t0[slots] = t_imp[keep]
        self.splash_life[slots] = life[keep]
        self.splash_pos[slots] = np.stack([x[keep], y[keep], z[keep]], axis=1)
        self.splash_weight[slots] = weight
        data = np.zeros((m, 8), dtype=np.float32)
        data[:, 0] = x[keep]
        data[:, 1] = y[keep]
        data[:, 2] = np.mod(z[keep], PERIOD_M)
        data[:, 3] = np.mod(t_imp[keep], TIME_PERIOD_S)
        data[:, 4] = d[keep]
        data[:, 5] = life[keep]
        data[:, 6] = kind[keep] + 0.999 * rng.random(m)  # type + a seed for the droplet pattern
        data[:, 7] = weight
        upd.splash_slots = slots
        upd.splash_data = data
