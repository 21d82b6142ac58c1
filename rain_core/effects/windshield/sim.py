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
* **Only what moves is moved.** Forces are evaluated only for the drops that may slide: a drop at rest keeps a
  bound on its force over its pinning (``fast_motion``: it holds while the drop rests in the same air and only
  loses water), and is not tested while that bound is below 1 (a test compares the two paths bit for bit); the
  sliding update runs only for the drops that are moving or starting. What depends on a drop's position alone
  (its film cell, the air's factors there, gravity along the curved glass, its merge-grid key) is kept in its
  row, written for all the drops placed (born, moved, merged) at once before it is read (``_flush_placed``), so
  the many drops at rest cost a few operations a step. The merge test gets the motion as columns of the drops
  that slid (``_merge_moves``).
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

* **Compiled kernels** where Numba is installed (``rain_core.jit``): each chain of NumPy calls of a sub-step
  (arrivals, motion and runs, the merge test, shedding, a wiper stroke, drying, the sort) is one loop over the
  rows in ``kernels``, the same operations in the same order; the NumPy code stays as their twin (the fallback
  without Numba, and the oracle: ``tests/effects/windshield/test_kernels.py`` compares the glass bit for bit).

Modules: ``drop_rows`` (the array's columns), ``drop_array`` (the array itself), ``arrivals`` (the bucket
table), ``fast_motion``, ``fast_merging`` and ``fast_wiping`` (mixins ahead of the reference's ``dynamics``,
``merging`` and ``wiping``), ``kernels`` (the compiled loops).

Work bounds per sub-step (``constants``): MAX_ARRIVALS_PER_SUBSTEP arrivals, MERGE_CELLS_MAX / MERGE_PAIRS_MAX
merge work, the drop budget of the inputs. ``tests/effects/windshield/test_fast_path.py`` compares this class
with the reference: the same seed gives the same drops (to rounding) over a few seconds of driving in heavy
rain with the wipers on, and the same statistics over longer runs.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from rain_core import checks, jit
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.arrivals import ArrivalTable
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BL_RUN_UP_M,
    CROSSWIND_GAIN,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    FLOW_AT_BOTTOM,
    FLOW_AT_TOP,
    FLOW_SPREAD,
    M_OBJECT_MIN,
    MAX_SUBSTEP_S,
    NU_AIR,
    VOLUME_PER_RADIUS3,
)
from rain_core.effects.windshield.drop_array import DropArray
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import ROW as _ROW
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.fast_arrivals import FastArrivals
from rain_core.effects.windshield.fast_merging import FastMerging
from rain_core.effects.windshield.fast_motion import FastMotion
from rain_core.effects.windshield.fast_wiping import FastWiping
from rain_core.effects.windshield.grid import GRID_CELL_M, PairFinder, _grid_shape
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.reference import WindshieldSimReference, _check_inputs
from rain_core.physics import G_M_S2, RHO_WATER
from rain_core.vehicles import CAR_SPEC, VehicleSpec

_GRID_O = (-1.0, -0.2)  # grid._GRID_ORIGIN, as floats for the sort key
SPLASH_R_PER_MM = 1e-3 * (math.pi / (6.0 * VOLUME_PER_RADIUS3)) ** (1.0 / 3.0)  # a whole raindrop's radius ∝ d
RHO_PI = RHO_WATER * math.pi  # (frame_impacts' film thickness: kg / (RHO_PI × r × r))
_G0, _G1 = _grid_shape(GRID_CELL_M)
_GRID_O2 = np.array(_GRID_O)
_NO_ROWS = np.zeros(0, np.int64)
_GRID_TOP2 = np.array([_G0 - 1, _G1 - 1])


