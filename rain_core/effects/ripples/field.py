"""The ripple field around the car (DESIGN §3): the wave solver's window anchored to the world, kept on the
standing water of the road's film-depth function, disturbed by wheel wakes, raindrops and spray droplets.

NumPy only: the field runs, steps and sleeps without OpenGL. The GPU solver is built on the GL side
(``backend.make_field``) and handed in; the field's textures (height and slopes) live in ``textures.py``, and the
upkeep of its water mask (following the film depth as the window scrolls) in ``water_mask.py``.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import checks, jit, physics
from rain_core.effects.ripples import kernels
from rain_core.effects.ripples.constants import (
    BACKENDS,
    CAPILLARY_SPEED_M_S,
    CRATER_RADIUS_PER_D,
    DEFAULT_DAMPING_PER_S,
    MAX_IMPULSE_M,
    MIN_FOOTPRINT_CELLS,
    RAIN_DENT_M_PER_KG_M_S,
    WAKE_REF_SPEED_M_S,
)
from rain_core.effects.ripples.raindrops import (
    DropLaw,
    RainBatch,
    drop_law,
    drops_at_quantiles,
    rain_key,
    raindrops,
)
from rain_core.effects.ripples.scroll import shift_line
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.effects.ripples.solver_f32 import WaveSolverF32
from rain_core.effects.ripples.wakes import wake_bumps
from rain_core.effects.ripples.water_mask import RAIN_FRACTION_STRIDE, WaterFollowing  # noqa: F401 (re-exported)
from rain_core.effects.ripples.wheels import FilmDepthFn, WheelBatch
from rain_core.effects.ripples.window import field_grid

# The raindrop kernel's stand-in for "every cell is water" (one compiled signature: bool (1, 1), the float32
# solver's mask dtype).
_NO_WATER = np.ones((1, 1), np.bool_)
# The solvers that need no OpenGL context, by backend name.
CPU_SOLVERS = {"reference": WaveSolver, "numpy32": WaveSolverF32}
# Raindrop candidates per frame are at most this many times max_drops_per_frame (a window with little water
# takes more candidates, so about max_drops_per_frame of them land on water, down to this water fraction).
RAIN_CANDIDATE_FACTOR = 4
class RippleField(WaterFollowing):
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
        self.max_drops_per_frame = int(checks.number("max_drops_per_frame", max_drops_per_frame, 1, 10**6))
        self.rain_gain = checks.number("rain_gain", rain_gain, 0.0, 1e6)
        self.wake_gain = checks.number("wake_gain", wake_gain, 0.0, 1e6)
        self.mask_refresh_s = checks.number("mask_refresh_s", mask_refresh_s, 0.0, 1e6, "s")
        self.reuse_tolerance = checks.number("reuse_tolerance", reuse_tolerance, 0.0, 0.5)
        self.seed = int(seed)
        self.rng = np.random.default_rng(seed)
        self._rain_frame = 0  # frames that rained so far: with the seed, the key of a frame's raindrops
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
        self._water_fraction = 1.0  # of the interior cells, sampled (sizes the raindrop candidates)
        self._water_fraction_stale = False  # the mask or the window moved since _water_fraction was counted
        # Water cells of each mask row on the lattice's columns (1, 1 + RAIN_FRACTION_STRIDE, …), kept through
        # scrolls along z and strips (so a frame's lattice count sums 127 numbers instead of reading the mask);
        # None: count afresh (a new mask, a lateral scroll).
        self._row_water: np.ndarray | None = None
        self._film_fn: FilmDepthFn | None = None
        self._film_key = None  # the film function's ``cache_key`` (None: unknown, keep re-asking)
        self._rows_to_renew = 0  # rows still to re-ask since the function last changed
        # Whether the mask follows _film_fn: the solver's mask then holds whether each cell's film depth is > 0
        # (exactly 0 or 1), except at cells not asked yet, which lie in _unknown_rows / _unknown_cols.
        self._following = False
        # Whole rows / columns whose depth is not asked yet (after a scroll, the strips that entered): a cell is
        # unknown iff its row or its column is, so the strips are found without scanning n² NaNs.
        self._unknown_rows = np.zeros(self.n, bool)
        self._unknown_cols = np.zeros(self.n, bool)
        self._all_cols = np.arange(self.n)
        self._all_cols_x: tuple[int | None, np.ndarray | None] = (None, None)  # (anchor x, their world x in m)
        self._refresh_row = 0.0  # where the rolling re-evaluation of the film depth has got to (rows)
        self._batch: list | None = None  # the frame's bumps while ``update`` gathers them
        self._law: DropLaw | None = None  # the arriving drops' law at the last rain rate (see _drop_law)
        self._rain_out, self._rain_wet = np.zeros((4, 0)), np.empty(0, bool)  # the raindrop kernel's output
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
            if self._row_water is not None:
                self._scroll_row_water(dx, dz)
            if self._following:  # the mask scrolled with the solver: ask only about the cells that entered
                shift_line(self._unknown_rows, dz, True)
                shift_line(self._unknown_cols, dx, True)
                if fill:
                    self._fill_unknown_depths()
            self._water_fraction_stale = True
            self.version += 1
        return dx, dz

    # -- sources --
    #
    # Every source ends in ``_emit``: outside ``update`` a bump batch goes to the solver at once; inside it the
    # frame's batches (raindrops, wakes, spray droplets) are gathered and handed over as one (one footprint
    # evaluation on the CPU, one buffer write and one draw on the GPU).

    def _emit(self, xs: np.ndarray, zs: np.ndarray, radii, amounts: np.ndarray) -> None:
        """Window-metre centres, radii (scalar or per bump, ≤ the span) and peaks (m), already valid."""
        radii = np.asarray(radii, dtype=np.float64)
        if radii.ndim == 0:  # one radius for all (np.full: a fraction of np.broadcast_to's Python-level cost)
            radii = np.full(xs.shape, radii)
        elif radii.shape != xs.shape:
            radii = np.broadcast_to(radii, xs.shape)
        if self._batch is not None:
            self._batch.append((xs, zs, radii, amounts))
        else:
            self.solver.add_impulses_unchecked(xs, zs, radii, amounts)

    def _flush_batch(self) -> None:
        batch, self._batch = self._batch, None
        if batch:
            xs, zs, radii, amounts = (np.concatenate(parts) for parts in zip(*batch, strict=True))
            self.solver.add_impulses_unchecked(xs, zs, radii, amounts)

    def add_wheel_sweep(self, p0_xz, p1_xz, speed_m_s: float, film_depth_mm: float, tire_width_m: float) -> int:
        """Disturb the water along a wheel's path from p0_xz to p1_xz (world m) this frame: a trough as wide as
        the tyre and film_depth × speed / WAKE_REF_SPEED_M_S deep (× wake_gain), its water in a crest on either
        side (the wake keeps the film's volume), laid as bumps at most one cell apart so a fast wheel leaves a
        continuous wake. speed in m/s (≥ 0), film depth in mm (≥ 0), tyre
        width in m (> 0). Returns the number of bumps laid (the part of the path inside the window)."""
        x0, z0 = (checks.number("p0_xz", v, unit="m") for v in p0_xz)
        x1, z1 = (checks.number("p1_xz", v, unit="m") for v in p1_xz)
        speed = checks.number("speed_m_s", speed_m_s, 0.0, 1e3, "m/s")
        depth = checks.number("film_depth_mm", film_depth_mm, 0.0, 1e3, "mm")
        width = checks.number("tire_width_m", tire_width_m, 1e-3, 10.0, "m")
        return int(self._wakes(np.array([[x0, z0, x1, z1, speed, depth, width]])).sum())

    def _wakes(self, wheels: np.ndarray) -> np.ndarray:
        """``add_wheel_sweep`` for W valid wheels at once: rows (x0, z0, x1, z1 world m, speed m/s, film depth
        mm, tyre width m). Returns the bumps laid per wheel (trough and crests)."""
        ox, oz = self.origin_xz
        # the clip, the bumps and the crests in one loop, or their NumPy twin
        make = kernels.wake_bumps if jit.active() else wake_bumps
        xs, zs, radii, peaks, counts = make(
            np.ascontiguousarray(wheels, np.float64), ox, oz, self.solver.length_m, self.cell_m,
            self.solver.max_radius_m, self.wake_gain, MIN_FOOTPRINT_CELLS * self.cell_m, WAKE_REF_SPEED_M_S)
        if xs.size:
            self._emit(xs, zs, radii, peaks)
        return counts

    def add_raindrops(self, rate_mm_h: float, dt_s: float) -> int:
        """Drops that hit the water cells of the window in dt_s seconds at a rain rate in mm/h: a Poisson count
        from the drop flux (rain_core.physics) over the interior cells, each landing uniformly and pressing the
        water only where its cell holds water (so the drops on water are a Poisson count of the water's area),
        diameters from Marshall–Palmer weighted by fall speed (the faster drops of a size class arrive more
        often), each pressing a dent ∝ its momentum m·v (RAIN_DENT_M_PER_KG_M_S × rain_gain). More drops than
        about ``max_drops_per_frame`` on water are represented by fewer, each carrying a proportional share (the
        momentum flux is kept). The drops are a hash of the seed, the frame and their index
        (``raindrops.py``): the GPU solver makes them itself from a few uniforms, the NumPy solvers with the
        twin. Returns the drops laid on water (on the GPU, their expected number)."""
        rate = checks.number("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        dt = checks.number("dt_s", dt_s, 0.0, math.inf, "s")
        return self._raindrops(rate, dt)

    def rain_batch(self, rate: float, dt: float) -> RainBatch | None:
        """The next frame's raindrops (advances the rng and the frame counter), None when none fall: the count
        of candidates over the interior, capped so that about ``max_drops_per_frame`` of them land on water
        (at most RAIN_CANDIDATE_FACTOR × that), with the dent per unit momentum scaled by the drops each
        represents."""
        if rate == 0.0 or dt == 0.0 or self.rain_gain == 0.0:
            return None
        law = self._drop_law(rate)
        expected = law.flux * (self.n - 2) ** 2 * self.cell_m ** 2 * dt
        total = int(self.rng.poisson(min(expected, 1e15)))
        if total == 0:
            return None
        self._rain_frame += 1
        count = total
        if total > self.max_drops_per_frame:
            fraction = self._rain_water_fraction()
            if fraction == 0.0:
                return None
            count = min(total, math.ceil(self.max_drops_per_frame / max(fraction, 1.0 / RAIN_CANDIDATE_FACTOR)))
        weight = total / count
        return RainBatch(rain_key(self.seed, self._rain_frame), count,
                         -self.rain_gain * RAIN_DENT_M_PER_KG_M_S * weight, CRATER_RADIUS_PER_D * 1e-3, law)

    def _raindrops(self, rate: float, dt: float) -> int:
        batch = self.rain_batch(rate, dt)
        if batch is None:
            return 0
        queue = getattr(self.solver, "queue_raindrops", None)
        if queue is not None:  # the GPU makes them: a few uniforms, no sampling, no upload
            queue(batch)
            return round(batch.count * self._rain_water_fraction())
        water = self.solver.water_mask
        if jit.active() and isinstance(self.solver, WaveSolverF32):  # the float32 solver: one loop
            if self._rain_out.shape[1] < batch.count:  # the candidates are capped: this grows a few times at most
                self._rain_out, self._rain_wet = np.zeros((4, batch.count)), np.empty(batch.count, bool)
            law = batch.law
            count = kernels.raindrop_bumps(
                batch.key, batch.count, self.n, self.cell_m, _NO_WATER if water is None else water, water is not None,
                law.cdf, law.grid, law.p_d, law.dp_d, physics.D_MIN_MM, physics.D_MAX_MM, batch.crater_m_per_mm,
                batch.peak_per_momentum, self._rain_out, self._rain_wet)
            xs, zs, radii, dents = self._rain_out[:, :count]  # views: the solver or the batch copies them now
        else:
            _, xs, zs, radii, dents = raindrops(batch, self.n, self.cell_m, water)
        if xs.size:
            self._emit(xs, zs, radii, dents)
        return int(xs.size)

    def add_droplet_impacts(self, impacts, radius_m: float = 0.02) -> int:
        """Droplets landing in the water (e.g. wheel spray): (x m, z m world, downward momentum kg·m/s) each,
        pressing a dent by the raindrops' law (RAIN_DENT_M_PER_KG_M_S × wake_gain); None: none. Rows with a
        NaN or inf are skipped. Returns the dents laid."""
        if impacts is None:
            return 0
        radius = checks.number("radius_m", radius_m, 0.0, self.solver.max_radius_m, "m")
        try:
            impacts = np.asarray(impacts if isinstance(impacts, np.ndarray) else list(impacts), dtype=np.float64)
            impacts = impacts.reshape(-1, 3)
        except (TypeError, ValueError):
            raise ValueError(f"impacts must be an (N, 3) array of x m, z m, momentum kg·m/s, got "
                             f"{checks.quote(impacts)}") from None
        if len(impacts) == 0 or self.wake_gain == 0.0:
            return 0
        ox, oz = self.origin_xz
        if jit.active():  # the filter, the dents and the window's coordinates in one loop (~150 a frame)
            out = np.empty((4, len(impacts)))
            count = kernels.droplet_dents(np.ascontiguousarray(impacts), ox, oz,
                                          -self.wake_gain * RAIN_DENT_M_PER_KG_M_S, MAX_IMPULSE_M, radius, out)
            self._emit(*out[:, :count])
            return count
        finite = np.isfinite(impacts)
        if not finite.all():  # the row reduction and the copy only when a row has a NaN or inf
            impacts = impacts[finite.all(axis=1)]
        dent = -self.wake_gain * RAIN_DENT_M_PER_KG_M_S * np.abs(impacts[:, 2])
        dent = np.minimum(np.maximum(dent, -MAX_IMPULSE_M), MAX_IMPULSE_M)  # np.clip's, without its wrapper
        self._emit(impacts[:, 0] - ox, impacts[:, 1] - oz, radius, dent)
        return len(impacts)

    def _flux_weighted_diameters(self, rate: float, count: int) -> np.ndarray:
        """Diameters (mm) of ``count`` drops arriving on a surface (``_flux_weighted_drops``)."""
        return self._flux_weighted_drops(rate, self.rng.random(count))[0]

    def _flux_weighted_drops(self, rate: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(diameter mm, momentum m·v kg·m/s) of drops arriving on a surface at quantiles ``u`` ∈ [0, 1) of their
        law (``raindrops.drops_at_quantiles``: the airborne N(D) of ``physics.drop_diameter_cdf`` weighted by
        the fall speed v(D), inverse-CDF sampling on a 512-interval table built for this rate, the momentum
        from a table)."""
        return drops_at_quantiles(self._drop_law(rate), u)

    def _drop_table(self, rate: float):
        """(rate, diameter grid mm, flux-weighted CDF, drop flux per m² per s, momentum kg·m/s on
        DROP_MOMENTUM_NODES equal diameter steps, its steps): ``_drop_law`` as a tuple."""
        law = self._drop_law(rate)
        return law.rate_mm_h, law.grid, law.cdf, law.flux, law.p_d, law.dp_d

    def _drop_law(self, rate: float) -> DropLaw:
        """The arriving drops' law (``raindrops.drop_law``), kept while the rate stays the same (the drop-size
        law costs more than a frame's drops; the GPU uploads its CDF only when it is a new one)."""
        if self._law is None or self._law.rate_mm_h != rate:
            self._law = drop_law(rate)
        return self._law

    # -- time --

    def step(self, dt_s: float) -> int:
        """Advance the water by dt_s seconds (sub-steps inside; frame jitter below ``reuse_tolerance`` does not
        retime it). Returns the sub-steps taken (0 while asleep)."""
        k = self.solver.step(dt_s, reuse_tolerance=self.reuse_tolerance)
        if k:
            self.version += 1
        return k

    def update(self, dt_s: float, center_xz=None, rate_mm_h: float = 0.0, wheels=(),
               film_depth_fn: FilmDepthFn | None = None, impacts=None) -> dict:
        """One frame: recenter on center_xz (world m; None keeps the window), follow the water mask of
        film_depth_fn(x_m, z_m) -> mm (see ``refresh_water_mask``: evaluated in full the first time, then in
        strips and bands, so it may be a new function object every frame; its ``cache_key``, if any, stops
        the bands while the levels stay the same), lay raindrops for
        rate_mm_h (mm/h), the wheel sweeps and the droplet ``impacts`` (as ``add_droplet_impacts``), then step
        by dt_s (s). ``wheels``: a ``WheelBatch``, or ``WheelSweep``s or 5-tuples in ``add_wheel_sweep`` order
        (p0, p1, speed, film depth mm or None, tyre width). Everything is validated here, once; the frame's
        bumps reach the solver as one batch. Returns what it did."""
        dt = checks.number("dt_s", dt_s, 0.0, math.inf, "s")
        rate = checks.number("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        batch = WheelBatch.of(wheels)
        if batch.needs_depth and film_depth_fn is None:
            raise ValueError("a wheel without film_depth_mm needs film_depth_fn")
        # With a film-depth function the cells that scroll in are asked together with this frame's band.
        fill = film_depth_fn is None or not self._following
        shift = (0, 0) if center_xz is None else self._recenter(*center_xz, fill=fill)
        # The wheels' depths ride along with the strips' call (one call of the road's function a frame).
        wheel_xz = batch.depth_points() if film_depth_fn is not None and batch.needs_depth else None
        wheel_depths = None
        if film_depth_fn is not None:
            if not self._following:
                self.refresh_water_mask(film_depth_fn)
            else:  # a new function object each frame (the weather moves on): keep rolling, no full re-ask
                self._film_fn = film_depth_fn
                key = getattr(film_depth_fn, "cache_key", None)
                if key is None or key != self._film_key:
                    self._rows_to_renew = self.n  # the depths may have changed: renew every row once more
                self._film_key = key
                if self._rows_to_renew > 0:
                    renewed, wheel_depths = self._refresh_depth_band(dt, wheel_xz)
                    self._rows_to_renew -= renewed
                else:  # the same depths as when every row was last asked: only the strips that entered
                    wheel_depths = self._fill_unknown_depths(extra_xz=wheel_xz)
        self._batch = []
        try:
            drops = self._raindrops(rate, dt)
            bumps = int(self._wakes(batch.rows(film_depth_fn, wheel_depths)).sum()) if len(batch) else 0
            self.add_droplet_impacts(impacts)
            self._flush_batch()
        finally:
            self._batch = None
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
