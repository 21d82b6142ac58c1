"""``WindshieldSim``: the fast path of the water on the windshield (CPU, float64, NumPy).

The model, the bookkeeping and every formula are those of ``WindshieldSimReference`` (``reference``), which this
class extends; it computes the same state with far fewer NumPy calls (issue 13: 2,000 drops at 120 km/h in
≤ 1 ms a step), and bounds its work per step whatever the input (issue 18). How:

* **One array of drops**. Position, velocity, mass, trail run, contact radius and the film cell under the drop
  are the columns of one preallocated (capacity, 8) array: appending writes rows, removing drops is one
  compaction of whole rows, sorting one gather. ``pos``, ``vel``, ``mass``, ``trail`` and ``fresh`` are views of
  it, as the reference's arrays were (assign ``pos`` or ``mass`` whole, through their setters, to keep the cell
  and the radius with them).
* **The radius is kept, not recomputed.** A cube root costs ~40 ns a drop; the reference takes five per drop a
  step. Here new and merged drops get an exact one, running drops (whose mass changes by a few per cent) one after
  their run, and the slow evaporation of all drops one Newton step from the last radius (relative error
  ≲ 1e-8 for the smallest drops, not accumulating: each step restarts from the current mass).
* **Only what moves is moved.** Forces are evaluated for every drop (they decide which start), the sliding update
  only for the drops that are moving or starting. What depends on a drop's position alone (its film cell, the
  air's factors there, gravity along the curved glass, its merge-grid key) is kept in its row, written where a
  drop is placed (``_placed``: born, moved, merged), so the many drops at rest cost a few operations a step.
  The merge test gets the motion as columns of the drops that slid (``_merge_moves``).
* **Arrivals without binary searches**. The flux-weighted size law is sampled through a bucket table over its
  cumulative distribution (a gather instead of ``np.interp``'s search; only the far tail searches), built only
  for large samples (a frame's few hundred arrivals search the 512-point CDF), and the impact speed comes from
  the same interval. The film's drying in the air is recomputed from per-cell factors when the car's speed
  changes. What the effect draws of a step (impacts, trails) is kept as
  columns and assembled only when asked.
* **Merging through tables**. ``grid.PairFinder`` keeps the occupied cells in tables so a neighbour lookup is a
  gather; the merge groups are formed on the few drops that touch, not on all of them.
* **Wiping a sector, not the glass**. A blade's sweep first keeps the drops inside its wedge (two half-planes),
  then tests those exactly as the reference does; film cells come from a per-blade table sorted by angle.

Modules: ``drop_rows`` (the array's columns), ``arrivals`` (the bucket table), ``fast_merging`` and
``fast_wiping`` (mixins ahead of the reference's ``merging`` and ``wiping``).

Work bounds per sub-step (``constants``): MAX_ARRIVALS_PER_SUBSTEP arrivals, MERGE_CELLS_MAX / MERGE_PAIRS_MAX
merge work, the drop budget of the inputs. ``tests/effects/windshield/test_fast_path.py`` compares this class
with the reference: the same seed gives the same drops (to rounding) over a few seconds of driving in heavy
rain with the wipers on, and the same statistics over longer runs.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from rain_core import checks
from rain_core.effects.windshield.arrivals import ArrivalTable
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BL_RUN_UP_M,
    CROSSWIND_GAIN,
    DRAG_CD,
    DROP_EVAP_KG_M_S,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    FRONTAL_PER_RADIUS2,
    GAMMA_W,
    HEIGHT_PER_RADIUS,
    HYSTERESIS,
    KINETIC_PIN,
    M_OBJECT_MIN,
    MAX_ARRIVALS_PER_SUBSTEP,
    MAX_SUBSTEP_S,
    MU_W,
    NU_AIR,
    SPLASH_MAX,
    SPLASH_SPEED_M_S,
    TRAIL_FILM_M,
    TRAIL_FRACTION,
    TRAIL_PARENT_MIN,
    TRAIL_SPACING_RADII,
    V_STOP_M_S,
    VISCOUS_C,
    VOLUME_PER_RADIUS3,
    drop_radius,
)
from rain_core.effects.windshield.drop_rows import BL as _BL
from rain_core.effects.windshield.drop_rows import CELL as _CELL
from rain_core.effects.windshield.drop_rows import COLS as _COLS
from rain_core.effects.windshield.drop_rows import GS as _GS
from rain_core.effects.windshield.drop_rows import GT as _GT
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import PLACED as _PLACED
from rain_core.effects.windshield.drop_rows import ROW as _ROW
from rain_core.effects.windshield.drop_rows import TRAIL as _TRAIL
from rain_core.effects.windshield.drop_rows import UP as _UP
from rain_core.effects.windshield.drop_rows import VS as _VS
from rain_core.effects.windshield.drop_rows import VT as _VT
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import Q as _Q
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.fast_merging import FastMerging
from rain_core.effects.windshield.fast_wiping import FastWiping
from rain_core.effects.windshield.grid import GRID_CELL_M, PairFinder, _grid_shape
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.reference import WindshieldSimReference, _check_inputs
from rain_core.physics import G_M_S2, RHO_AIR, RHO_WATER
from rain_core.vehicles import CAR_SPEC, VehicleSpec

_MASS_PER_A3 = RHO_WATER * VOLUME_PER_RADIUS3  # kg / m³: a drop's mass over its contact radius cubed
_EMPTY1 = np.zeros(0)
_EMPTY_I = np.zeros(0, np.int64)
_GRID_O = (-1.0, -0.2)  # grid._GRID_ORIGIN, as floats for the sort key
_G0, _G1 = _grid_shape(GRID_CELL_M)


class WindshieldSim(FastMerging, FastWiping, WindshieldSimReference):
    """Water on the windshield: drops, film, wiper beads and the wipers (the fast path; see the module
    docstring). Same constructor, state and queries as ``WindshieldSimReference``."""

    def __init__(self, spec: VehicleSpec = CAR_SPEC, seed: int = 0):
        super().__init__(spec, seed)
        g = self.glass
        self._pairs = PairFinder()
        self._merged_away: np.ndarray | None = None  # rows the last merge emptied, until _shed_outside
        self._sensor: float | None = 0.0
        self._inputs_seen: GlassInputs | None = None
        self._table: ArrivalTable | None = None
        self._air_key: bytes | None = None
        self._w0, self._dw, self._height = g.width_bottom, g._dw, g.height
        self._sensor_box = (self.sensor_lo.tolist(), self.sensor_hi.tolist())
        self._sensor_area = float(np.prod(self.sensor_hi - self.sensor_lo))
        # Gravity along the curved glass (GlassGeometry.gravity), its constants folded.
        self._g_up = -G_M_S2 * float(g.up[1])
        self._g_sag = -G_M_S2 * g.sag * float(g.normal[1])
        # Per blade: bin radii of its bead, and its film cells sorted by angle (a sweep is a range of them).
        self._bin_r = []
        self._cells_by_angle = []
        self._bins_of_cells = []
        for b, blade in enumerate(self.blades):
            self._bin_r.append(
                blade.r_inner_m + (np.arange(BEAD_BINS) + 0.5) / BEAD_BINS * (blade.r_outer_m - blade.r_inner_m)
            )
            r_c, phi_c = self._cell_polar[b]
            order = np.argsort(phi_c, kind="stable")
            reach = (r_c[order] >= blade.r_inner_m) & (r_c[order] <= blade.r_outer_m)  # the cells it can sweep
            self._cells_by_angle.append((order[reach], phi_c[order][reach]))
            self._bins_of_cells.append(self._bin_of(blade, r_c))
        # The air over each film cell (airflow.air_velocity) is head·_cell_up (or head·FLOW_AT_BOTTOM in a
        # tailwind) along the glass and |up|·FLOW_SPREAD·_cell_q + CROSSWIND_GAIN·cross across it: the
        # position-only factors, kept so the film's drying costs a few operations when the car's speed changes.
        ct = self.cell_centres.reshape(-1, 2)
        frac = np.clip(ct[:, 1] / g.height, 0.0, 1.0)
        self._cell_up = FLOW_AT_BOTTOM + (FLOW_AT_TOP - FLOW_AT_BOTTOM) * frac
        self._cell_q = 2.0 * ct[:, 0] / g.width(ct[:, 1])

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        del state["_rows"]  # a view of _buf: rebuilt on the copy's own array (copy.deepcopy, pickle)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._rows = self._buf.view(_ROW).ravel()

    def load_state(self, other: WindshieldSimReference) -> None:
        """Take over the whole state of another simulation of the same glass (its drops, film, beads, wipers,
        counters and random generator), e.g. a reference's, to run both on from the same glass."""
        self._n = 0
        self._append(other.pos, other.vel, other.mass)
        self.trail[:] = other.trail
        self.fresh[:] = other.fresh
        self.film = other.film.copy()
        self.beads = other.beads.copy()
        self.rng = copy.deepcopy(other.rng)
        self.wipers = copy.deepcopy(other.wipers)
        for name in ("arrived", "wiped", "shed", "evaporated", "time_s", "arrival_count", "merges", "_budget"):
            setattr(self, name, getattr(other, name))

    # --- the drop array ---------------------------------------------------------------------------------------
    def _init_drops(self) -> None:
        self._n = 0
        self._buf = np.zeros((512, _COLS))
        self._rows = self._buf.view(_ROW).ravel()  # one element a drop: whole-row gathers are ~7× faster
        self._fresh_buf = np.zeros(512, bool)  # born, grown or merged since the last merge test

    @property
    def pos(self) -> np.ndarray:
        return self._buf[: self._n, _S : _T + 1]

    @pos.setter
    def pos(self, value) -> None:
        d = self._buf[: self._n]
        d[:, _S : _T + 1] = value
        d[:, _PLACED] = self._placed(d[:, _S], d[:, _T])

    @property
    def vel(self) -> np.ndarray:
        return self._buf[: self._n, _VS : _VT + 1]

    @vel.setter
    def vel(self, value) -> None:
        self._buf[: self._n, _VS : _VT + 1] = value

    @property
    def mass(self) -> np.ndarray:
        return self._buf[: self._n, _M]

    @mass.setter
    def mass(self, value) -> None:
        self._buf[: self._n, _M] = value
        self._buf[: self._n, _A] = drop_radius(self._buf[: self._n, _M])

    @property
    def trail(self) -> np.ndarray:
        return self._buf[: self._n, _TRAIL]

    @trail.setter
    def trail(self, value) -> None:
        self._buf[: self._n, _TRAIL] = value

    @property
    def fresh(self) -> np.ndarray:
        return self._fresh_buf[: self._n]

    @fresh.setter
    def fresh(self, value) -> None:
        self._fresh_buf[: self._n] = value

    @property
    def count(self) -> int:
        return self._n

    def radius(self) -> np.ndarray:
        """Contact radius (m) of each drop."""
        return self._buf[: self._n, _A].copy()

    @property
    def sensor_kg_m2(self) -> float:
        """The rain sensor's reading (kg/m²): as the wipers saw it in the last step in auto mode, else now."""
        return self._sensor if self._sensor is not None else self.sensor_reading()

    @sensor_kg_m2.setter
    def sensor_kg_m2(self, value: float) -> None:
        self._sensor = value

    def sensor_reading(self) -> float:
        """The reference's ``sensor_reading`` on the drop array's columns (the same drops, the same sums)."""
        d = self._buf[: self._n]
        s, t = d[:, _S], d[:, _T]
        lo, hi = self._sensor_box
        inside = (s >= lo[0]) & (s <= hi[0]) & (t >= lo[1]) & (t <= hi[1])
        drops = float(d[inside, _M].sum()) / self._sensor_area
        film = float(self.film.ravel()[self._sensor_cells].sum()) / max(self._sensor_cell_area, 1e-12)
        return drops + film

    def _reserve(self, n: int) -> None:
        if n > len(self._buf):
            cap = max(n, 2 * len(self._buf))
            buf = np.zeros((cap, _COLS))
            buf[: self._n] = self._buf[: self._n]
            fresh = np.zeros(cap, bool)
            fresh[: self._n] = self._fresh_buf[: self._n]
            self._buf, self._fresh_buf = buf, fresh
            self._rows = buf.view(_ROW).ravel()

    def _append(self, pos: np.ndarray, vel: np.ndarray, mass: np.ndarray, radius: np.ndarray | None = None) -> None:
        k = len(mass)
        if k == 0:
            return
        n = self._n
        self._reserve(n + k)
        rows = self._buf[n : n + k]
        rows[:, _S : _T + 1] = pos
        rows[:, _VS : _VT + 1] = vel
        rows[:, _M] = mass
        rows[:, _TRAIL] = 0.0
        rows[:, _A] = drop_radius(mass) if radius is None else radius
        rows[:, _PLACED] = self._placed(rows[:, _S], rows[:, _T])
        self._fresh_buf[n : n + k] = True
        self._n = n + k

    def _keep(self, keep: np.ndarray) -> None:
        n = self._n
        rows = self._rows[:n][keep]
        fresh = self._fresh_buf[:n][keep]
        k = len(rows)
        self._rows[:k] = rows
        self._fresh_buf[:k] = fresh
        self._n = k

    def _sort_drops(self) -> None:
        """Keep the drops in merge-grid cell order (grid.grid_keys), as the reference does."""
        n = self._n
        if n < 2:
            return
        keys = self._buf[:n, _KEY]
        if not (keys[1:] < keys[:-1]).any():
            return
        order = np.argsort(keys, kind="stable")
        self._rows[:n] = self._rows[:n].take(order)
        self._fresh_buf[:n] = self._fresh_buf[:n][order]

    # --- glass helpers (GlassGeometry's formulas on columns, without building (n, 2) arrays) -----------------
    def _inside(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        return (t >= 0.0) & (t <= self._height) & (np.abs(s) <= 0.5 * (self._w0 + self._dw * t))

    def _cells(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Film cell (GlassGeometry.cell_index) of points (s, t) m on the glass."""
        u = np.minimum(s / (self._w0 + self._dw * t) * FILM_CELLS + 0.5 * FILM_CELLS, FILM_CELLS - 0.5)
        v = np.minimum(t * (FILM_CELLS / self._height), FILM_CELLS - 0.5)
        return (v.astype(np.int64) * FILM_CELLS) + u.astype(np.int64)

    def _placed(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The position's columns (drop_rows CELL … KEY) of drops at (s, t) m, (k, 7): the film cell, the air's
        factors, the boundary layer's run, gravity per unit mass and the merge-grid key, with the operations
        (so the bits) of the formulas they replace in ``_move`` and ``_sort_drops``."""
        out = np.empty((len(s), 7))
        out[:, 0] = self._cells(s, t)
        height = self._height
        w = self._w0 + self._dw * t
        frac = np.minimum(np.maximum(t / height, 0.0), 1.0)
        out[:, 1] = FLOW_AT_BOTTOM + (FLOW_AT_TOP - FLOW_AT_BOTTOM) * frac
        out[:, 2] = 2.0 * s / w
        out[:, 3] = NU_AIR * (BL_RUN_UP_M + np.maximum(t, 0.0))
        # Gravity along the curved glass (GlassGeometry.gravity), per unit mass.
        x = 2.0 * (s / w + 0.5) - 1.0
        y = 2.0 * (t / height) - 1.0
        bv = 1.0 - y * y
        dbu = -4.0 * x
        out[:, 4] = self._g_sag * (dbu / w * bv)
        out[:, 5] = self._g_up + self._g_sag * (dbu * (-s * self._dw / (w * w)) * bv + (1.0 - x * x) * (-4.0 * y)
                                                / height)
        k0 = np.minimum(np.maximum(((s - _GRID_O[0]) / GRID_CELL_M).astype(np.int64), 0), _G0 - 1)
        k1 = np.minimum(np.maximum(((t - _GRID_O[1]) / GRID_CELL_M).astype(np.int64), 0), _G1 - 1)
        out[:, 6] = k0 * _G1 + k1
        return out

    # --- inputs -------------------------------------------------------------------------------------------
    def _prepare(self, inputs: GlassInputs) -> None:
        """Per-inputs work, redone only when they change: the arrival law, the air, the film's drying."""
        if inputs is self._inputs_seen:
            return
        self._inputs_seen = inputs
        key = (
            inputs.rate_mm_h,
            inputs.sheltered,
            inputs.drop_scale,
            inputs.car_rotation.tobytes(),
            inputs.car_velocity_m_s.tobytes(),
            inputs.wind_m_s.tobytes(),
        )
        if self._rate_cache is None or self._rate_cache[0] != key:
            rate, closing, cdf = self.arrival_rate_per_s(inputs)
            self._rate_cache = (key, (rate, closing, cdf))
            self._table = ArrivalTable(closing, cdf) if rate > 0 else None
        air_local = inputs.relative_air_local()
        air_key = air_local.tobytes()
        if air_key != self._air_key:
            self._air_key = air_key
            self._air_local = air_local
            head, cross = float(air_local[2]), float(air_local[0])
            up = head * self._cell_up if head >= 0.0 else np.full(len(self._cell_up), head * FLOW_AT_BOTTOM)
            side = np.abs(up) * FLOW_SPREAD * self._cell_q + CROSSWIND_GAIN * cross
            air = np.sqrt(side * side + up * up)  # norm2(air_velocity(...)) of the cell centres
            self._evap = FILM_EVAP_KG_M2_S * (1.0 + air / EVAP_AIR_M_S) * self._areas_flat

    # --- the step -------------------------------------------------------------------------------------------
    def step(self, dt_s: float, inputs: GlassInputs) -> None:
        """Advance the water and the wipers by dt_s seconds (finite, ≥ 0; clamped to checks.MAX_FRAME_DT_S)."""
        dt_s = checks.time_step(dt_s)
        if type(inputs) is not GlassInputs:
            _check_inputs(inputs)
        self._reset_frame_records()
        if dt_s == 0.0:
            return
        self._budget = inputs.drop_budget
        self._prepare(inputs)
        rate = self._rate_cache[1][0]
        air_local = self._air_local
        n_sub = max(1, math.ceil(dt_s / MAX_SUBSTEP_S - 1e-9))
        h = dt_s / n_sub
        auto = inputs.wiper_mode == "auto"
        wipers = self.wipers
        for _ in range(n_sub):
            if rate > 0.0:
                self._arrive_fast(h, rate, inputs)
            self._merge_moves(*self._move(h, air_local, inputs))
            self._shed_outside()
            self._sensor = self.sensor_reading() if auto else None
            segments = wipers._advance(
                h,
                inputs.wiper_mode,
                inputs.wiper_interval_s,
                inputs.wiper_low_cpm,
                inputs.wiper_high_cpm,
                self._sensor if auto else 0.0,
                inputs.wiper_sensitivity,
            )
            for seg in segments:
                self._sweep(seg, inputs.blade_wear)
            self._film_step(h, self._evap, inputs)
            self._sort_drops()
        self.time_s += dt_s

    # --- arrivals -------------------------------------------------------------------------------------------
    def _arrive_fast(self, h: float, rate_per_s: float, inputs: GlassInputs) -> None:
        """The reference's ``_arrive`` (same random numbers, same outcome)."""
        rng = self.rng
        n_all = int(rng.poisson(rate_per_s * h))
        if n_all == 0:
            return
        n = min(n_all, MAX_ARRIVALS_PER_SUBSTEP)
        d_mm, u_n = self._table.sample(rng.random(n))
        m = (RHO_WATER * math.pi / 6.0 * 1e-9) * (d_mm * d_mm * d_mm)
        # GlassGeometry.sample_uniform, inlined: its u (across) and x (up) are also the film cell's u and v.
        g = self.glass
        u1, u2 = rng.random(n), rng.random(n)
        w0, dw, height = self._w0, self._dw * self._height, self._height
        q = u1 * (w0 + 0.5 * dw)
        x = 2.0 * q / (w0 + np.sqrt(w0 * w0 + 2.0 * dw * q)) if dw != 0 else q / w0
        v = np.minimum(np.maximum(x, 0.0), 1.0)
        t = v * height
        s = (u2 - 0.5) * g.width(t)
        self.arrived += float(m.sum())
        self.arrival_count += n
        lo, hi = SPLASH_SPEED_M_S
        splash = np.minimum(np.maximum((u_n - lo) / (hi - lo), 0.0), 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        is_obj = keep >= M_OBJECT_MIN
        cells = self._cells(s, t)
        room = max(self._budget - self._n, 0)
        obj = np.flatnonzero(is_obj)
        landed = is_obj
        if len(obj) > room:
            # A full glass: the surplus lands on (joins) a drop already in its cell, or else the film.
            over = obj[room:]
            obj = obj[:room]
            landed = is_obj.copy()
            landed[over] = self._give_to_drops(cells[over], keep[over])
        to_film = m - np.where(landed, keep, 0.0)
        self.film.ravel()[:] += np.bincount(cells, weights=to_film, minlength=FILM_CELLS * FILM_CELLS)
        a_obj = drop_radius(keep[obj])
        self._impacts.append((s, t, d_mm, splash, obj, a_obj, to_film))
        if len(obj):
            self._append(np.column_stack([s[obj], t[obj]]), 0.0, keep[obj], a_obj)
        if n_all > n:
            self._arrive_as_mist(n_all - n, float(m.mean()))

    def _give_to_drops(self, cells: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """Add each mass (kg) to a random drop of its film cell; returns which ones found a drop."""
        placed = np.zeros(len(cells), bool)
        n = self._n
        if n == 0 or len(cells) == 0:
            return placed
        d = self._buf[:n]
        drop_cells = d[:, _CELL].astype(np.int16)
        counts = np.bincount(drop_cells, minlength=FILM_CELLS * FILM_CELLS)
        c = counts[cells]
        placed = c > 0
        if placed.any():
            order = np.argsort(drop_cells, kind="stable")  # 16-bit keys: a radix sort
            starts = np.cumsum(counts) - counts
            pick = order[starts[cells[placed]] + self.rng.integers(0, c[placed])]
            np.add.at(d[:, _M], pick, mass[placed])
            d[pick, _A] = drop_radius(d[pick, _M])
            self._fresh_buf[pick] = True
        return placed

    # --- motion (dynamics.DropDynamics._move) ---------------------------------------------------------------
    def _move(self, h: float, air_local: np.ndarray, inputs) -> tuple:
        """Forces, pinning, viscous sliding; returns for the merge test (``_merge_moves``) the drop count before
        the step's trail droplets, the drops that slid (``go``), their start (s, t) and displacement (m), as
        columns: the others did not move."""
        n = self._n
        if n == 0:
            return 0, _EMPTY_I, _EMPTY1, _EMPTY1, _EMPTY1, _EMPTY1
        d = self._buf[:n]
        s, t, m = d[:, _S], d[:, _T], d[:, _M]
        a = d[:, _A]  # the radius at the start of the step (the Newton update below comes after its last use)
        # The air over the glass (airflow.air_velocity), from the position's factors (drop_rows).
        head, cross = float(air_local[2]), float(air_local[0])
        if head >= 0.0:
            up = head * d[:, _UP]
            side = up * FLOW_SPREAD * d[:, _Q] + CROSSWIND_GAIN * cross
        else:  # a tailwind: a weak, separated flow down the glass
            up = np.full(n, head * FLOW_AT_BOTTOM)
            side = abs(head * FLOW_AT_BOTTOM) * FLOW_SPREAD * d[:, _Q] + CROSSWIND_GAIN * cross
        air_speed = np.sqrt(side * side + up * up)
        # Drag in the boundary layer (airflow.drag).
        delta = 5.0 * np.sqrt(d[:, _BL] / np.maximum(air_speed, 1e-3))
        eta = np.minimum(np.maximum(HEIGHT_PER_RADIUS * a / delta, 0.0), 1.0)
        profile = 1.5 * eta - 0.5 * (eta * eta * eta)
        vs, vt = d[:, _VS], d[:, _VT]
        rel_s = side * profile - vs
        rel_t = up * profile - vt
        coef = (0.5 * RHO_AIR * DRAG_CD * FRONTAL_PER_RADIUS2) * a**2 * np.sqrt(rel_s * rel_s + rel_t * rel_t)
        # Gravity along the curved glass (GlassGeometry.gravity), per unit mass from drop_rows.
        f_s = m * d[:, _GS] + coef * rel_s
        f_t = m * d[:, _GT] + coef * rel_t
        fmag = np.sqrt(f_s * f_s + f_t * f_t)
        pin = GAMMA_W * 2.0 * a * HYSTERESIS
        speed = np.sqrt(vs * vs + vt * vt)
        moving = speed > 0.0
        go = np.flatnonzero(moving | (fmag > pin))  # moving, or starting to
        s_g = t_g = ds = dt_ = _EMPTY1
        if len(go):
            # The sliding update, for the drops that slide (the others stay at rest).
            mv = moving[go]
            fs_g, ft_g, fm_g, pin_g, m_g, a_g = f_s[go], f_t[go], fmag[go], pin[go], m[go], a[go]
            vs_g, vt_g, sp_g = vs[go], vt[go], speed[go]
            sp_g, fm_safe = np.maximum(sp_g, 1e-300), np.maximum(fm_g, 1e-300)
            dir_s = np.where(mv, vs_g / sp_g, fs_g / fm_safe)
            dir_t = np.where(mv, vt_g / sp_g, ft_g / fm_safe)
            kp = KINETIC_PIN * pin_g
            damp = 1.0 + h * (VISCOUS_C * MU_W * a_g / m_g)
            nv_s = (vs_g + h * ((fs_g - kp * dir_s) / m_g)) / damp
            nv_t = (vt_g + h * ((ft_g - kp * dir_t) / m_g)) / damp
            stop = mv & (
                (nv_s * vs_g + nv_t * vt_g <= 0.0)
                | ((np.sqrt(nv_s * nv_s + nv_t * nv_t) < V_STOP_M_S) & (fm_g < pin_g))
            )
            nv_s[stop] = 0.0
            nv_t[stop] = 0.0
            d[go, _VS] = nv_s
            d[go, _VT] = nv_t
            ds, dt_ = h * nv_s, h * nv_t
            s_g, t_g = s[go], t[go]
            es, et = s_g + ds, t_g + dt_
            d[go, _S] = es
            d[go, _T] = et
            moved = (ds != 0.0) | (dt_ != 0.0)
            if moved.any():  # (one that left the glass is shed before its columns are read)
                d[go[moved], _PLACED] = self._placed(es[moved], et[moved])
        # Slow evaporation of the drops themselves (hours for a millimetre drop; kept for the balance).
        loss = np.minimum(DROP_EVAP_KG_M_S * a * np.sqrt(1.0 + air_speed / EVAP_AIR_M_S) * h, m)
        m -= loss
        self.evaporated += float(loss.sum())
        # The radius follows the mass: one Newton step from the last radius (see the module docstring).
        ra = d[:, _A]
        ra2 = ra * ra
        ra -= (ra2 * ra - m * (1.0 / _MASS_PER_A3)) / (3.0 * ra2)
        if len(go):
            step_len = np.sqrt(ds * ds + dt_ * dt_)
            run = np.flatnonzero(step_len > 0.0)
            if len(run):
                self._run(go[run], s_g[run], t_g[run], ds[run], dt_[run], step_len[run], a_g[run])
        return n, go, s_g, t_g, ds, dt_

    def _run(self, idx, s0, t0, ds, dt, step_len, a) -> None:
        """Running drops take up the film in their path, lay a thin wet line and drop trail droplets
        (dynamics.DropDynamics._sweep_film_and_trail on the running drops ``idx``, their start (s0, t0) m,
        displacement (ds, dt) m, its length (m) and their radius (m), as 1-D columns)."""
        ms, mt = s0 + 0.5 * ds, t0 + 0.5 * dt
        inside = self._inside(ms, mt)
        if not inside.all():
            sel = np.flatnonzero(inside)
            if len(sel) == 0:
                return
            idx, s0, t0, ds, dt, step_len, a, ms, mt = (v[sel] for v in (idx, s0, t0, ds, dt, step_len, a, ms, mt))
        d = self._buf[: self._n]
        cells = self._cells(ms, mt)
        flat = self.film.ravel()
        swept_area = 2.0 * a * step_len
        frac = swept_area / self._areas_flat[cells]
        total = np.bincount(cells, weights=frac, minlength=flat.size)[cells]
        scale = np.where(total > 1.0, 1.0 / np.maximum(total, 1e-300), 1.0)
        take = flat[cells] * frac * scale
        np.subtract.at(flat, cells, take)
        np.maximum(flat, 0.0, out=flat)
        mass = d[idx, _M]
        wet = np.minimum(RHO_WATER * TRAIL_FILM_M * swept_area, 0.1 * mass)
        np.add.at(flat, cells, wet)
        mass += take - wet
        d[idx, _M] = mass
        es, et = s0 + ds, t0 + dt
        self._trails.append((s0, t0, es, et, a))
        # Trail droplets: one every TRAIL_SPACING_RADII radii of run, behind the drop, from heavy drops only.
        spacing = TRAIL_SPACING_RADII * a
        run = d[idx, _TRAIL] + step_len
        k = np.minimum(np.floor(run / spacing), 4).astype(np.int64)
        k[mass < TRAIL_PARENT_MIN] = 0
        run -= k * spacing
        d[idx, _TRAIL] = np.minimum(run, spacing)
        total_k = int(k.sum())
        if total_k:
            if total_k == np.count_nonzero(k):  # one droplet per drop at most: the common case
                local = np.flatnonzero(k)
                gap = 1.3 * a[local]
            else:
                local = np.repeat(np.arange(len(idx)), k)
                within = np.arange(total_k) - np.repeat(np.cumsum(k) - k, k)
                gap = (1.3 + TRAIL_SPACING_RADII * within) * a[local]
            # Behind the drop on the path it ran, clear of it (so they do not join again at once).
            gap /= step_len[local]
            ws = es[local] - ds[local] * gap
            wt = et[local] - dt[local] * gap
            ok = self._inside(ws, wt)
            if not ok.all():
                local, ws, wt = local[ok], ws[ok], wt[ok]
            parent = idx[local]
            m_t = TRAIL_FRACTION * d[parent, _M]
            np.subtract.at(d[:, _M], parent, m_t)
        d[idx, _A] = drop_radius(d[idx, _M])
        if total_k:
            room = max(self._budget - self._n, 0)
            as_drop = np.zeros(len(m_t), bool)
            as_drop[:room] = m_t[:room] >= M_OBJECT_MIN
            film_part = ~as_drop
            if film_part.any():
                np.add.at(flat, self._cells(ws[film_part], wt[film_part]), m_t[film_part])
            if as_drop.any():
                self._append(np.column_stack([ws[as_drop], wt[as_drop]]), 0.0, m_t[as_drop])

    # --- what the last step did (for drawing): kept as columns, assembled only when asked ------------------
    def frame_impacts(self) -> np.ndarray:
        """Impacts of the last step: (n, 4) s, t (m), splash radius (m), satellite film thickness (m)."""
        rows = []
        for s, t, d_mm, splash, obj, a_obj, to_film in self._impacts:
            r = d_mm * (1e-3 * (math.pi / (6.0 * VOLUME_PER_RADIUS3)) ** (1.0 / 3.0))  # a whole drop's radius ∝ d
            r[obj] = a_obj
            r *= 1.5 + 4.0 * splash
            rows.append(np.column_stack([s, t, r, to_film / (RHO_WATER * math.pi * r * r)]))
        return np.concatenate(rows) if rows else np.zeros((0, 4))

    def frame_trails(self) -> np.ndarray:
        """Paths of running drops in the last step: (n, 5) s0, t0, s1, t1 (m), drop radius (m)."""
        rows = [np.column_stack(cols) for cols in self._trails]
        return np.concatenate(rows) if rows else np.zeros((0, 5))

    def _shed_outside(self) -> None:
        """Drops that left the glass are shed; drops worn below half the object size become film. The drops
        the step's merge joined into others go too: one compaction for all three (the reference compacts after
        each; the sums run over the same drops in the same order)."""
        n = self._n
        gone = self._merged_away
        self._merged_away = None
        if n == 0:
            return
        d = self._buf[:n]
        outside = ~self._inside(d[:, _S], d[:, _T])
        if gone is not None:
            outside[gone] = False  # no longer drops
        if outside.any():
            self.shed += float(d[outside, _M].sum())
        tiny = d[:, _M] < 0.5 * M_OBJECT_MIN
        tiny &= ~outside
        if gone is not None:
            tiny[gone] = False
        if tiny.any():
            np.add.at(self.film.ravel(), self._cells(d[tiny, _S], d[tiny, _T]), d[tiny, _M])
        drop = outside | tiny
        if gone is not None:
            drop[gone] = True
        if drop.any():
            self._keep(~drop)
