"""The ripple field around the car (DESIGN §3): the wave solver's window anchored to the world, kept on the
standing water of the road's film-depth function, disturbed by wheel wakes, raindrops and spray droplets.

NumPy only: the field runs, steps and sleeps without OpenGL. The GPU solver is built on the GL side
(``backend.make_field``) and handed in; the field's textures (height and slopes) live in ``textures.py``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from rain_core import checks, physics
from rain_core.effects.ripples.constants import (
    BACKENDS,
    CAPILLARY_SPEED_M_S,
    CRATER_RADIUS_PER_D,
    DEFAULT_DAMPING_PER_S,
    RAIN_DENT_M_PER_KG_M_S,
    WAKE_REF_SPEED_M_S,
)
from rain_core.effects.ripples.solver import WaveSolver, shifted
from rain_core.effects.ripples.solver_f32 import WaveSolverF32

# The solvers that need no OpenGL context, by backend name.
CPU_SOLVERS = {"reference": WaveSolver, "numpy32": WaveSolverF32}


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


def field_grid(n: int, extent_m: float) -> tuple[int, float, float]:
    """(n, extent in m, cell size in m) of a field of n cells per side (≥ 8) spanning extent_m; ValueError if
    either is bad."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 8:
        raise ValueError(f"n must be an int >= 8 (cells per side), got {n!r}")
    extent = checks.number("extent_m", extent_m, 1e-3, 1e5, "m")
    return int(n), extent, extent / (int(n) - 1)


