"""The rainfall simulation (CPU, NumPy only). Drops have no state: ``RainfallSim.advance(RainInput) ->
RainUpdate`` computes, once per frame, the few numbers the shaders need (the boxes, the wind's integral, the
thinning, the splash rate), whatever the budget; ``drops`` and ``splashes`` are the float64 twins of the
shaders (``shaders/rainfall/drops.glsl``, ``splash.vert``) for the tests and the benchmark."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from rain_core import checks, layout, physics
from rain_core.effects.rainfall.boxes import Boxes, box_heights, drawn_density_factor, layer_boxes, membership
from rain_core.effects.rainfall.constants import (
    BOX_BOTTOM_Y_M,
    BUDGET_FULL_AT_MM_H,
    GROUND_Y_M,
    LAYER_PROFILE,
    LAYER_SCALES,
    RATE_OFF_MM_H,
    RATE_RAMP_S,
    SPLASH_CAPACITY_MAX,
    SPLASH_CAPACITY_MIN,
    SPLASH_D_MIN_MM,
    SPLASH_LAYER,
    SPLASH_PERIOD_S,
    TYPE_FILM_CROWN,
    TYPE_PROMPT,
    TYPE_PUDDLE_CROWN,
)
from rain_core.effects.rainfall.drops import (
    SALT_D,
    SALT_KEEP,
    SALT_KIND,
    SALT_PHASE,
    SALT_SPLASH,
    SALT_TURB_X,
    SALT_TURB_Z,
    SALT_V,
    SALT_X,
    SALT_Z,
    TURB_EPS,
    cycle_hash,
    cycles,
    drop_table,
    hash32,
    instance_keys,
    seed_key,
    table_bin,
    truncated_exp_quantile,
    turbulence_steps,
    u01,
)
from rain_core.effects.rainfall.rates import LAM_INSTANCES, splash_flux_per_m2_s, splash_life_s, thinning
from rain_core.effects.rainfall.vehicle_fate import cull_vehicles, inside_vehicles

CAPACITY_MAX = 4_000_000  # instances; the settings allow 1M (quality.particle_budget)
CONTAINER_RANGE_M = (10.0, 120.0)  # m, as the settings' rainfall.container_m
DENSITY_SCALE_MAX = 4.0  # as the settings' rainfall.density_scale
# Splash fall speeds for the shader's table (u_splash_v): D = SPLASH_D_MIN_MM … D_MAX_MM in 15 steps.
SPLASH_V_D_MM = np.linspace(SPLASH_D_MIN_MM, physics.D_MAX_MM, 16)
SPLASH_V_M_S = np.asarray(physics.terminal_velocity(SPLASH_V_D_MM)).astype(np.float32).astype(np.float64)


@dataclass
class RainInput:
    """What the rain simulation needs from one frame. Positions and velocities in the world frame (m, m/s).
    Validated on construction: ValueError naming the field and its range."""

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

    def __post_init__(self):
        self.time_s = checks.number("time_s", self.time_s, unit="s")
        self.camera_position = checks.vec3("camera_position", self.camera_position, "m")
        self.camera_forward = checks.vec3("camera_forward", self.camera_forward, "any length")
        self.camera_velocity = checks.vec3("camera_velocity", self.camera_velocity, "m/s", physics.MAX_SPEED_M_S)
        self.rate_mm_h = checks.number("rate_mm_h", self.rate_mm_h, 0.0, physics.R_MAX_MM_H, "mm/h")
        self.wind_m_s = checks.vec3("wind_m_s", self.wind_m_s, "m/s", physics.MAX_SPEED_M_S)
        self.container_m = checks.number("container_m", self.container_m, *CONTAINER_RANGE_M, "m")
        self.density_scale = checks.number("density_scale", self.density_scale, 0.0, DENSITY_SCALE_MAX, "×")
        self.wetness = checks.number("wetness", self.wetness, 0.0, 1.0)
        self.puddles = checks.number("puddles", self.puddles, 0.0, 1.0)

    @classmethod
    def unchecked(cls, **fields) -> RainInput:
        """A RainInput of values checked where they entered — the scene's camera, weather and settings — built
        without the per-field checks: RainfallEffect makes one every frame (DESIGN: validate at the boundary, not
        in per-frame loops). Every field must be given, arrays as float64 (3,)."""
        if fields.keys() != _RAIN_INPUT_FIELDS:
            raise TypeError(f"RainInput.unchecked needs exactly the fields {sorted(_RAIN_INPUT_FIELDS)}")
        inp = cls.__new__(cls)
        inp.__dict__.update(fields)
        return inp


_RAIN_INPUT_FIELDS = frozenset(RainInput.__dataclass_fields__)


@dataclass
class RainUpdate:
    """One frame's state of the rain, all the GPU needs (uniforms; nothing per drop). Units: m, s, m/s, mm/h."""

    time_s: float
    boxes: Boxes  # world frame
    rate_mm_h: float  # the effect's rate (ramped)
    wind_m_s: np.ndarray
    wind_integral_m: np.ndarray  # ∫ wind dt (float64; the shader gets it modulo each box)
    thin_a: float  # r(D) = thin_a·exp(−thin_b·D): real drops per m³ per unit instance density (rates.thinning)
    thin_b: float
    thin_c: float
    density: np.ndarray  # (L,) instances per m³ of each layer's box
    starts: np.ndarray  # (L + 1,) first instance index of each layer
    drawn_expected: float  # instances expected to pass the thinning
    splash_accept: float  # share of the splash slots' impacts drawn
    splash_weight: float  # real impacts per drawn splash
    splash_lam: float  # 1/mm, Marshall–Palmer slope of the splashing drops
    wetness: float
    puddles: float
    splashes: bool
    vehicles: tuple  # the vehicles that cull drops (nearest first, at most MAX_VEHICLES)
    cpu_ms: float = 0.0