class WindshieldSim(FastArrivals, FastMotion, FastMerging, FastWiping, DropArray, WindshieldSimReference):
    """Water on the windshield: drops, film, wiper beads and the wipers (the fast path; see the module
    docstring). Same constructor, state and queries as ``WindshieldSimReference``."""

    _shed_sensor: int | None = None  # the rain sensor's drops the last shed took (_shed_outside), or None

    def __init__(self, spec: VehicleSpec = CAR_SPEC, seed: int = 0):
        super().__init__(spec, seed)
        g = self.glass
        self._pairs = PairFinder()
        self._cell_mark = np.zeros(FILM_CELLS * FILM_CELLS, bool)  # scratch of _give_to_drops, all False
        self._merged_away: np.ndarray | None = None  # rows the last merge emptied, until _shed_outside
        self._sensor: float | None = 0.0
        self._inputs_seen: GlassInputs | None = None
        self._table: ArrivalTable | None = None
        self._air_key: bytes | None = None
        self._evap_of: np.ndarray | None = None  # the drying rates _evap_step was made from, and for which h
        self._evap_h = 0.0
        self._evap_step: np.ndarray | None = None
        self._w0, self._dw, self._height = g.width_bottom, g._dw, g.height
        self._sensor_box = (self.sensor_lo.tolist(), self.sensor_hi.tolist())
        self._sensor_area = float(np.prod(self.sensor_hi - self.sensor_lo))
        # Gravity along the curved glass (GlassGeometry.gravity), its constants folded.
        self._g_up = -G_M_S2 * float(g.up[1])
        self._g_sag = -G_M_S2 * g.sag * float(g.normal[1])
        # Per blade: bin radii of its bead (also as Python floats: fast_wiping._bead_off_glass), and its film
        # cells sorted by angle (a sweep is a range of them).
        self._bin_r = []
        self._cells_by_angle = []
        self._bins_of_cells = []
        for b, blade in enumerate(self.blades):
            self._bin_r.append(
                blade.r_inner_m + (np.arange(BEAD_BINS) + 0.5) / BEAD_BINS * (blade.r_outer_m - blade.r_inner_m)
            )
            r_c, phi_c = self._cell_polar[b]
            order = phi_c.argsort(kind="stable")
            reach = (r_c[order] >= blade.r_inner_m) & (r_c[order] <= blade.r_outer_m)  # the cells it can sweep
            self._cells_by_angle.append((order[reach], phi_c[order][reach]))
            self._bins_of_cells.append(self._bin_of(blade, r_c))
        self._bin_r_list = [r.tolist() for r in self._bin_r]
        self._kw_tables = None  # fast_wiping._sweep_tables
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
        state["_ks"] = None  # the kernels' work arrays: made again when needed
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._rows = self._buf.view(_ROW).ravel()

    def load_state(self, other: WindshieldSimReference) -> None:
        """Take over the whole state of another simulation of the same glass (its drops, film, beads, wipers,
        counters and random generator), e.g. a reference's, to run both on from the same glass."""
        self._n = 0
        self.changed()
        self._append(other.pos, other.vel, other.mass)
        self.trail[:] = other.trail
        self.fresh[:] = other.fresh
        self.film = other.film.copy()
        self.beads = other.beads.copy()
        self.rng = copy.deepcopy(other.rng)
        self.wipers = copy.deepcopy(other.wipers)
        for name in ("arrived", "wiped", "shed", "evaporated", "time_s", "arrival_count", "merges", "_budget"):
            setattr(self, name, getattr(other, name))

    def blade_angles(self) -> list[float]:
        """Each blade's angle now (rad), the reference's: kept while the wipers' phase and the blades are the same
        (the water pass and the glass pass both ask each frame)."""
        phase = self.wipers.phase
        memo = self.__dict__.get("_angles_memo")
        if memo is None or memo[0] != phase or memo[1] is not self.blades:
            memo = self._angles_memo = (phase, self.blades, super().blade_angles())
        return list(memo[2])

    @property
    def sensor_kg_m2(self) -> float:
        """The rain sensor's reading (kg/m²): as the wipers saw it in the last step in auto mode, else now."""
        return self._sensor if self._sensor is not None else self.sensor_reading()

    @sensor_kg_m2.setter
    def sensor_kg_m2(self, value: float) -> None:
        self._sensor = value

    def sensor_reading(self) -> float:
        """The reference's ``sensor_reading`` on the drop array's columns (the same drops, the same sums)."""
        lo, hi = self._sensor_box
        if jit.active():
            m = self._scratch().shed_m  # (free outside _shed_outside)
            return self._sensor_of(m[: kernels.sensor_masses(self._buf, self._n, lo[0], hi[0], lo[1], hi[1], m)])
        d = self._buf[: self._n]
        s, t = d[:, _S], d[:, _T]
        inside = (s >= lo[0]) & (s <= hi[0]) & (t >= lo[1]) & (t <= hi[1])
        drops = float(d[inside, _M].sum()) / self._sensor_area
        film = float(self.film.ravel()[self._sensor_cells].sum()) / max(self._sensor_cell_area, 1e-12)
        return drops + film

    def _sensor_of(self, m: np.ndarray) -> float:
        """The sensor's reading from the masses (kg) of the drops in its box, in row order (``sensor_reading``)."""
        drops = float(np.add.reduce(m)) / self._sensor_area
        film = float(self.film.ravel()[self._sensor_cells].sum()) / max(self._sensor_cell_area, 1e-12)
        return drops + film

    # --- glass helpers (GlassGeometry's formulas on columns, without building (n, 2) arrays) -----------------
    def _inside(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        return (t >= 0.0) & (t <= self._height) & (np.abs(s) <= 0.5 * (self._w0 + self._dw * t))

    def _cells(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Film cell (GlassGeometry.cell_index) of points (s, t) m on the glass."""
        u = np.minimum(s / (self._w0 + self._dw * t) * FILM_CELLS + 0.5 * FILM_CELLS, FILM_CELLS - 0.5)
        v = np.minimum(t * (FILM_CELLS / self._height), FILM_CELLS - 0.5)
        return (v.astype(np.int64) * FILM_CELLS) + u.astype(np.int64)

    def _placed(self, s: np.ndarray, t: np.ndarray, st: np.ndarray | None = None) -> np.ndarray:
        """The position's columns (drop_rows CELL … KEY) of drops at (s, t) m, (k, 7): the film cell, the air's
        factors, the boundary layer's run, gravity per unit mass and the merge-grid key, with the operations
        (so the bits) of the formulas they replace in ``_move`` and ``_sort_drops`` (``_cells``, airflow, the
        glass's gravity, grid.grid_keys), written in place to save NumPy calls. ``st``: (s, t) as (k, 2), if
        the caller has them so (s and t may be its columns)."""
        out = np.empty((len(s), 7))
        height, dw = self._height, self._dw
        w = dw * t
        w += self._w0  # the glass's width at t
        sw = s / w
        th = t / height
        # The film cell (_cells).
        u = sw * FILM_CELLS
        u += 0.5 * FILM_CELLS
        np.minimum(u, FILM_CELLS - 0.5, out=u)
        v = t * (FILM_CELLS / height)
        np.minimum(v, FILM_CELLS - 0.5, out=v)
        cell = v.astype(np.int64)
        cell *= FILM_CELLS
        cell += u.astype(np.int64)
        out[:, 0] = cell
        # The air's factors and the boundary layer's run (airflow).
        frac = np.maximum(th, 0.0)
        np.minimum(frac, 1.0, out=frac)
        col = out[:, 1]
        np.multiply(frac, FLOW_AT_TOP - FLOW_AT_BOTTOM, out=col)
        col += FLOW_AT_BOTTOM
        col = out[:, 2]
        np.multiply(s, 2.0, out=col)
        col /= w
        run = np.maximum(t, 0.0)
        run += BL_RUN_UP_M
        np.multiply(run, NU_AIR, out=out[:, 3])
        # Gravity along the curved glass (GlassGeometry.gravity), per unit mass.
        x = sw + 0.5
        x *= 2.0
        x -= 1.0
        y = th * 2.0
        y -= 1.0
        bv = y * y
        np.subtract(1.0, bv, out=bv)
        dbu = x * -4.0
        g = dbu / w
        g *= bv
        np.multiply(g, self._g_sag, out=out[:, 4])
        g = np.negative(s)
        g *= dw
        g /= w * w
        g *= dbu
        g *= bv
        x *= x
        np.subtract(1.0, x, out=x)
        y *= -4.0
        x *= y
        x /= height
        g += x
        g *= self._g_sag
        np.add(g, self._g_up, out=out[:, 5])
        # The merge-grid key (grid.grid_keys).
        if st is None:
            st = np.stack([s, t], axis=1)
        k = st - _GRID_O2  # both axes at once
        k /= GRID_CELL_M
        k = k.astype(np.int64)
        np.maximum(k, 0, out=k)
        np.minimum(k, _GRID_TOP2, out=k)
        key = k[:, 0] * _G1
        key += k[:, 1]
        out[:, 6] = key
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
            if jit.active():
                rate, closing, cdf, self._table = self._arrival_law(inputs)
            else:
                rate, closing, cdf = self.arrival_rate_per_s(inputs)
                self._table = ArrivalTable(closing, cdf) if rate > 0 else None
            self._rate_cache = (key, (rate, closing, cdf))
        air_local = inputs.relative_air_local()
        air_key = air_local.tobytes()
        if air_key != self._air_key:
            self._air_key = air_key
            self._air_local = air_local
            head, cross = float(air_local[2]), float(air_local[0])
            if jit.active():
                evap = self.__dict__.get("_evap")
                if evap is None:
                    evap = self._evap = np.empty(len(self._cell_up))
                kernels.film_drying(head, cross, self._cell_up, self._cell_q, self._areas_flat, evap)
                self._evap_of = None  # rewritten in place: _film_step's drying per sub-step is made again
                return
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
        self.changed()
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
            self._shed_outside(auto)
            if auto:  # (the shed's compaction took the sensor's drops on its way: _shed_sensor)
                k = self._shed_sensor
                self._sensor = self.sensor_reading() if k is None else self._sensor_of(self._ks.sensor_m[:k])
            else:
                self._sensor = None
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
            self._a_bound = None  # (the film step and the next sub-step grow drops: the next shed measures again)
            self._film_step(h, self._evap, inputs)
            self._sort_drops()
        self.time_s += dt_s

    def _film_step(self, h: float, evap_kg_s: np.ndarray, inputs: GlassInputs) -> None:
        """film.FilmBeading._film_step with fewer NumPy calls (the same operations and random numbers): the
        drying per sub-step is kept while the air and the sub-step stay, and the beads' two draws are one."""
        if self._evap_of is not evap_kg_s or self._evap_h != h:
            self._evap_of, self._evap_h = evap_kg_s, h
            self._evap_step = evap_kg_s * h
        flat = self.film.ravel()
        if jit.active():
            ks = self._scratch()
            k = kernels.evaporate_film(flat, self._evap_step, ks.film_loss, self._bead_mass, ks.thick)
            self.evaporated += float(np.add.reduce(ks.film_loss))
            thick = ks.thick[:k]
        else:
            loss = np.minimum(flat, self._evap_step)
            flat -= loss
            self.evaporated += float(np.add.reduce(loss))
            # Beading: a film thicker than the threshold pulls together into a drop somewhere in its cell.
            thick = (flat > self._bead_mass).nonzero()[0]
        if len(thick) == 0:
            return
        thick, m = self._beads(flat, thick, max(int(inputs.drop_budget) - self._n, 0))
        if len(thick) == 0:  # a full glass: every thick cell joined drops (no draws below: the same stream)
            return
        k = len(thick)
        r = self.rng.random(2 * k)  # the reference's rng.random(k) for u, then for v
        if jit.active():  # where in their cells, on the glass: one loop
            st = np.empty((2, k))
            kernels.bead_points(thick, r, self._w0, self._dw, self._height, st)
            self._append_at_rest(st[0], st[1], m)
            return
        iv, iu = np.divmod(thick, FILM_CELLS)
        u = (iu + r[:k]) / FILM_CELLS
        v = (iv + r[k:]) / FILM_CELLS
        self._bead_drops(u, v, m)

    # --- what the last step did (for drawing): kept as columns, assembled only when asked ------------------
    def frame_impacts(self) -> np.ndarray:
        """Impacts of the last step: (n, 4) s, t (m), splash radius (m), satellite film thickness (m)."""
        out = np.empty((sum(len(cols[0]) for cols in self._impacts), 4))
        row = 0
        for s, t, d_mm, splash, obj, a_obj, to_film in self._impacts:
            end = row + len(s)
            block = out[row:end]
            r = d_mm * SPLASH_R_PER_MM
            r[obj] = a_obj
            r *= 1.5 + 4.0 * splash
            block[:, 0] = s
            block[:, 1] = t
            block[:, 2] = r
            block[:, 3] = to_film / (RHO_PI * r * r)
            row = end
        return out

    def impact_columns(self) -> list[tuple]:
        """The last step's impacts as the arrivals keep them, a tuple a sub-step: (s, t (m), raindrop diameter (mm),
        splash fraction, the indices (ascending) of those that became drops, their radius (m), film (kg)), the
        columns ``frame_impacts`` assembles (the water pass reads them directly: render_kernels.impact_rows)."""
        return self._impacts

    def frame_trails(self) -> np.ndarray:
        """Paths of running drops in the last step: (n, 5) s0, t0, s1, t1 (m), drop radius (m)."""
        out = np.empty((sum(len(cols[0]) for cols in self._trails), 5))
        row = 0
        for cols in self._trails:
            end = row + len(cols[0])
            for c, col in enumerate(cols):
                out[row:end, c] = col
            row = end
        return out

    def _shed_outside(self, sensor: bool = False) -> None:
        """Drops that left the glass are shed; drops worn below half the object size become film. The drops
        the step's merge joined into others go too: one compaction for all three (the reference compacts after
        each; the sums run over the same drops in the same order). The kernel's compaction also takes, for the
        rest of the sub-step, the largest radius (``_a_bound``: the sweeps' wedges) and with ``sensor`` the rain
        sensor's drops (``_shed_sensor``: how many masses it wrote to the scratch's ``sensor_m``), else None."""
        n = self._n
        gone = self._merged_away
        self._merged_away = None
        self._shed_sensor = None
        if n == 0:
            return
        if jit.active():
            ks = self._scratch()
            lo, hi = self._sensor_box
            self._n, n_shed, n_sensor, self._a_bound = kernels.shed_rows(
                self._buf, self._fresh_buf, n, self._shed_all, _NO_ROWS if gone is None else gone,
                self.film.ravel(), self._w0, self._dw, self._height, ks.drop, ks.shed_m, sensor, lo[0], hi[0], lo[1],
                hi[1], ks.sensor_m)
            self._shed_all = False
            if sensor:
                self._shed_sensor = n_sensor
            if n_shed:
                self.shed += float(np.add.reduce(ks.shed_m[:n_shed]))
            return
        d = self._buf[:n]
        if self._shed_all:  # positions were set from outside (the ``pos`` setter): test them all
            self._shed_all = False
            outside = ~self._inside(d[:, _S], d[:, _T])
        else:
            # Only the drops placed in this sub-step's motion (moved, merged, trail droplets: their position
            # columns are still to be written) can be off the glass; the others rest where they were on it, and
            # arrivals and beads are placed on it.
            placed = (d[:, _KEY] == _DIRTY).nonzero()[0]
            outside = np.zeros(n, bool)
            if len(placed):
                outside[placed] = ~self._inside(d[placed, _S], d[placed, _T])
        if gone is not None:
            outside[gone] = False  # no longer drops
        if np.count_nonzero(outside):
            self.shed += float(np.add.reduce(d[outside, _M]))
        tiny = d[:, _M] < 0.5 * M_OBJECT_MIN
        tiny &= ~outside
        if gone is not None:
            tiny[gone] = False
        if np.count_nonzero(tiny):
            np.add.at(self.film.ravel(), self._cells(d[tiny, _S], d[tiny, _T]), d[tiny, _M])
        drop = outside | tiny
        if gone is not None:
            drop[gone] = True
        if np.count_nonzero(drop):
            self._keep(~drop)
