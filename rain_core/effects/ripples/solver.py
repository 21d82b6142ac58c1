"""Interactive water (DESIGN §3, issue 5): a wave-equation heightfield around the ego car that wheel wakes and
raindrops disturb, its normals for the road's water, and a tiled rain-ring normal map for far puddles.

The scheme
----------
The damped 2D wave equation ∂²z/∂t² = s²∇²z − 2γ·∂z/∂t on an n×n grid of spacing h (metres). The grid includes
its fixed edge rows and columns (held at 0), so it spans L = (n − 1)·h. Cells where the water film depth is
zero are held at 0 like the edges (no ripples on merely wet asphalt). Array layout: ``height[iz, ix]`` is the
cell at x = ix·h, z = iz·h (a texture's row is its z cell, its column its x cell).

Leapfrog in time with a centred damping term, written in the (current, previous) form the GPU stores::

    z⁺ = z + α·(z − z⁻) + β·C²·(Σ 4 neighbours − 4z),   C = s·Δt/h,   α = e^(−2γΔt),   β = (1 + α)/2

With v = (z⁺ − z)/Δt and A = −(5-point Laplacian)/h² this is v⁺ = α·v⁻ − β·Δt·s²·A·z, i.e. the leapfrog with
the centred damping γ'·(v⁺ + v⁻), γ'Δt = tanh(γΔt). α is the per-step velocity factor: over a time T the
velocity decays by e^(−2γT) whatever the sub-step, so damping does not depend on dt, and a slowly oscillating
mode's amplitude e-folds at γ (``damping_per_s``). γ = 0 gives Gomez's undamped scheme exactly.

Discrete energy (the scheme's conserved quantity, in m⁴/s²: a quadratic invariant, not joules)::

    E^(n−½) = h²·Σ ½·((zⁿ − zⁿ⁻¹)/Δt)² + ½·s²·Σ_edges Δzⁿ⁻¹·Δzⁿ

(kinetic from the staggered velocity, potential from the staggered product of gradients; edges between
neighbouring cells, differences of heights). Taking the inner product of the scheme with (v⁺ + v⁻) gives
E⁺ − E⁻ = −(γ'Δt/2)·h²·|v⁺ + v⁻|² ≤ 0: constant without damping, non-increasing with it. E is a positive
quadratic form exactly when C² ≤ 1/2 (the largest eigenvalue of A is below 8/h²), which bounds the state.

Sub-stepping and a changing Δt
------------------------------
A frame dt is split into k = ceil(dt/Δt_max) equal sub-steps, Δt_max the largest step with C² ≤ 1/2, so the
leapfrog is exact for that dt. When the sub-step changes from Δt₀ to Δt₁ the stored previous level must be
re-expressed. Rescaling it (z⁻' = z − (z − z⁻)·Δt₁/Δt₀) keeps the staggered velocity but changes E by
−½s²(Δt₁ − Δt₀)⟨v, A z⟩, of either sign. Instead the state is synchronised with a half kick of the old step
and de-synchronised with a half kick of the new one (the variable-step Störmer–Verlet)::

    u = (z − z⁻)/Δt₀ − (Δt₀/2)·s²·A z        (velocity at the time of z)
    v' = u + (Δt₁/2)·s²·A z,   z⁻' = z − Δt₁·v'

In synchronous variables E_Δt(z, u) = h²·[½|u|² + ½s²⟨z, A z⟩ − (Δt²s⁴/8)|A z|²], so a longer step never
raises the energy, and a shorter one raises it by exactly h²·(s⁴/8)(Δt₀² − Δt₁²)|A z|². That rise is taken
out of the kinetic part (u scaled by λ < 1; if ever the kinetic part is too small, the height is scaled too),
so E never grows across a change either: a tiny, high-frequency-weighted loss, only when the step shrinks.
A state fresh from ``reset`` is synchronous with u = 0 (at rest), the Δt → 0 limit of the same formulas, so
the first step starts it exactly on the discrete standing-wave solution.

Backends, all with one interface (``reset``, ``step``, ``height``, ``energy``, ``add_impulse``, ...):
``WaveSolver`` (float64 NumPy, the reference), ``WaveSolverF32`` (vectorised in-place float32 NumPy),
``WaveSolverGPU`` (the same stencil in ``shaders/ripples/step.frag`` on an RG32F texture, ping-ponged; in
``gpu.py``, the one module of them that needs OpenGL). ``backend.choose_backend`` measures which fast path is
faster on this machine; ``field.RippleField`` is the world-anchored field around the car that the effect drives.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import checks
from rain_core.effects.ripples.constants import (
    DEFAULT_MAX_SUBSTEPS,
    FOOTPRINT_BATCH_CELLS,
    MAX_CELLS_PER_SIDE,
    MAX_COURANT2,
    MAX_IMPULSE_M,
    MIN_FOOTPRINT_CELLS,
    MIN_STEP_FRACTION,
    SLEEP_SLOPE,
)
from rain_core.effects.ripples.scroll import shift_in_place, shifted


class WaveSolver:
    """Float64 NumPy reference of the damped leapfrog wave solver (see the module docstring for the scheme).

    ``WaveSolver(n, cell_m, speed_m_s, damping_per_s=0.0)``: n cells per side including the fixed edges (3 to
    ``MAX_CELLS_PER_SIDE``), cell size in m, wave speed in m/s, amplitude damping rate in 1/s.
    ``sleep_energy`` (m⁴/s²): below it, with no sources, the solver zeroes the field and stops stepping (None:
    the energy of a field with RMS slope ``SLEEP_SLOPE``; 0 never sleeps). Energy is checked every
    ``sleep_check_every`` step() calls.
    """

    dtype = np.float64
    mask_dtype = np.float64  # the water mask's storage (the NumPy steps multiply by it)

    def __init__(self, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0, *,
                 sleep_energy: float | None = None, max_substeps: int = DEFAULT_MAX_SUBSTEPS,
                 sleep_check_every: int = 8):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 3 <= n <= MAX_CELLS_PER_SIDE:
            raise ValueError(f"n must be an int in [3, {MAX_CELLS_PER_SIDE}] (cells per side, edges included), "
                             f"got {checks.quote(n)}")
        if isinstance(max_substeps, bool) or not isinstance(max_substeps, int | np.integer) \
                or not 1 <= max_substeps <= 10**6:
            raise ValueError(f"max_substeps must be an int in [1, 1000000], got {checks.quote(max_substeps)}")
        self.n = int(n)
        self.cell_m = checks.number("cell_m", cell_m, 1e-9, 1e6, "m")
        self.speed_m_s = checks.number("speed_m_s", speed_m_s, 1e-9, 1e6, "m/s")
        self.damping_per_s = checks.number("damping_per_s", damping_per_s, 0.0, 1e6, "1/s")
        self.length_m = (self.n - 1) * self.cell_m
        self.max_substeps = int(max_substeps)
        self.sleep_check_every = max(1, int(sleep_check_every))
        if sleep_energy is None:
            sleep_energy = 0.5 * (self.speed_m_s * SLEEP_SLOPE) ** 2 * self.length_m ** 2
        self.sleep_energy = checks.number("sleep_energy", sleep_energy, 0.0, math.inf, "m⁴/s²")
        dt_max = math.sqrt(MAX_COURANT2) * self.cell_m / self.speed_m_s
        while self.courant2(dt_max) > MAX_COURANT2:  # so every Δt ≤ dt_max keeps C² ≤ 1/2 after rounding
            dt_max = math.nextafter(dt_max, 0.0)
        self.dt_max = dt_max
        self.min_step_s = MIN_STEP_FRACTION * dt_max  # shorter calls are carried, not stepped (see step)
        self._carry = 0.0  # s of calls shorter than min_step_s, not yet stepped
        self._mask: np.ndarray | None = None  # None: all water; else 1 water / 0 held, in self.mask_dtype
        self._dt: float | None = None  # sub-step of the stored (z, z⁻); None: synchronous and at rest
        self._debt = 0.0  # s of frame time not yet simulated (only with reuse_tolerance)
        self._dt_avg: float | None = None  # running mean frame time, s (only with reuse_tolerance)
        self.retimes = 0  # sub-step changes of a moving state (each costs a retime pass)
        self.time_s = 0.0
        self.steps = 0
        self._asleep = False
        self._sourced = False
        self._since_check = 0
        self._alloc()

    # -- storage (overridden by the fast paths) --

    def _alloc(self):
        self._z = np.zeros((self.n, self.n), self.dtype)
        self._zp = np.zeros((self.n, self.n), self.dtype)

    def _get_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(z, z⁻) as float64 copies."""
        return self._z.astype(np.float64), self._zp.astype(np.float64)

    def _set_state(self, z: np.ndarray, zp: np.ndarray):
        self._z = np.ascontiguousarray(z, dtype=self.dtype)
        self._zp = np.ascontiguousarray(zp, dtype=self.dtype)

    def _deposit(self, flat: np.ndarray, values: np.ndarray):
        # Scattered adds (NumPy ≥ 2 makes ufunc.at fast): no dense n×n accumulator allocated every frame.
        vals = values.astype(self.dtype)
        np.add.at(self._z.ravel(), flat, vals)
        np.add.at(self._zp.ravel(), flat, vals)

    def _advance(self, k: int, alpha: float, kc2: float):
        z, zp = self._z, self._zp
        for _ in range(k):
            new = np.zeros_like(z)
            lap = z[:-2, 1:-1] + z[2:, 1:-1] + z[1:-1, :-2] + z[1:-1, 2:] - 4.0 * z[1:-1, 1:-1]
            new[1:-1, 1:-1] = z[1:-1, 1:-1] + alpha * (z[1:-1, 1:-1] - zp[1:-1, 1:-1]) + kc2 * lap
            if self._mask is not None:
                new *= self._mask
            zp, z = z, new
        self._z, self._zp = z, zp

    def _apply_mask_to_state(self):
        if self._mask is not None:
            self._z *= self._mask
            self._zp *= self._mask

    # -- maths shared by every backend (float64) --

    def courant2(self, dt_s: float) -> float:
        """C² = (s·Δt/h)² for a sub-step Δt in s."""
        return (self.speed_m_s * dt_s / self.cell_m) ** 2

    def coefficients(self, dt_s: float) -> tuple[float, float]:
        """(α, β·C²) of the stencil for a sub-step Δt in s: α = e^(−2γΔt), β = (1 + α)/2."""
        alpha = math.exp(-2.0 * self.damping_per_s * dt_s)
        return alpha, 0.5 * (1.0 + alpha) * self.courant2(dt_s)

    def plan(self, dt_s: float) -> tuple[int, float]:
        """(k, Δt): k equal sub-steps of Δt (s) for a frame of dt_s (s), C² ≤ 1/2. A frame longer than
        max_substeps·Δt_max is shortened to that (the water lives through less time than the stall; the app
        must not freeze for it)."""
        if dt_s > self.max_substeps * self.dt_max:  # before ceil: dt/Δt_max may not even be a finite number
            return self.max_substeps, self.dt_max
        k = max(1, math.ceil(dt_s / self.dt_max))
        sub = dt_s / k
        while sub > self.dt_max:
            k += 1
            sub = dt_s / k
        return k, sub

    def _laplacian_a(self, z: np.ndarray) -> np.ndarray:
        """A z = −(5-point Laplacian of z)/h² in 1/m, on water cells only (0 on edges and held cells)."""
        az = np.zeros_like(z)
        c = az[1:-1, 1:-1]
        np.multiply(z[1:-1, 1:-1], 4.0, out=c)
        c -= z[:-2, 1:-1]
        c -= z[2:, 1:-1]
        c -= z[1:-1, :-2]
        c -= z[1:-1, 2:]
        c *= 1.0 / self.cell_m ** 2
        if self._mask is not None:
            az *= self._mask
        return az

    def _sync(self, dt_old: float | None) -> tuple[np.ndarray, np.ndarray | None]:
        """(A z, u) in the storage dtype; u = (z − z⁻)/Δt₀ − (Δt₀/2)s²·A z, None when synchronous at rest."""
        az = self._laplacian_a(self._z)
        if dt_old is None:
            return az, None
        u = self._z - self._zp
        u *= 1.0 / dt_old
        u -= az * (0.5 * dt_old * self.speed_m_s ** 2)
        return az, u

    def _sums(self, dt_old: float | None, synced=None) -> tuple[float, float, float]:
        """(Σu², Σ z·Az, Σ(Az)²) over the water cells, u the synchronous velocity (accumulated in float64)."""
        az, u = synced if synced is not None else self._sync(dt_old)
        k_sum = 0.0 if u is None else float(np.sum(u * u, dtype=np.float64))
        return k_sum, float(np.sum(self._z * az, dtype=np.float64)), float(np.sum(az * az, dtype=np.float64))

    def _guard(self, dt_old: float, dt_new: float, sums: tuple[float, float, float]) -> tuple[float, float]:
        """(λ, μ): scales of the synchronous velocity and of the height so that E does not rise when the
        sub-step shrinks from dt_old to dt_new (module docstring)."""
        k_sum, p_sum, r_sum = sums
        s2 = self.speed_m_s ** 2
        rise = s2 * s2 / 8.0 * (dt_old ** 2 - dt_new ** 2) * r_sum  # of the potential part, per h²
        if rise <= 0.0:
            return 1.0, 1.0
        if 0.5 * k_sum > rise:
            return math.sqrt(1.0 - rise / (0.5 * k_sum)), 1.0
        # The kinetic part cannot pay: stop it and lower the height to the old energy.
        e_old = 0.5 * k_sum + 0.5 * s2 * p_sum - s2 * s2 / 8.0 * dt_old ** 2 * r_sum
        q_new = 0.5 * s2 * p_sum - s2 * s2 / 8.0 * dt_new ** 2 * r_sum
        mu = math.sqrt(max(e_old, 0.0) / q_new) if q_new > 0.0 else 0.0
        return 0.0, min(mu, 1.0)

    def _retime(self, dt_new: float):
        """Re-express the stored state for a new sub-step, without raising the energy (module docstring)."""
        dt_old = self._dt
        az, u = self._sync(dt_old)
        lam = mu = 1.0
        if dt_old is not None and dt_new < dt_old:
            lam, mu = self._guard(dt_old, dt_new, self._sums(dt_old, (az, u)))
        self.retimes += dt_old is not None
        z = self._z
        if mu != 1.0:
            z *= mu
        v1 = az * (mu * 0.5 * dt_new * self.speed_m_s ** 2)
        if u is not None and lam != 0.0:
            u *= lam
            v1 += u
        v1 *= dt_new
        np.subtract(z, v1, out=self._zp)
        self._dt = dt_new

    # -- public interface --

    @property
    def height(self) -> np.ndarray:
        """The current (n, n) height field in metres (float64 here; float32 on the fast paths)."""
        return self._z

    @property
    def asleep(self) -> bool:
        """True while the field is at rest and the solver skips its steps (woken by any source)."""
        return self._asleep

    @property
    def substep_s(self) -> float | None:
        """The sub-step Δt (s) of the stored state; None before the first step after a reset."""
        return self._dt

    @property
    def water_mask(self) -> np.ndarray | None:
        """(n, n) 1 where water may move, 0 where held (``mask_dtype``: float64 for the reference, which multiplies
        by it; bool for the float32 solver, whose steps multiply by it as 0.0 / 1.0, and on the GPU, whose CPU
        copy only scrolls and uploads); None when every interior cell is water."""
        return self._mask

    def reset(self, height0=None):
        """Start at rest (zero velocity) from height0, an (n, n) array in metres (None: flat). Edges and held
        cells are set to 0. Raises ValueError for a wrong shape, NaN/inf or heights beyond ±MAX_IMPULSE_M."""
        if height0 is None:
            z = np.zeros((self.n, self.n))
        else:
            z = checks.finite_array("height0", height0, (self.n, self.n)).copy()
            if np.any(np.abs(z) > MAX_IMPULSE_M):
                raise ValueError(f"height0 must be within ±{MAX_IMPULSE_M:g} m")
        z[0, :] = z[-1, :] = z[:, 0] = z[:, -1] = 0.0
        if self._mask is not None:
            z *= self._mask
        self._set_state(z, z.copy())
        self._dt = None
        self._debt = 0.0
        self._carry = 0.0
        self._dt_avg = None
        self.time_s = 0.0
        self.steps = 0
        self._asleep = False
        self._sourced = False
        self._since_check = 0

    def step(self, dt_s: float, *, reuse_tolerance: float = 0.0) -> int:
        """Advance by dt_s seconds (finite, ≥ 0) in equal sub-steps with C² ≤ 1/2; returns the number of
        sub-steps taken (0 while asleep or for dt_s = 0). Raises ValueError for NaN, inf, negative or
        non-numeric dt_s. A call shorter than ``min_step_s`` (MIN_STEP_FRACTION of Δt_max, e.g. a denormal dt)
        takes no step: its time is carried into the next call. A call longer than max_substeps·Δt_max is
        shortened to that (``plan``), so the field stays finite whatever the dt.

        reuse_tolerance (default 0: exact): when > 0, keep the current sub-step if a whole number of them is
        within that fraction of dt_s and carry the difference into the next call, so frame-time jitter does
        not retime the state every frame. The water then lags real time by at most tol/(1 − tol) of a frame,
        and each sub-step change (rare: a real change of frame rate, or the carried remainder drifting past
        tol) lets it slip by at most that much for good.
        """
        dt = checks.number("dt_s", dt_s, 0.0, math.inf, "s")
        tol = checks.number("reuse_tolerance", reuse_tolerance, 0.0, 0.5)
        if dt == 0.0 or self._asleep:
            return 0
        if dt < self.min_step_s:
            self._carry += dt
            if self._carry < self.min_step_s:
                return 0
            dt, self._carry = self._carry, 0.0
        elif self._carry:
            dt, self._carry = dt + self._carry, 0.0
        dt = min(dt, self.max_substeps * self.dt_max)  # what plan() would shorten it to anyway
        k, sub = self._schedule(dt, tol)
        if k == 0:
            return 0
        if sub != self._dt:
            self._retime(sub)
        alpha, kc2 = self.coefficients(sub)
        self._advance(k, alpha, kc2)
        self.time_s += k * sub
        self.steps += k
        self._maybe_sleep()
        return k

    def _schedule(self, dt: float, tol: float) -> tuple[int, float]:
        """(k, Δt) for this call. With a tolerance: keep the current sub-step while k·Δt stays within tol of
        the frame time plus the carried remainder; otherwise change to the sub-step of the running mean frame
        time and drop the remainder (a slip of at most tol of a frame, so the next change is far off); a
        frame time far from both gets the exact plan."""
        if tol == 0.0:
            return self.plan(dt)
        self._dt_avg = dt if self._dt_avg is None else self._dt_avg + 0.05 * (dt - self._dt_avg)
        want = dt + self._debt
        if want <= 0.0:  # the last call ran ahead by more than this frame
            self._debt = want
            return 0, 0.0
        for keep in (True, False):
            sub = self._dt if keep else self.plan(self._dt_avg)[1]  # the plan only when the sub-step misses
            if sub is None:
                continue
            k = max(1, round(want / sub))
            if k <= self.max_substeps and abs(k * sub - want) <= tol * want:
                self._debt = want - k * sub if keep else 0.0
                return k, sub
        self._debt = 0.0
        return self.plan(want)

    def _maybe_sleep(self):
        self._since_check += 1
        if self._since_check < self.sleep_check_every:
            return
        self._since_check = 0
        if self._sourced:
            self._sourced = False
            return
        if self.sleep_energy > 0.0 and self.energy() < self.sleep_energy:
            self._set_state(np.zeros((self.n, self.n)), np.zeros((self.n, self.n)))
            self._dt = None
            self._debt = 0.0
            self._carry = 0.0
            self._asleep = True

    def energy(self) -> float:
        """The scheme's discrete energy E^(n−½) in m⁴/s² (module docstring): constant without damping and
        sources, never growing with damping, across sub-step changes included."""
        z, zp = self._z, self._zp
        f64 = np.float64
        if self._dt is None:  # synchronous at rest: E = ½s²·Σ_edges Δz² (the Δt → 0 limit)
            kinetic, zp = 0.0, z
        else:
            d = z - zp
            kinetic = 0.5 * (self.cell_m / self._dt) ** 2 * float(np.sum(d * d, dtype=f64))
        potential = float(np.sum(np.diff(zp, axis=0) * np.diff(z, axis=0), dtype=f64)
                          + np.sum(np.diff(zp, axis=1) * np.diff(z, axis=1), dtype=f64))
        return kinetic + 0.5 * self.speed_m_s ** 2 * potential

    @property
    def max_radius_m(self) -> float:
        """The largest impulse radius accepted (m): the field's span (a wider bump is no ripple, and its
        footprint would be an allocation as large as the radius squared)."""
        return self.length_m

    def add_impulse(self, x_m: float, z_m: float, radius_m: float, amount: float):
        """Displace the water by a raised-cosine bump of peak ``amount`` metres (negative: a dent) and radius
        ``radius_m`` (0 to ``max_radius_m``) centred at (x_m, z_m), metres from cell (0, 0). The velocity is
        unchanged (both stored levels move), so the bump is released from rest. A bump narrower than 1.5 cells
        is widened to that with its volume kept. Held cells and edges receive nothing; a bump off the grid is
        ignored."""
        self.add_impulses([checks.number("x_m", x_m, unit="m")], [checks.number("z_m", z_m, unit="m")],
                          checks.number("radius_m", radius_m, 0.0, self.max_radius_m, "m"),
                          [checks.number("amount", amount, -MAX_IMPULSE_M, MAX_IMPULSE_M, "m")])

    def add_impulses(self, xs_m, zs_m, radius_m, amounts_m):
        """Vectorised ``add_impulse``: arrays of centres (m) and peaks (m); radius_m (m, 0 to ``max_radius_m``)
        one for all or one per bump. Validates, then ``add_impulses_unchecked``."""
        xs = checks.finite_array("xs_m", xs_m).ravel()
        zs = checks.finite_array("zs_m", zs_m).ravel()
        amounts = checks.finite_array("amounts_m", amounts_m).ravel()
        if not (xs.shape == zs.shape == amounts.shape):
            raise ValueError("xs_m, zs_m and amounts_m must have the same length")
        radii = checks.finite_array("radius_m", radius_m)
        if radii.ndim and radii.size != xs.size:
            raise ValueError("radius_m must be a scalar or have one entry per impulse")
        radii = np.broadcast_to(radii.ravel() if radii.ndim else radii, xs.shape)
        if np.any(radii < 0.0) or np.any(radii > self.max_radius_m):
            bad = radii[(radii < 0.0) | (radii > self.max_radius_m)][0]
            raise ValueError(f"radius_m must be in [0, {self.max_radius_m:g}] m (the field's span), got {bad!r}")
        if np.any(np.abs(amounts) > MAX_IMPULSE_M):
            raise ValueError(f"impulse amounts must be within ±{MAX_IMPULSE_M:g} m")
        self.add_impulses_unchecked(xs, zs, radii, amounts)

    def add_impulses_unchecked(self, xs: np.ndarray, zs: np.ndarray, radii: np.ndarray, amounts: np.ndarray):
        """``add_impulses`` for callers that validated at their own boundary (the ripple field, once a frame):
        1-D float64 arrays of one length, finite, radii in [0, max_radius_m], |amounts| ≤ MAX_IMPULSE_M.
        The whole batch is one deposit (on the GPU, one buffer write and one draw)."""
        if xs.size == 0:
            return
        flat, values = self._footprint(xs, zs, radii, amounts)
        if flat.size:
            self._deposit(flat, values)
            self._sourced = True
            self._asleep = False

    def _bumps(self, xs, zs, radii, amounts) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The bumps that touch the grid, widened to MIN_FOOTPRINT_CELLS with their volume kept: (x m, z m,
        radius m, peak m), float64."""
        r_eff = np.maximum(radii, MIN_FOOTPRINT_CELLS * self.cell_m)
        amounts = amounts * (radii / r_eff) ** 2  # bump volume ∝ peak·radius²: keep it when widening
        keep = (xs > -r_eff) & (xs < self.length_m + r_eff) & (zs > -r_eff) & (zs < self.length_m + r_eff) \
            & (amounts != 0.0)
        return xs[keep], zs[keep], r_eff[keep], amounts[keep]

    def _footprint(self, xs, zs, radii, amounts) -> tuple[np.ndarray, np.ndarray]:
        """Flat cell indices and values of the bumps (interior water cells only). Bumps are evaluated in
        groups of equal reach, at most FOOTPRINT_BATCH_CELLS cells at a time, so the work and the temporaries
        stay bounded whatever the batch mixes (raindrops of 1.5 cells with a wake of 20)."""
        xs, zs, r_eff, amounts = self._bumps(xs, zs, radii, amounts)
        if xs.size == 0:
            return np.zeros(0, np.int64), np.zeros(0)
        reach = np.ceil(r_eff / self.cell_m).astype(np.int64)  # cells from the centre's cell to the rim
        order = np.argsort(reach, kind="stable")
        levels, starts = np.unique(reach[order], return_index=True)
        ends = np.append(starts[1:], order.size)
        flats, values = [], []
        for level, start, end in zip(levels.tolist(), starts.tolist(), ends.tolist(), strict=True):
            width = 2 * level + 1
            group = order[start:end]
            if width * width > FOOTPRINT_BATCH_CELLS:  # a huge bump: clipped to the grid, rows in chunks
                for i in group.tolist():
                    self._footprint_clipped(xs[i], zs[i], r_eff[i], amounts[i], flats, values)
                continue
            per = max(1, FOOTPRINT_BATCH_CELLS // (width * width))
            for lo in range(0, group.size, per):
                sel = group[lo:lo + per]
                self._footprint_group(xs[sel], zs[sel], r_eff[sel], amounts[sel], level, flats, values)
        flat = np.concatenate(flats) if flats else np.zeros(0, np.int64)
        vals = np.concatenate(values) if values else np.zeros(0)
        if self._mask is not None and flat.size:
            vals = vals * self._mask.ravel()[flat]
        return flat, vals

    def _footprint_group(self, xs, zs, r_eff, amounts, reach: int, flats: list, values: list) -> None:
        """Bumps whose rims lie within ``reach`` cells of their centre's cell: one (K, W, W) distance test,
        then the raised cosine only where a cell lies inside a rim (under a third of the square)."""
        h, n = self.cell_m, self.n
        # Cells within r of x lie from floor(x/h) − floor(r/h) to floor(x/h) + ceil(r/h).
        offsets = np.arange(-reach, reach + 1)
        cols = np.floor(xs / h).astype(np.int64)[:, None] + offsets  # (K, W)
        rows = np.floor(zs / h).astype(np.int64)[:, None] + offsets
        dx2 = (cols * h - xs[:, None]) ** 2
        dz2 = (rows * h - zs[:, None]) ** 2
        d2 = dx2[:, None, :] + dz2[:, :, None]  # (K, W rows, W cols)
        # Candidates by squared distance (with a hair of slack), then the exact rim test on them alone.
        k, i, j = np.nonzero(d2 <= (r_eff * r_eff * (1.0 + 1e-9))[:, None, None])
        row, col = rows[k, i], cols[k, j]
        rel = np.sqrt(d2[k, i, j]) / r_eff[k]
        keep = (rel < 1.0) & (row >= 1) & (row <= n - 2) & (col >= 1) & (col <= n - 2)
        k, row, col, rel = k[keep], row[keep], col[keep], rel[keep]
        vals = 0.5 * (1.0 + np.cos(np.pi * rel)) * amounts[k]
        nonzero = vals != 0.0
        flats.append(row[nonzero] * n + col[nonzero])
        values.append(vals[nonzero])

    def _footprint_clipped(self, x, z, r, amount, flats: list, values: list) -> None:
        """One bump wider than a batch: only the interior cells it covers, a band of rows at a time."""
        h, n = self.cell_m, self.n
        c0, c1 = max(1, math.floor((x - r) / h)), min(n - 2, math.ceil((x + r) / h))
        r0, r1 = max(1, math.floor((z - r) / h)), min(n - 2, math.ceil((z + r) / h))
        if c0 > c1 or r0 > r1:
            return
        cols = np.arange(c0, c1 + 1)
        dx2 = (cols * h - x) ** 2
        band = max(1, FOOTPRINT_BATCH_CELLS // cols.size)
        for lo in range(r0, r1 + 1, band):
            rows = np.arange(lo, min(lo + band, r1 + 1))
            rel = np.sqrt(dx2[None, :] + ((rows * h - z) ** 2)[:, None]) / r
            vals = np.where(rel < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.minimum(rel, 1.0))), 0.0) * amount
            inside = vals != 0.0
            flats.append((rows[:, None] * n + cols[None, :])[inside])
            values.append(vals[inside])

    def set_water_mask(self, mask):
        """Where the water may move: an (n, n) bool array, or film depths (mm, finite, ≥ 0) where depth > 0
        means water. Cells without water are held at rest (set to 0 now and kept there); None: all water."""
        if mask is None:
            self._mask = None
            return
        a = np.asarray(mask)
        if a.shape != (self.n, self.n):
            raise ValueError(f"mask must have shape {(self.n, self.n)}, got {a.shape}")
        if a.dtype != bool:
            a = checks.finite_array("mask", a)
            if np.any(a < 0):
                raise ValueError("a film-depth mask must be >= 0 mm")
            a = a > 0.0
        self._mask = a.astype(self.mask_dtype)
        self._apply_mask_to_state()

    def set_water_mask_blocks(self, blocks):
        """Replace the mask over some blocks, each (row0, col0, block): the rows row0… and columns col0… take
        ``block`` ((rows, cols) bool, True: water; trusted, no validation), and hold the cells that turned dry:
        what ``set_water_mask`` of the whole updated mask does, for the cost of the blocks (the field renews
        strips of its mask every frame)."""
        if self._mask is None:
            self._mask = np.ones((self.n, self.n), self.mask_dtype)
        regions = []
        for row0, col0, block in blocks:
            region = (slice(row0, row0 + block.shape[0]), slice(col0, col0 + block.shape[1]))
            self._mask[region] = block
            regions.append(region)
        if regions:
            self._apply_mask_to_blocks(regions)

    def _apply_mask_to_blocks(self, regions):
        # Cells outside the blocks keep their mask, and held cells already store 0: zeroing the blocks suffices.
        for region in regions:
            self._z[region] *= self._mask[region]
            self._zp[region] *= self._mask[region]

    def shift(self, dx_cells: int, dz_cells: int):
        """Scroll the window by whole cells: new[iz, ix] = old[iz + dz, ix + dx]; cells that enter are at rest,
        edges stay 0, the mask scrolls with the water (entering cells count as water until a new mask)."""
        dx, dz = int(dx_cells), int(dz_cells)
        if dx == 0 and dz == 0:
            return
        if self._mask is not None:
            shift_in_place(self._mask, dx, dz, 1.0)
        if self._asleep:
            return
        if self.dtype == np.float64:  # the reference: new arrays, so a height taken before stays as it was
            self._z, self._zp = shifted(self._z, dx, dz, 0.0), shifted(self._zp, dx, dz, 0.0)
        else:  # the fast path steps in place anyway: no n² allocations per scroll
            shift_in_place(self._z, dx, dz, 0.0)
            shift_in_place(self._zp, dx, dz, 0.0)
        for a in (self._z, self._zp):
            a[0, :] = a[-1, :] = a[:, 0] = a[:, -1] = 0.0