class RainfallSim:
    """The CPU side of the rainfall: per frame a handful of numbers, and the float64 twin of every drop.

    capacity: the particle budget (instances, [0, CAPACITY_MAX]); seed: mixed into every hash (same seed and
    inputs → same drops); world: a rain_core.world.World (its roof map and road height map) or None for open
    ground everywhere. ``advance(RainInput) -> RainUpdate``; ``drops()`` and ``splashes()`` evaluate the
    instances as the shaders do."""

    def __init__(self, capacity: int, seed: int = 0, world=None):
        if isinstance(capacity, bool) or not isinstance(capacity, int | np.integer) or not (
                0 <= capacity <= CAPACITY_MAX):
            raise ValueError(f"capacity must be an integer in [0, {CAPACITY_MAX}] drops, got {checks.quote(capacity)}")
        self.capacity = int(capacity)
        self.seed = int(seed)
        self.key = seed_key(self.seed)
        self.splash_key = self.key ^ SALT_SPLASH
        self.world = world
        self.splash_capacity = int(np.clip(self.capacity // 16, SPLASH_CAPACITY_MIN, SPLASH_CAPACITY_MAX))
        self.container_m: float | None = None
        self.table = np.zeros((len(LAYER_SCALES), 1, 4), np.float32)
        self.table_version = 0
        self._thin_key = None
        self._thin = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
        self.reset()

    def reset(self) -> None:
        """Forget the frame history (the next ``advance`` starts at the set rate, with no wind travelled)."""
        self.rate_eff = 0.0
        self.fade = 0.0  # the air's drops while the rain stops: → 0 with the rate, → 1 while it rains
        self.t_prev: float | None = None
        self.wind_integral = np.zeros(3)
        self.last: RainUpdate | None = None

    @property
    def boxes(self) -> Boxes | None:
        return None if self.last is None else self.last.boxes

    # --- layout: instances per layer, the drop table ---

    def _layout(self, container_m: float) -> None:
        if container_m == self.container_m:
            return
        self.container_m = container_m
        heights = box_heights(container_m)
        h = 0.5 * container_m * np.asarray(LAYER_SCALES)
        volumes = (2.0 * h) ** 2 * heights
        share = np.asarray(LAYER_PROFILE) * volumes
        counts = np.floor(self.capacity * share / share.sum()).astype(np.int64)
        counts[-1] = self.capacity - counts[:-1].sum()
        self.counts = counts
        self.starts = np.concatenate([[0], np.cumsum(counts)])
        self.density = counts / volumes
        self.table = drop_table(heights, LAM_INSTANCES)
        self.table_version += 1
        self._thin_key = None

    # --- one frame ---

    def advance(self, inp: RainInput) -> RainUpdate:
        """Advance to inp.time_s: the rate ramp, the wind's integral, the boxes, the thinning, the splash rate."""
        t_start = time.perf_counter()
        t = inp.time_s
        if self.t_prev is not None and t < self.t_prev - 1e-9:
            self.reset()
        first = self.t_prev is None
        dt = 0.0 if first else t - self.t_prev
        target = inp.rate_mm_h
        fade_target = 1.0 if target > 0.0 else 0.0
        if first:
            self.rate_eff, self.fade = target, fade_target
        else:
            # The rate follows the set rate; the fade empties the air when it stops: Marshall–Palmer's count
            # falls only as R^0.21, so without it the last drops would vanish at once at RATE_OFF_MM_H.
            k = math.exp(-dt / RATE_RAMP_S)
            self.rate_eff = target + (self.rate_eff - target) * k
            self.fade = fade_target + (self.fade - fade_target) * k
            if abs(self.rate_eff - target) < 1e-9 * max(target, 1.0):
                self.rate_eff = target
            if abs(self.fade - fade_target) < 1e-9:
                self.fade = fade_target
            if target == 0.0 and self.rate_eff < RATE_OFF_MM_H:
                self.rate_eff = self.fade = 0.0
        wind = np.asarray(inp.wind_m_s, dtype=np.float64)
        self.wind_integral = self.wind_integral + wind * dt
        self._layout(inp.container_m)
        boxes = layer_boxes(inp.camera_position, inp.camera_forward, inp.container_m)
        scale = inp.density_scale * self.fade
        lo_x, _, lo_z = boxes.lo[SPLASH_LAYER].tolist()  # Python floats: the same float64 products
        hi_x, _, hi_z = boxes.hi[SPLASH_LAYER].tolist()
        area = (hi_x - lo_x) * (hi_z - lo_z)
        key = (self.rate_eff, scale, area)
        if key != self._thin_key:  # the rate settles after the ramp: then nothing here is recomputed
            a, b, c = thinning(self.rate_eff, scale, float(self.density.sum()))
            drawn = drawn_fraction_of_table(self.table, a, b, c) * self.capacity
            lam = float(physics.mp_slope_per_mm(self.rate_eff)) if self.rate_eff > 0 else 1e3
            self._thin = (a, b, c, drawn, *self.splash_rate_per_s(self.rate_eff, area, scale), lam)
            self._thin_key = key
        a, b, c, drawn, per_s, weight, lam = self._thin
        outer = 0.5 * inp.container_m
        cam = inp.camera_position
        near = cull_vehicles(inp.vehicles, (cam[0], cam[2]), 2.0 * outer) if inp.vehicles else []
        upd = RainUpdate(
            time_s=t, boxes=boxes, rate_mm_h=self.rate_eff, wind_m_s=wind, wind_integral_m=self.wind_integral.copy(),
            thin_a=a, thin_b=b, thin_c=c, density=self.density, starts=self.starts, drawn_expected=drawn,
            splash_accept=min(1.0, per_s * SPLASH_PERIOD_S / self.splash_capacity), splash_weight=weight,
            splash_lam=lam,
            wetness=inp.wetness, puddles=inp.puddles, splashes=bool(inp.splashes), vehicles=tuple(near))
        self.last = upd
        self.t_prev = t
        upd.cpu_ms = (time.perf_counter() - t_start) * 1e3
        return upd

    def target_count(self, rate_mm_h: float, density_scale: float = 1.0) -> float:
        """Instances expected to be drawn at rate R (mm/h), by the current layout (after a first ``advance``)."""
        a, b, c = thinning(rate_mm_h, density_scale, float(self.density.sum()))
        return drawn_fraction_of_table(self.table, a, b, c) * self.capacity

    # --- the twin of the shaders ---

    def _frame(self, time_s):
        upd = self.last
        if upd is None:
            raise RuntimeError("RainfallSim: call advance() first")
        t = upd.time_s if time_s is None else float(time_s)
        return upd, t, upd.wind_integral_m + upd.wind_m_s * (t - upd.time_s)

    def layer_of(self, index) -> np.ndarray:
        return np.searchsorted(self.starts, np.asarray(index), side="right") - 1

    def drops(self, index=None, time_s: float | None = None) -> dict[str, np.ndarray]:
        """The instances ``index`` (default all) at time_s (default the last frame's; the wind's integral is
        extrapolated with the last wind), float64, as ``shaders/rainfall/drops.glsl`` computes them.

        Returns arrays: ``index``, ``layer``, ``d_mm``, ``pos`` (n, 3) m world, ``vel`` (n, 3) m/s, ``cycle``
        (uint32), ``s`` (fraction of the current pass), ``drawn`` (passed the thinning), ``occluded`` (under a
        roof, in a vehicle or below the ground), ``visible`` (drawn and not occluded, with a weight > 0),
        ``weight`` (real drops each stands for, membership included)."""
        upd, t, w_int = self._frame(time_s)
        idx = np.arange(self.capacity) if index is None else np.asarray(index, dtype=np.int64)
        layer = self.layer_of(idx)
        keys = instance_keys(idx, self.key)
        phase = u01(hash32(keys ^ SALT_PHASE))
        tab = self.table[layer, table_bin(idx)].astype(np.float64)
        d, m, vq = tab[:, 0], tab[:, 1], tab[:, 2]
        count, s = cycles(m, phase, t)
        hc = cycle_hash(keys, count)
        x0, z0 = u01(hash32(hc ^ SALT_X)), u01(hash32(hc ^ SALT_Z))
        keep = u01(hash32(hc ^ SALT_KEEP))
        jx, jz = turbulence_steps(hc, SALT_TURB_X), turbulence_steps(hc, SALT_TURB_Z)
        boxes = upd.boxes
        lo, ext = boxes.lo[layer], boxes.ext[layer]
        off, turb, yoff = box_offsets(boxes, w_int)
        pos = np.empty((len(idx), 3))
        pos[:, 0] = lo[:, 0] + np.mod(x0 * ext[:, 0] + off[layer, 0] + jx * turb[layer, 0], ext[:, 0])
        pos[:, 1] = lo[:, 1] + np.mod(ext[:, 1] * (1.0 - s) + yoff[layer], ext[:, 1])
        pos[:, 2] = lo[:, 2] + np.mod(z0 * ext[:, 2] + off[layer, 2] + jz * turb[layer, 2], ext[:, 2])
        vel = np.stack([upd.wind_m_s[0] * (1.0 + jx * TURB_EPS), -vq, upd.wind_m_s[2] * (1.0 + jz * TURB_EPS)], 1)
        r = upd.thin_a * np.exp(-upd.thin_b * d)
        drawn = keep < np.minimum(1.0, r / upd.thin_c)
        occluded = pos[:, 1] < GROUND_Y_M
        if self.world is not None:
            occluded |= pos[:, 1] < np.asarray(self.world.occluder_height(pos[:, 0], pos[:, 2]))
        if upd.vehicles:
            occluded |= inside_vehicles(pos, upd.vehicles)
        weight = (np.maximum(r, upd.thin_c) * membership(pos, boxes, layer)
                  / drawn_density_factor(pos, boxes, upd.density))
        visible = drawn & ~occluded & (weight > 0)
        return {"index": idx, "layer": layer, "d_mm": d, "pos": pos, "vel": vel, "cycle": count, "s": s,
                "drawn": drawn, "occluded": occluded, "visible": visible, "weight": weight}

    def positions(self, index, time_s: float | None = None) -> np.ndarray:
        """World positions (m) of instances at time_s (see ``drops``)."""
        return self.drops(index, time_s)["pos"]

    # --- splashes ---

    def splash_rate_per_s(self, rate_mm_h: float, area_m2: float, density_scale: float = 1.0) -> tuple[float, float]:
        """(splashes drawn per s, real impacts each stands for) on area_m2 of open ground at R (mm/h)."""
        phys = density_scale * splash_flux_per_m2_s(rate_mm_h) * area_m2
        cap = 0.8 * self.splash_capacity / SPLASH_PERIOD_S
        ref = splash_flux_per_m2_s(BUDGET_FULL_AT_MM_H) * area_m2
        drawn = min(cap, phys * min(1.0, cap / ref)) if ref > 0 else 0.0
        return drawn, (phys / drawn if drawn > 0 else 0.0)

    def splashes(self, time_s: float | None = None) -> dict[str, np.ndarray]:
        """Every splash slot at time_s (default the last frame's), float64, as ``shaders/rainfall/splash.vert``:
        ``pos`` (n, 3) m world, ``age`` s, ``life`` s, ``d_mm``, ``kind``, ``drawn`` (passed the rate's
        thinning), ``visible`` (drawn, alive, on open ground)."""
        upd, t, _ = self._frame(time_s)
        n = self.splash_capacity
        keys = instance_keys(np.arange(n), self.splash_key)
        phase = u01(hash32(keys ^ SALT_PHASE))
        c0, tau = splash_clock(t)
        x = tau + phase
        fl = np.floor(x)
        count = ((c0 + fl.astype(np.int64)) & 0xFFFFFFFF).astype(np.uint32)
        age = (x - fl) * SPLASH_PERIOD_S
        hc = cycle_hash(keys, count)
        drawn = u01(hash32(hc ^ SALT_KEEP)) < upd.splash_accept
        lo, ext = upd.boxes.lo[SPLASH_LAYER], upd.boxes.ext[SPLASH_LAYER]
        so = np.mod(-lo, ext)
        px = lo[0] + np.mod(u01(hash32(hc ^ SALT_X)) * ext[0] + so[0], ext[0])
        pz = lo[2] + np.mod(u01(hash32(hc ^ SALT_Z)) * ext[2] + so[2], ext[2])
        d = splash_diameters(hc, upd.splash_lam)
        life = splash_life_s(d)
        kerb = (np.abs(px) >= layout.ROAD_HALF_WIDTH_M) & (
            np.abs(px) <= layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M)
        py = np.where(kerb, layout.KERB_HEIGHT_M, GROUND_Y_M)
        pos = np.stack([px, py, pz], axis=1)
        on_road = np.abs(px) < layout.ROAD_HALF_WIDTH_M
        if self.world is not None and hasattr(self.world, "road_height01"):
            puddle = on_road & (np.asarray(self.world.road_height01(px, pz)) < upd.puddles)
        else:
            puddle = np.zeros(n, dtype=bool)
        kind = np.where(puddle, TYPE_PUDDLE_CROWN, np.where(upd.wetness >= 0.3, TYPE_FILM_CROWN, TYPE_PROMPT))
        open_ = np.ones(n, dtype=bool)
        if self.world is not None:
            open_ &= np.asarray(self.world.occluder_height(px, pz)) < py
        if upd.vehicles:
            open_ &= ~inside_vehicles(pos + [0.0, 0.01, 0.0], upd.vehicles)
        visible = upd.splashes & drawn & (age < life) & open_
        return {"pos": pos, "age": age, "life": life, "d_mm": d, "kind": kind, "drawn": drawn, "visible": visible,
                "seed": u01(hash32(hc ^ SALT_KIND))}

    def splashes_live(self, time_s: float | None = None) -> int:
        return int(np.count_nonzero(self.splashes(time_s)["visible"])) if self.last is not None else 0


def drawn_fraction_of_table(table: np.ndarray, a: float, b: float, c: float) -> float:
    if a <= 0:
        return 0.0
    return float(np.mean(np.minimum(1.0, a * np.exp(-b * table[-1, :, 0].astype(np.float64)) / c)))


def box_offsets(boxes: Boxes, wind_integral) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per layer, reduced in float64 so the GPU gets small numbers: off (L, 3) = (∫wind − lo) mod the box (x, z),
    turb (L, 3) = TURB_EPS·∫wind mod the box (x, z), yoff (L,) = (BOX_BOTTOM_Y_M − lo_y) mod the box height."""
    ext = boxes.ext
    w = np.asarray(wind_integral, dtype=np.float64)
    off = np.mod(w[None, :] - boxes.lo, ext)
    turb = np.mod(TURB_EPS * w[None, :], ext)
    off[:, 1] = 0.0
    turb[:, 1] = 0.0
    yoff = np.mod(BOX_BOTTOM_Y_M - boxes.lo[:, 1], ext[:, 1])
    return off, turb, yoff


def splash_clock(t: float) -> tuple[int, float]:
    """(whole splash periods mod 2^32, the fraction) at t (s), from float64."""
    x = t / SPLASH_PERIOD_S
    c0 = math.floor(x)
    return c0 & 0xFFFFFFFF, x - c0


def splash_diameters(hc: np.ndarray, lam: float) -> np.ndarray:
    """Diameters (mm) of the drops that splash, ∝ N(D)·v(D) on [SPLASH_D_MIN_MM, D_MAX_MM]: up to four
    truncated-exponential draws, each kept with probability v(D)/v_max (the last is kept anyway)."""
    v_max = SPLASH_V_M_S[-1]
    d = np.zeros(len(hc))
    done = np.zeros(len(hc), dtype=bool)
    for k in range(len(SALT_D)):
        dk = truncated_exp_quantile(u01(hash32(hc ^ SALT_D[k])), lam, SPLASH_D_MIN_MM, physics.D_MAX_MM)
        ok = u01(hash32(hc ^ SALT_V[k])) * v_max < np.interp(dk, SPLASH_V_D_MM, SPLASH_V_M_S)
        take = ~done & (ok | (k == len(SALT_D) - 1))
        d = np.where(take, dk, d)
        done |= take
    return d
