"""``WindshieldSimReference``: the water on the windshield — drops, film, wiper beads and the wipers — as the plain
float64 NumPy reference (the truth the fast ``WindshieldSim`` in ``sim`` is tested and benchmarked against).

Where the water lives (the bookkeeping)
---------------------------------------
All water mass is on the CPU, in float64, in three places:

* **drops** — objects with position (s, t) m on the glass, velocity m/s and mass kg;
* **the film** — a coarse FILM_CELLS × FILM_CELLS grid over the glass's UV square holding kg per cell: mist
  (arrivals too small to be objects), impact satellites, wet trails, wiper residue and wiper leakage;
* **the wiper beads** — kg per radial bin along each blade, the water a blade pushes in front of it.

Four counters (kg) close the balance exactly: ``arrived − wiped − shed − evaporated = on the glass``
(``mass_on_glass()``; ``balance_error_kg()`` is the difference, float64 rounding only). *Wiped*: water a blade
pushes off the glass (past an edge, or shed at the end of a stroke); *shed*: drops that run or are blown off
an edge of the glass; *evaporated*: from the film and, very slowly, from drops.

Arrivals come at ``physics.flux_on_surface_per_s`` for the glass's normal and velocity through the rain and
wind, with diameters drawn from the *flux-weighted* Marshall–Palmer law (the distribution in the air times
each size's closing speed on the glass), none under a roof. A fast impact splashes: a fraction of the drop
(rising with the normal impact speed) spreads as satellite mist into the film around it.

The parts of a sub-step live beside this module: drop motion, trails and shedding (``dynamics``), merging
(``merging``), film evaporation and beading (``film``), the blades pushing water (``wiping``).

Work per sub-step: at most MAX_ARRIVALS_PER_SUBSTEP arrivals are drawn one by one; the rest of a storm's drops
(only at rates and speeds far beyond real rain) land as mist, their expected mass spread over the film by area.
The reference merge tests every candidate pair of its spatial hash, without a cap: it is the truth for tests at
ordinary settings. The fast path (``sim.WindshieldSim``) caps its merge work as well.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import checks, physics
from rain_core.effects.windshield.airflow import air_velocity
from rain_core.effects.windshield.constants import (
    BEAD_BINS,
    BEAD_THRESHOLD_M,
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    M_OBJECT_MIN,
    MAX_ARRIVALS_PER_SUBSTEP,
    MAX_SUBSTEP_S,
    SPLASH_MAX,
    SPLASH_SPEED_M_S,
    drop_radius,
    norm2,
    uniform_index,
)
from rain_core.effects.windshield.dynamics import DropDynamics
from rain_core.effects.windshield.film import FilmBeading
from rain_core.effects.windshield.glass import GlassGeometry
from rain_core.effects.windshield.grid import grid_keys
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.merging import Merging
from rain_core.effects.windshield.wipers import (
    SENSOR_CENTRE_FRACTION,
    SENSOR_SIZE_M,
    WiperController,
    tandem_blades,
)
from rain_core.effects.windshield.wiping import Wiping
from rain_core.physics import RHO_WATER
from rain_core.vehicles import CAR_SPEC, VehicleSpec

_D_GRID_MM = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 512)  # arrival diameters (mm)
_V_GRID_M_S = np.asarray(physics.terminal_velocity(_D_GRID_MM), dtype=np.float64)


def _check_inputs(inputs) -> None:
    if not isinstance(inputs, GlassInputs):  # GlassInputs checks its own fields when it is made
        raise ValueError(f"inputs must be a GlassInputs, got {type(inputs).__name__}")


class WindshieldSimReference(DropDynamics, Merging, FilmBeading, Wiping):
    """Water on the windshield: drops, film, wiper beads and the wipers themselves (CPU, float64, NumPy; the
    reference).

    ``step(dt_s, inputs)`` advances by dt_s seconds (sub-stepped at MAX_SUBSTEP_S; clamped to
    ``checks.MAX_FRAME_DT_S``). State: ``pos`` (n, 2) (s, t) m, ``vel`` (n, 2) m/s, ``mass`` (n,) kg; ``film``
    (FILM_CELLS, FILM_CELLS) kg per cell ([iv, iu]); ``beads`` (2, BEAD_BINS) kg; counters ``arrived``,
    ``wiped``, ``shed``, ``evaporated`` (kg). Same seed and inputs → the same state (``np.random.Generator``
    seeded once).
    """

    def __init__(self, spec: VehicleSpec = CAR_SPEC, seed: int = 0):
        self.glass = GlassGeometry(spec)
        self.rng = np.random.default_rng(seed)
        self.blades = tandem_blades(self.glass.width_bottom, self.glass.width_top, self.glass.height)
        self.wipers = WiperController()
        self._init_drops()
        self.cell_centres, self.cell_areas = self.glass.cells(FILM_CELLS)
        self.film = np.zeros((FILM_CELLS, FILM_CELLS))
        self.beads = np.zeros((len(self.blades), BEAD_BINS))
        self.arrived = self.wiped = self.shed = self.evaporated = 0.0
        self.time_s = 0.0
        self.arrival_count = 0
        self._areas_flat = self.cell_areas.ravel()
        flat_centres = self.cell_centres.reshape(-1, 2)
        self._cell_polar = []
        for blade in self.blades:
            rel = flat_centres - np.asarray(blade.pivot)
            self._cell_polar.append((np.hypot(rel[:, 0], rel[:, 1]), np.arctan2(rel[:, 1], rel[:, 0])))
        sc = np.array(SENSOR_CENTRE_FRACTION) * (self.glass.width_bottom, self.glass.height)
        self.sensor_lo = sc - 0.5 * np.array(SENSOR_SIZE_M)
        self.sensor_hi = sc + 0.5 * np.array(SENSOR_SIZE_M)
        inside = np.all((flat_centres >= self.sensor_lo) & (flat_centres <= self.sensor_hi), axis=1)
        self._sensor_cells = np.flatnonzero(inside)
        self._sensor_cell_area = float(self._areas_flat[self._sensor_cells].sum())
        self.sensor_kg_m2 = 0.0
        self._bead_mass = RHO_WATER * BEAD_THRESHOLD_M * self._areas_flat
        self._rate_cache: tuple | None = None
        self._n0_cache: tuple = (None, 0.0, None)
        self.merges = 0
        self._budget = 6000
        self._reset_frame_records()

    def _init_drops(self) -> None:
        self.pos = np.zeros((0, 2))
        self.vel = np.zeros((0, 2))
        self.mass = np.zeros(0)
        self.trail = np.zeros(0)  # distance run since the last trail droplet (m)
        self.fresh = np.zeros(0, bool)  # born, grown or merged since the last merge test

    # --- queries --------------------------------------------------------------------------------------------
    @property
    def count(self) -> int:
        return len(self.mass)

    def radius(self) -> np.ndarray:
        return drop_radius(self.mass)

    def mass_on_glass(self) -> float:
        """Water on the glass (kg): drops + film + the wiper beads."""
        return float(self.mass.sum() + self.film.sum() + self.beads.sum())

    def balance_error_kg(self) -> float:
        """arrived − wiped − shed − evaporated − on the glass (kg); 0 up to float64 rounding."""
        return self.arrived - self.wiped - self.shed - self.evaporated - self.mass_on_glass()

    def film_thickness_m(self, out: np.ndarray | None = None) -> np.ndarray:
        """Mean film thickness per cell (m), (FILM_CELLS, FILM_CELLS) indexed [iv, iu]; ``out``: a float64 array of
        that shape to write it to (the effect asks every frame)."""
        return np.divide(self.film, RHO_WATER * self.cell_areas, out=out)

    def has_water(self) -> bool:
        return self.count > 0 or bool(self.film.any()) or bool(self.beads.any())

    def sensor_reading(self) -> float:
        """Water on the rain-sensor patch, kg/m² (drops whose centres lie in it, plus its film cells)."""
        area = float(np.prod(self.sensor_hi - self.sensor_lo))
        inside = np.all((self.pos >= self.sensor_lo) & (self.pos <= self.sensor_hi), axis=1)
        drops = float(self.mass[inside].sum()) / area
        film = float(self.film.ravel()[self._sensor_cells].sum()) / max(self._sensor_cell_area, 1e-12)
        return drops + film

    def blade_angles(self) -> list[float]:
        """Each blade's angle now (rad)."""
        return [float(b.angle(self.wipers.progress)) for b in self.blades]

    # --- arrivals -------------------------------------------------------------------------------------------
    def arrival_rate_per_s(self, inputs: GlassInputs) -> tuple[float, np.ndarray, np.ndarray]:
        """Arrivals on the glass: (drops per second, closing speed (m/s) and the flux-weighted size CDF for
        each diameter of _D_GRID_MM). The count is ``physics.flux_on_surface_per_s`` for the glass's world
        normal and velocity, by the trapezoid rule on the diameter grid (within 1e-4), × ``drop_scale``."""
        zeros = np.zeros_like(_D_GRID_MM)
        if inputs.rate_mm_h <= 0.0 or inputs.sheltered or inputs.drop_scale <= 0.0:
            return 0.0, zeros, zeros
        rot = np.asarray(inputs.car_rotation, float)
        n_world = rot @ self.glass.normal
        vs = np.asarray(inputs.car_velocity_m_s, float)
        wind = np.asarray(inputs.wind_m_s, float).copy()
        wind[1] = 0.0
        a = float((wind - vs) @ n_world)
        closing = np.maximum(_V_GRID_M_S * n_world[1] - a, 0.0)  # −u·n̂ per diameter, as in physics
        if self._n0_cache[0] != inputs.rate_mm_h:
            shape = np.exp(-physics.mp_slope_per_mm(inputs.rate_mm_h) * _D_GRID_MM)
            self._n0_cache = (inputs.rate_mm_h, float(physics.effective_n0(inputs.rate_mm_h)), shape)
        _, n0, shape = self._n0_cache
        pdf = shape * closing
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(_D_GRID_MM))])
        flux = self.glass.area_m2 * n0 * float(cdf[-1])
        return flux * inputs.drop_scale, closing, cdf

    def _sample_arrivals(self, n: int, closing: np.ndarray, cdf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """n diameters (mm) from the flux-weighted law N(D)·closing(D), and their impact speeds (m/s)."""
        d = np.interp(self.rng.random(n) * cdf[-1], cdf, _D_GRID_MM)
        return d, np.interp(d, _D_GRID_MM, closing)

    def _arrive(self, h: float, arrivals: tuple, inputs: GlassInputs) -> None:
        rate_per_s, closing, cdf = arrivals
        n_all = int(self.rng.poisson(rate_per_s * h)) if rate_per_s > 0 else 0
        if n_all == 0:
            return
        n = min(n_all, MAX_ARRIVALS_PER_SUBSTEP)
        d_mm, u_n = self._sample_arrivals(n, closing, cdf)
        m = RHO_WATER * math.pi / 6.0 * (d_mm * 1e-3) ** 3
        st = self.glass.sample_uniform(n, self.rng)
        self.arrived += float(m.sum())
        self.arrival_count += n
        lo, hi = SPLASH_SPEED_M_S
        splash = np.clip((u_n - lo) / (hi - lo), 0.0, 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        is_obj = keep >= M_OBJECT_MIN
        cells = self.glass.cell_index(st)
        room = max(int(inputs.drop_budget) - self.count, 0)
        joined = np.zeros(n, bool)
        if int(is_obj.sum()) > room:
            # A full glass: the surplus lands on (joins) a drop already in its cell, or else the film.
            over = np.flatnonzero(is_obj)[room:]
            is_obj[over] = False
            joined[over] = self._give_to_drops(cells[over], keep[over])
        to_film = m - np.where(is_obj | joined, keep, 0.0)
        np.add.at(self.film.ravel(), cells, to_film)
        splash_r = drop_radius(np.where(is_obj, keep, m)) * (1.5 + 4.0 * splash)
        self._impacts.append(np.column_stack([st, splash_r, to_film / (RHO_WATER * math.pi * splash_r**2)]))
        self._append(st[is_obj], np.zeros((int(is_obj.sum()), 2)), keep[is_obj])
        if n_all > n:
            self._arrive_as_mist(n_all - n, float(m.mean()))

    def _arrive_as_mist(self, count: int, mean_mass_kg: float) -> None:
        """``count`` arrivals beyond the per-sub-step cap: their expected mass (kg), spread over the film by area."""
        total = count * mean_mass_kg
        self.film += total * (self.cell_areas / self.cell_areas.sum())
        self.arrived += total
        self.arrival_count += count

    # --- the drop arrays ------------------------------------------------------------------------------------
    def _give_to_drops(self, cells: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """Add each mass (kg) to a random drop of its film cell; returns which ones found a drop."""
        placed = np.zeros(len(cells), bool)
        if self.count == 0 or len(cells) == 0:
            return placed
        drop_cells = self.glass.cell_index(self.pos)
        counts = np.bincount(drop_cells, minlength=FILM_CELLS * FILM_CELLS)
        starts = np.cumsum(counts) - counts
        order = np.argsort(drop_cells, kind="stable")
        c = counts[cells]
        placed = c > 0
        if placed.any():
            pick = order[starts[cells[placed]] + uniform_index(self.rng.random(int(placed.sum())), c[placed])]
            np.add.at(self.mass, pick, mass[placed])
            self.fresh[pick] = True
        return placed

    def _append(self, pos: np.ndarray, vel: np.ndarray, mass: np.ndarray) -> None:
        if len(mass) == 0:
            return
        self.pos = np.concatenate([self.pos, pos])
        self.vel = np.concatenate([self.vel, vel])
        self.mass = np.concatenate([self.mass, mass])
        self.trail = np.concatenate([self.trail, np.zeros(len(mass))])
        self.fresh = np.concatenate([self.fresh, np.ones(len(mass), bool)])

    def _sort_drops(self) -> None:
        """Keep the drop arrays in merge-grid cell order, so the next grid sort finds them nearly sorted."""
        if self.count < 2:
            return
        keys = grid_keys(self.pos)
        if np.all(keys[1:] >= keys[:-1]):
            return
        order = np.argsort(keys, kind="stable")
        self.pos, self.vel, self.mass = self.pos[order], self.vel[order], self.mass[order]
        self.trail, self.fresh = self.trail[order], self.fresh[order]

    def _keep(self, keep: np.ndarray) -> None:
        self.pos, self.vel, self.mass, self.trail = self.pos[keep], self.vel[keep], self.mass[keep], self.trail[keep]
        self.fresh = self.fresh[keep]

    # --- what the last step did (for drawing) ---------------------------------------------------------------
    def _reset_frame_records(self) -> None:
        self._impacts: list[np.ndarray] = []
        self._trails: list[np.ndarray] = []
        self._sweep_ranges = [[math.inf, -math.inf] for _ in self.blades]

    def frame_impacts(self) -> np.ndarray:
        """Impacts of the last step: (n, 4) s, t (m), splash radius (m), satellite film thickness (m)."""
        return np.concatenate(self._impacts) if self._impacts else np.zeros((0, 4))

    def frame_trails(self) -> np.ndarray:
        """Paths of running drops in the last step: (n, 5) s0, t0, s1, t1 (m), drop radius (m)."""
        return np.concatenate(self._trails) if self._trails else np.zeros((0, 5))

    def frame_sweeps(self) -> list[tuple[float, float] | None]:
        """Per blade, the range of angles (rad) its rubber swept in the last step, or None."""
        return [(lo, hi) if lo <= hi else None for lo, hi in self._sweep_ranges]

    # --- the step -------------------------------------------------------------------------------------------
    def step(self, dt_s: float, inputs: GlassInputs) -> None:
        """Advance the water and the wipers by dt_s seconds (finite, ≥ 0; clamped to checks.MAX_FRAME_DT_S)."""
        dt_s = checks.time_step(dt_s)
        _check_inputs(inputs)
        self._reset_frame_records()
        if dt_s == 0.0:
            return
        self._budget = int(inputs.drop_budget)
        key = (
            inputs.rate_mm_h,
            inputs.sheltered,
            inputs.drop_scale,
            np.asarray(inputs.car_rotation).tobytes(),
            np.asarray(inputs.car_velocity_m_s).tobytes(),
            np.asarray(inputs.wind_m_s).tobytes(),
        )
        if self._rate_cache is None or self._rate_cache[0] != key:
            self._rate_cache = (key, self.arrival_rate_per_s(inputs))
        arrivals = self._rate_cache[1]
        air_local = inputs.relative_air_local()
        air = norm2(air_velocity(self.glass, self.cell_centres.reshape(-1, 2), air_local))
        evap = FILM_EVAP_KG_M2_S * (1.0 + air / EVAP_AIR_M_S) * self._areas_flat
        n_sub = max(1, math.ceil(dt_s / MAX_SUBSTEP_S - 1e-9))
        h = dt_s / n_sub
        for _ in range(n_sub):
            self._arrive(h, arrivals, inputs)
            start, disp = self._move(h, air_local, inputs)
            self._merge(start, disp)
            self._shed_outside()
            self.sensor_kg_m2 = self.sensor_reading()
            segments = self.wipers.advance(
                h,
                inputs.wiper_mode,
                inputs.wiper_interval_s,
                inputs.wiper_low_cpm,
                inputs.wiper_high_cpm,
                self.sensor_kg_m2,
                inputs.wiper_sensitivity,
            )
            for seg in segments:
                self._sweep(seg, inputs.blade_wear)
            self._film_step(h, evap, inputs)
            self._sort_drops()
        self.time_s += dt_s