class RippleField:
    """The ripple heightfield around the ego car, anchored to the world: cell (ix, iz) of the window lies at
    world (origin_x + ix·h, origin_z + iz·h) with the origin on a fixed world lattice, so when the car moves
    the window scrolls by whole cells, cells that enter are at rest and a wake stays where it was made.

    ``RippleField(n=512, extent_m=25.0, speed_m_s, damping_per_s, backend="numpy32", solver=None)``: backend
    "numpy32" or "reference" builds that NumPy solver ("auto", with no context to time a GPU against, is
    numpy32); a solver built elsewhere (the GPU one: ``backend.make_field``) is passed as ``solver``, with
    ``backend`` naming it and ``backend_timings`` what ``choose_backend`` measured. seed: the raindrop rng.
    ``version`` counts the changes of the height and of the window (for whoever mirrors them in textures).
    """

    def __init__(self, n: int = 512, extent_m: float = 25.0, speed_m_s: float = CAPILLARY_SPEED_M_S,
                 damping_per_s: float = DEFAULT_DAMPING_PER_S, backend: str = "numpy32", *,
                 solver: WaveSolver | None = None, backend_timings: dict[str, float] | None = None, seed: int = 0,
                 recenter_margin_cells: int = 4, max_drops_per_frame: int = 4096, rain_gain: float = 1.0,
                 wake_gain: float = 1.0, mask_refresh_s: float = 1.0, reuse_tolerance: float = 0.25):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
        self.n, self.extent_m, self.cell_m = field_grid(n, extent_m)
        self.recenter_margin_cells = max(1, int(recenter_margin_cells))
        self.max_drops_per_frame = max(1, int(max_drops_per_frame))
        self.rain_gain = checks.number("rain_gain", rain_gain, 0.0, 1e6)
        self.wake_gain = checks.number("wake_gain", wake_gain, 0.0, 1e6)
        self.mask_refresh_s = checks.number("mask_refresh_s", mask_refresh_s, 0.0, 1e6, "s")
        self.reuse_tolerance = checks.number("reuse_tolerance", reuse_tolerance, 0.0, 0.5)
        self.rng = np.random.default_rng(seed)
        self.backend_timings: dict[str, float] = dict(backend_timings or {})
        if solver is None:
            backend = "numpy32" if backend == "auto" else backend
            if backend not in CPU_SOLVERS:
                raise ValueError(f"backend {backend!r} needs an OpenGL context: build the field with "
                                 "rain_core.effects.ripples.make_field(ctx, ...)")
            solver = CPU_SOLVERS[backend](self.n, self.cell_m, speed_m_s, damping_per_s)
        elif solver.n != self.n or solver.cell_m != self.cell_m:
            raise ValueError(f"the solver's grid ({solver.n} cells of {solver.cell_m:g} m) is not the field's "
                             f"({self.n} cells of {self.cell_m:g} m)")
        self.backend = backend
        self.solver = solver
        half = (self.n - 1) // 2
        self._anchor = (-half, -half)  # world lattice index of cell (0, 0); the window starts centred on 0
        self._centred = False
        self._water_cells: np.ndarray | None = None  # flat indices of water cells (None: all interior)
        self._film_fn: FilmDepthFn | None = None
        self._depth_mm: np.ndarray | None = None  # film depth of each cell from _film_fn (NaN: not yet asked)
        self._refresh_row = 0.0  # where the rolling re-evaluation of the film depth has got to (rows)
        self.version = 0

    # -- geometry --

    @property
    def origin_xz(self) -> tuple[float, float]:
        """World (x, z) in m of cell (0, 0) of the window."""
        return self._anchor[0] * self.cell_m, self._anchor[1] * self.cell_m

    def world_to_cell(self, x_m, z_m):
        """Fractional window cell indices (ix, iz) of world positions in m (vectorised)."""
        ox, oz = self.origin_xz
        return (np.asarray(x_m, dtype=np.float64) - ox) / self.cell_m, \
            (np.asarray(z_m, dtype=np.float64) - oz) / self.cell_m

    def cell_centres_xz(self) -> tuple[np.ndarray, np.ndarray]:
        """World x and z in m of every cell, two (n, n) arrays indexed [iz, ix]."""
        ox, oz = self.origin_xz
        coords = np.arange(self.n) * self.cell_m
        return np.meshgrid(ox + coords, oz + coords)

    def recenter(self, x_m: float, z_m: float) -> tuple[int, int]:
        """Keep the window centred on world (x_m, z_m) in m: scroll by whole cells once the centre is
        ``recenter_margin_cells`` off (the first call jumps there). Returns the shift (dx, dz) in cells."""
        return self._recenter(x_m, z_m, fill=True)

    def _recenter(self, x_m: float, z_m: float, fill: bool) -> tuple[int, int]:
        x = checks.number("x_m", x_m, unit="m")
        z = checks.number("z_m", z_m, unit="m")
        half = (self.n - 1) / 2.0
        target = (round(x / self.cell_m - half), round(z / self.cell_m - half))
        dx, dz = target[0] - self._anchor[0], target[1] - self._anchor[1]
        if not self._centred:
            self._centred = True
        elif max(abs(dx), abs(dz)) < self.recenter_margin_cells:
            return 0, 0
        if dx or dz:
            self.solver.shift(dx, dz)
            self._anchor = target
            if self._depth_mm is not None:  # keep what is known, ask only about the cells that entered
                self._depth_mm = shifted(self._depth_mm, dx, dz, np.nan)
                if fill:
                    self._fill_unknown_depths()
            self._update_water_cells()
            self.version += 1
        return dx, dz

    # -- water --

    def set_water_mask(self, mask):
        """(n, n) bool, or film depth in mm (> 0: water), indexed [iz, ix] over the window; None: all water.
        Replaces any film-depth function given to ``update``."""
        self._film_fn = None
        self._depth_mm = None
        self._set_mask(mask)

    def _set_mask(self, mask):
        self.solver.set_water_mask(mask)
        self._update_water_cells()
        self.version += 1

    def refresh_water_mask(self, film_depth_fn: FilmDepthFn):
        """Evaluate film_depth_fn(x_m, z_m) -> depth in mm (vectorised over arrays of world positions in m) at
        every cell now, hold the cells without water at rest, and keep following the function: after a
        scroll only the cells that enter are asked, and ``update`` re-asks a band of rows each frame so the
        whole window is renewed every ``mask_refresh_s`` (puddles fill and dry over seconds; one full
        evaluation of the road's film depth at 512² costs tens of ms)."""
        self._film_fn = film_depth_fn
        self._depth_mm = np.full((self.n, self.n), np.nan)
        self._fill_unknown_depths()

    def _ask_depths(self, rows, cols) -> np.ndarray:
        ox, oz = self.origin_xz
        xs, zs = np.meshgrid(ox + np.asarray(cols) * self.cell_m, oz + np.asarray(rows) * self.cell_m)
        depth = np.asarray(self._film_fn(xs, zs), dtype=np.float64)
        depth = np.broadcast_to(depth, xs.shape)
        if not np.all(np.isfinite(depth)) or np.any(depth < 0.0):
            raise ValueError("film_depth_fn must return finite depths >= 0 mm")
        return depth

    def _fill_unknown_depths(self, extra_rows=None):
        """Ask the film-depth function about the rows and columns not known yet (after a scroll, whole strips)
        and about extra_rows, in at most two calls, and update the mask."""
        unknown = np.isnan(self._depth_mm)
        rows = np.flatnonzero(unknown.all(axis=1))
        if extra_rows is not None:
            rows = np.union1d(rows, extra_rows)
        if rows.size == 0 and not unknown.any():
            return
        if rows.size:
            self._depth_mm[rows, :] = self._ask_depths(rows, np.arange(self.n))
            unknown[rows, :] = False
        cols = np.flatnonzero(unknown.any(axis=0))
        if cols.size:
            self._depth_mm[:, cols] = self._ask_depths(np.arange(self.n), cols)
        self._apply_depth_mask()

    def _apply_depth_mask(self):
        water = self._depth_mm > 0.0
        current = self.solver.water_mask
        if current is None or not np.array_equal(water, current > 0.5):
            self._set_mask(water)

    def _refresh_depth_band(self, dt: float):
        """Re-ask the film depth of the next band of rows (the whole window every mask_refresh_s), together
        with any cells that scrolled in."""
        if self.mask_refresh_s == 0.0:
            rows = np.arange(self.n)
        else:
            start = int(self._refresh_row)
            self._refresh_row += self.n * dt / self.mask_refresh_s
            stop = min(int(self._refresh_row), start + self.n)
            rows = np.arange(start, max(stop, start)) % self.n
            self._refresh_row %= self.n
        self._fill_unknown_depths(rows)

    def _update_water_cells(self):
        mask = self.solver.water_mask
        if mask is None:
            self._water_cells = None
            return
        water = np.asarray(mask) > 0.5
        water[0, :] = water[-1, :] = water[:, 0] = water[:, -1] = False  # the fixed edges take no drops
        self._water_cells = np.flatnonzero(water.ravel())

    # -- sources --

    def add_wheel_sweep(self, p0_xz, p1_xz, speed_m_s: float, film_depth_mm: float, tire_width_m: float) -> int:
        """Disturb the water along a wheel's path from p0_xz to p1_xz (world m) this frame: a trough as wide as
        the tyre and film_depth × speed / WAKE_REF_SPEED_M_S deep (× wake_gain), laid as bumps at most one cell
        apart so a fast wheel leaves a continuous wake. speed in m/s (≥ 0), film depth in mm (≥ 0), tyre
        width in m (> 0). Returns the number of bumps laid (the part of the path inside the window)."""
        x0, z0 = (checks.number("p0_xz", v, unit="m") for v in p0_xz)
        x1, z1 = (checks.number("p1_xz", v, unit="m") for v in p1_xz)
        speed = checks.number("speed_m_s", speed_m_s, 0.0, 1e3, "m/s")
        depth_m = checks.number("film_depth_mm", film_depth_mm, 0.0, 1e3, "mm") * 1e-3
        radius = 0.5 * checks.number("tire_width_m", tire_width_m, 1e-3, 10.0, "m")
        trough = self.wake_gain * depth_m * speed / WAKE_REF_SPEED_M_S
        if trough == 0.0:
            return 0
        ox, oz = self.origin_xz
        seg = self._clip_segment(x0 - ox, z0 - oz, x1 - ox, z1 - oz, radius + 2.0 * self.cell_m)
        if seg is None:
            return 0
        ax, az, bx, bz = seg
        length = math.hypot(bx - ax, bz - az)
        count = max(1, math.ceil(length / self.cell_m))
        t = (np.arange(count) + 0.5) / count
        # A row of raised cosines of radius R spaced ds sums to R/ds times one peak along its axis: scale each
        # peak by ds/R so the trough depth does not depend on the frame rate or the grid.
        spacing = length / count if length > 0.0 else radius
        peak = -trough * min(spacing / radius, 1.0)
        self.solver.add_impulses(ax + t * (bx - ax), az + t * (bz - az), radius, np.full(count, peak))
        return count

    def _clip_segment(self, ax, az, bx, bz, pad):
        """Liang–Barsky clip of a segment (window metres) to the window grown by pad; None if outside."""
        lo, hi = -pad, self.solver.length_m + pad
        t0, t1 = 0.0, 1.0
        for p, q in ((-(bx - ax), ax - lo), (bx - ax, hi - ax), (-(bz - az), az - lo), (bz - az, hi - az)):
            if p == 0.0:
                if q < 0.0:
                    return None
                continue
            r = q / p
            if p < 0.0:
                t0 = max(t0, r)
            else:
                t1 = min(t1, r)
            if t0 > t1:
                return None
        return ax + t0 * (bx - ax), az + t0 * (bz - az), ax + t1 * (bx - ax), az + t1 * (bz - az)

    def add_raindrops(self, rate_mm_h: float, dt_s: float) -> int:
        """Drops that hit the water cells of the window in dt_s seconds at a rain rate in mm/h: a Poisson count
        from the drop flux (rain_core.physics), diameters from Marshall–Palmer weighted by fall speed (the
        faster drops of a size class arrive more often), each pressing a dent ∝ its momentum m·v
        (RAIN_DENT_M_PER_KG_M_S × rain_gain). More than ``max_drops_per_frame`` drops are represented by that
        many drops each carrying a proportional share (the momentum flux is kept). Returns the drops laid."""
        rate = checks.number("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        dt = checks.number("dt_s", dt_s, 0.0, math.inf, "s")
        if rate == 0.0 or dt == 0.0 or self.rain_gain == 0.0:
            return 0
        interior = (self.n - 2) ** 2
        cells = interior if self._water_cells is None else self._water_cells.size
        if cells == 0:
            return 0
        expected = physics.flux_horizontal_per_m2_s(rate) * cells * self.cell_m ** 2 * dt
        count = int(self.rng.poisson(min(expected, 1e15)))
        if count == 0:
            return 0
        drawn = min(count, self.max_drops_per_frame)
        weight = count / drawn
        diam = self._flux_weighted_diameters(rate, drawn)
        speed = np.asarray(physics.terminal_velocity(diam), dtype=np.float64)
        momentum = physics.RHO_WATER * math.pi / 6.0 * (diam * 1e-3) ** 3 * speed  # kg·m/s
        if self._water_cells is None:
            flat_cells = self.rng.integers(0, interior, drawn)
            iz, ix = np.divmod(flat_cells, self.n - 2)
            iz, ix = iz + 1, ix + 1
        else:
            iz, ix = np.divmod(self._water_cells[self.rng.integers(0, cells, drawn)], self.n)
        jitter = self.rng.random((2, drawn)) - 0.5  # anywhere within the cell
        self.solver.add_impulses((ix + jitter[0]) * self.cell_m, (iz + jitter[1]) * self.cell_m,
                                 CRATER_RADIUS_PER_D * diam * 1e-3,
                                 -self.rain_gain * RAIN_DENT_M_PER_KG_M_S * weight * momentum)
        return drawn

    def add_droplet_impacts(self, impacts, radius_m: float = 0.02) -> int:
        """Droplets landing in the water (e.g. wheel spray): (x m, z m world, downward momentum kg·m/s) each,
        pressing a dent by the raindrops' law (RAIN_DENT_M_PER_KG_M_S × wake_gain); None: none. Returns the dents
        laid."""
        if impacts is None:
            return 0
        impacts = np.asarray(list(impacts), dtype=np.float64).reshape(-1, 3)
        if len(impacts) == 0 or self.wake_gain == 0.0:
            return 0
        impacts = impacts[np.all(np.isfinite(impacts), axis=1)]
        ox, oz = self.origin_xz
        self.solver.add_impulses(impacts[:, 0] - ox, impacts[:, 1] - oz, radius_m,
                                 -self.wake_gain * RAIN_DENT_M_PER_KG_M_S * np.abs(impacts[:, 2]))
        return len(impacts)

    def _flux_weighted_diameters(self, rate: float, count: int) -> np.ndarray:
        """Diameters (mm) of drops arriving on a surface: the law of ``physics.sample_drop_diameters`` (the
        airborne N(D), ``physics.drop_diameter_cdf``) weighted by the fall speed v(D), since faster drops of a
        size class arrive more often; inverse-CDF sampling on a 512-point table built for this rate."""
        grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 513)
        mass = np.diff(np.asarray(physics.drop_diameter_cdf(grid, rate), dtype=np.float64))
        mid = 0.5 * (grid[1:] + grid[:-1])
        weights = mass * np.asarray(physics.terminal_velocity(mid), dtype=np.float64)
        cdf = np.concatenate([[0.0], np.cumsum(weights)])
        cdf /= cdf[-1]
        return np.interp(self.rng.random(count), cdf, grid)

    # -- time --

    def step(self, dt_s: float) -> int:
        """Advance the water by dt_s seconds (sub-steps inside; frame jitter below ``reuse_tolerance`` does not
        retime it). Returns the sub-steps taken (0 while asleep)."""
        k = self.solver.step(dt_s, reuse_tolerance=self.reuse_tolerance)
        if k:
            self.version += 1
        return k

    def update(self, dt_s: float, center_xz=None, rate_mm_h: float = 0.0, wheels: Iterable = (),
               film_depth_fn: FilmDepthFn | None = None) -> dict:
        """One frame: recenter on center_xz (world m; None keeps the window), follow the water mask of
        film_depth_fn(x_m, z_m) -> mm (see ``refresh_water_mask``: evaluated in full the first time, then in
        strips and bands, so it may be a new function object every frame), lay raindrops for
        rate_mm_h (mm/h) and the wheel sweeps (``WheelSweep`` or 5-tuples in ``add_wheel_sweep`` order:
        p0, p1, speed, film depth mm, tyre width), then step by dt_s (s). Returns what it did."""
        dt = checks.number("dt_s", dt_s, 0.0, math.inf, "s")
        # With a film-depth function the cells that scroll in are asked together with this frame's band.
        fill = film_depth_fn is None or self._depth_mm is None
        shift = (0, 0) if center_xz is None else self._recenter(*center_xz, fill=fill)
        if film_depth_fn is not None:
            if self._depth_mm is None:
                self.refresh_water_mask(film_depth_fn)
            else:  # a new function object each frame (the weather moves on): keep rolling, no full re-ask
                self._film_fn = film_depth_fn
                self._refresh_depth_band(dt)
        drops = self.add_raindrops(rate_mm_h, dt)
        bumps = 0
        for wheel in wheels:
            if isinstance(wheel, WheelSweep):
                p0, p1, speed, depth, width = (wheel.p0_xz, wheel.p1_xz, wheel.speed_m_s, wheel.film_depth_mm,
                                               wheel.tire_width_m)
            else:
                p0, p1, speed, depth, width = wheel
            if depth is None:
                if film_depth_fn is None:
                    raise ValueError("a wheel without film_depth_mm needs film_depth_fn")
                mid_x, mid_z = 0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1])
                depth = float(np.asarray(film_depth_fn(np.array([mid_x]), np.array([mid_z]))).ravel()[0])
            bumps += self.add_wheel_sweep(p0, p1, speed, depth, width)
        substeps = self.step(dt)
        return {"shift": shift, "drops": drops, "wake_bumps": bumps, "substeps": substeps,
                "asleep": self.asleep, "backend": self.backend}

    @property
    def asleep(self) -> bool:
        """True while the water is at rest and the solver skips its steps."""
        return self.solver.asleep

    @property
    def height(self) -> np.ndarray:
        """The (n, n) height field in m, indexed [iz, ix] (see origin_xz)."""
        return self.solver.height

    def release(self):
        """Free the solver's GL objects, if it has any (the GPU solver); a NumPy field holds none."""
        release = getattr(self.solver, "release", None)
        if release is not None:
            release()
