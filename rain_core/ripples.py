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
``WaveSolverGPU`` (the same stencil in ``shaders/ripples_step.frag`` on an RG32F texture, ping-ponged).
``choose_backend`` measures which fast path is faster on this machine; ``RippleField`` is the world-anchored
field around the car that the renderer uses.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from rain_core.renderer import Effect

# Wave speed. Shallow-water gravity waves on a 5 mm film travel at sqrt(g·d) ≈ 0.22 m/s, and capillary-gravity
# ripples of 1–10 cm wavelength at 0.23–0.4 m/s; 0.22 m/s reads as sluggish at driving-view scale, so the
# default sits in the capillary-gravity range.
CAPILLARY_SPEED_M_S = 0.35
# Amplitude e-folding rate, 1/s: a wake fades to ~10 % in ~4.6 s.
DEFAULT_DAMPING_PER_S = 0.5
MAX_COURANT2 = 0.5  # the leapfrog's stability bound on C² = (s·Δt/h)²
MAX_IMPULSE_M = 1e9  # |amount| bound: keeps float32 state finite (no ripple is a kilometre high)
DEFAULT_MAX_SUBSTEPS = 1000  # per step() call; a stall longer than this many Δt_max is shortened (see step)
SLEEP_SLOPE = 1e-4  # sleep when the energy is below that of a field with this RMS slope everywhere
MIN_FOOTPRINT_CELLS = 1.5  # impulses narrower than this many cells are widened (volume kept)

# Wheel wake: the dent under a tyre, in metres, is film depth × speed / WAKE_REF_SPEED_M_S (proportional to
# both, as the issue asks): at 10 m/s (36 km/h) the tyre presses a trough as deep as the film.
WAKE_REF_SPEED_M_S = 10.0
# Raindrop dent: depth in metres per unit momentum (kg·m/s), over a crater of radius CRATER_RADIUS_PER_D × D.
# Calibrated so a 2 mm drop at its terminal 6.5 m/s (p = 2.7e-5 kg·m/s) presses a 1 mm deep, 5 mm radius dent
# (craters of a few drop radii, Engel 1966). On a 5 cm grid the dent is spread over 1.5 cells with its
# volume kept, so single drops are µm-scale there; the visible rain rings come from RainRippleTexture.
RAIN_DENT_M_PER_KG_M_S = 37.0
CRATER_RADIUS_PER_D = 2.5
RHO_WATER_KG_M3 = 1000.0

BACKENDS = ("auto", "numpy32", "gpu", "reference")


def _finite(name: str, value, lo: float = -math.inf, hi: float = math.inf, unit: str = "") -> float:
    """``value`` as a float; ValueError naming the argument if it is not finite or outside [lo, hi]."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number{unit and ' in ' + unit}, got {value!r}") from None
    if not math.isfinite(x) or x < lo or x > hi:
        raise ValueError(f"{name} must be finite and in [{lo:g}, {hi:g}]{unit and ' ' + unit}, got {value!r}")
    return x


def _finite_array(name: str, value, shape=None) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if shape is not None and a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return a


def _shifted(a: np.ndarray, dx: int, dz: int, fill) -> np.ndarray:
    """out[iz, ix] = a[iz + dz, ix + dx] where that exists, else ``fill``."""
    n_z, n_x = a.shape
    out = np.full_like(a, fill)
    if abs(dx) < n_x and abs(dz) < n_z:
        out[max(0, -dz):n_z - max(0, dz), max(0, -dx):n_x - max(0, dx)] = \
            a[max(0, dz):n_z - max(0, -dz), max(0, dx):n_x - max(0, -dx)]
    return out


def _unbind(ctx, targets):
    """Bind framebuffer 0 if one of ``targets`` (RenderTargets) is bound: releasing the bound framebuffer
    leaves moderngl re-binding a deleted name later (GL_INVALID_OPERATION, and draws into other targets
    are lost)."""
    current = ctx.fbo
    if current is not None and any(current.glo == t.fbo.glo for t in targets):
        ctx.detect_framebuffer(0).use()


# --- the float64 reference ---------------------------------------------------------------------------------

class WaveSolver:
    """Float64 NumPy reference of the damped leapfrog wave solver (see the module docstring for the scheme).

    ``WaveSolver(n, cell_m, speed_m_s, damping_per_s=0.0)``: n cells per side including the fixed edges (≥ 3),
    cell size in m, wave speed in m/s, amplitude damping rate in 1/s. ``sleep_energy`` (m⁴/s²): below it, with
    no sources, the solver zeroes the field and stops stepping (None: the energy of a field with RMS slope
    ``SLEEP_SLOPE``; 0 never sleeps). Energy is checked every ``sleep_check_every`` step() calls.
    """

    dtype = np.float64

    def __init__(self, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0, *,
                 sleep_energy: float | None = None, max_substeps: int = DEFAULT_MAX_SUBSTEPS,
                 sleep_check_every: int = 8):
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 3:
            raise ValueError(f"n must be an int >= 3 (cells per side, edges included), got {n!r}")
        if isinstance(max_substeps, bool) or not isinstance(max_substeps, int | np.integer) or max_substeps < 1:
            raise ValueError(f"max_substeps must be an int >= 1, got {max_substeps!r}")
        self.n = int(n)
        self.cell_m = _finite("cell_m", cell_m, 1e-9, 1e6, "m")
        self.speed_m_s = _finite("speed_m_s", speed_m_s, 1e-9, 1e6, "m/s")
        self.damping_per_s = _finite("damping_per_s", damping_per_s, 0.0, 1e6, "1/s")
        self.length_m = (self.n - 1) * self.cell_m
        self.max_substeps = int(max_substeps)
        self.sleep_check_every = max(1, int(sleep_check_every))
        if sleep_energy is None:
            sleep_energy = 0.5 * (self.speed_m_s * SLEEP_SLOPE) ** 2 * self.length_m ** 2
        self.sleep_energy = _finite("sleep_energy", sleep_energy, 0.0, math.inf, "m⁴/s²")
        dt_max = math.sqrt(MAX_COURANT2) * self.cell_m / self.speed_m_s
        while self.courant2(dt_max) > MAX_COURANT2:  # so every Δt ≤ dt_max keeps C² ≤ 1/2 after rounding
            dt_max = math.nextafter(dt_max, 0.0)
        self.dt_max = dt_max
        self._mask: np.ndarray | None = None  # None: all water; else 1.0 water / 0.0 held, in self.dtype
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
        add = self._z.ravel()
        prev = self._zp.ravel()
        if flat.size > self.n * self.n // 8:  # many sources: one dense accumulation beats scattered adds
            acc = np.bincount(flat, weights=values, minlength=self.n * self.n).astype(self.dtype)
            add += acc
            prev += acc
        else:
            vals = values.astype(self.dtype)
            np.add.at(add, flat, vals)
            np.add.at(prev, flat, vals)

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
        k = max(1, math.ceil(dt_s / self.dt_max))
        if k > self.max_substeps:
            return self.max_substeps, self.dt_max
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
        """(n, n) 1.0 where water may move, 0.0 where held; None when every interior cell is water."""
        return self._mask

    def reset(self, height0=None):
        """Start at rest (zero velocity) from height0, an (n, n) array in metres (None: flat). Edges and held
        cells are set to 0. Raises ValueError for a wrong shape or NaN/inf."""
        if height0 is None:
            z = np.zeros((self.n, self.n))
        else:
            z = _finite_array("height0", height0, (self.n, self.n)).copy()
        z[0, :] = z[-1, :] = z[:, 0] = z[:, -1] = 0.0
        if self._mask is not None:
            z *= self._mask
        self._set_state(z, z.copy())
        self._dt = None
        self._debt = 0.0
        self._dt_avg = None
        self.time_s = 0.0
        self.steps = 0
        self._asleep = False
        self._sourced = False
        self._since_check = 0

    def step(self, dt_s: float, *, reuse_tolerance: float = 0.0) -> int:
        """Advance by dt_s seconds (finite, ≥ 0) in equal sub-steps with C² ≤ 1/2; returns the number of
        sub-steps taken (0 while asleep or for dt_s = 0). Raises ValueError for NaN, inf or negative dt_s.

        reuse_tolerance (default 0: exact): when > 0, keep the current sub-step if a whole number of them is
        within that fraction of dt_s and carry the difference into the next call, so frame-time jitter does
        not retime the state every frame. The water then lags real time by at most tol/(1 − tol) of a frame,
        and each sub-step change (rare: a real change of frame rate, or the carried remainder drifting past
        tol) lets it slip by at most that much for good.
        """
        dt = _finite("dt_s", dt_s, 0.0, math.inf, "s")
        tol = _finite("reuse_tolerance", reuse_tolerance, 0.0, 0.5)
        if dt == 0.0 or self._asleep:
            return 0
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
        for keep, sub in ((True, self._dt), (False, self.plan(self._dt_avg)[1])):
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

    def add_impulse(self, x_m: float, z_m: float, radius_m: float, amount: float):
        """Displace the water by a raised-cosine bump of peak ``amount`` metres (negative: a dent) and radius
        ``radius_m`` centred at (x_m, z_m), metres from cell (0, 0). The velocity is unchanged (both stored
        levels move), so the bump is released from rest. A bump narrower than 1.5 cells is widened to that
        with its volume kept. Held cells and edges receive nothing; a bump off the grid is ignored."""
        self.add_impulses([_finite("x_m", x_m, unit="m")], [_finite("z_m", z_m, unit="m")],
                          _finite("radius_m", radius_m, 0.0, math.inf, "m"),
                          [_finite("amount", amount, -MAX_IMPULSE_M, MAX_IMPULSE_M, "m")])

    def add_impulses(self, xs_m, zs_m, radius_m, amounts_m):
        """Vectorised ``add_impulse``: arrays of centres (m) and peaks (m); radius_m (m, ≥ 0) one for all or
        one per bump."""
        xs = _finite_array("xs_m", xs_m).ravel()
        zs = _finite_array("zs_m", zs_m).ravel()
        amounts = _finite_array("amounts_m", amounts_m).ravel()
        if not (xs.shape == zs.shape == amounts.shape):
            raise ValueError("xs_m, zs_m and amounts_m must have the same length")
        radii = _finite_array("radius_m", radius_m)
        if radii.ndim and radii.size != xs.size:
            raise ValueError("radius_m must be a scalar or have one entry per impulse")
        radii = np.broadcast_to(radii.ravel() if radii.ndim else radii, xs.shape)
        if np.any(radii < 0.0):
            raise ValueError("radius_m must be >= 0 m")
        if np.any(np.abs(amounts) > MAX_IMPULSE_M):
            raise ValueError(f"impulse amounts must be within ±{MAX_IMPULSE_M:g} m")
        flat, values = self._footprint(xs, zs, radii, amounts)
        if flat.size:
            self._deposit(flat, values)
            self._sourced = True
            self._asleep = False

    def _footprint(self, xs, zs, radii, amounts) -> tuple[np.ndarray, np.ndarray]:
        """Flat cell indices and values of the bumps (interior water cells only)."""
        h, n = self.cell_m, self.n
        r_eff = np.maximum(radii, MIN_FOOTPRINT_CELLS * h)
        amounts = amounts * (radii / r_eff) ** 2  # bump volume ∝ peak·radius²: keep it when widening
        keep = (xs > -r_eff) & (xs < self.length_m + r_eff) & (zs > -r_eff) & (zs < self.length_m + r_eff) \
            & (amounts != 0.0)
        xs, zs, amounts, r_eff = xs[keep], zs[keep], amounts[keep], r_eff[keep]
        if xs.size == 0:
            return np.zeros(0, np.int64), np.zeros(0)
        # Cells within r of x lie from floor(x/h) − floor(r/h) to floor(x/h) + ceil(r/h).
        reach = r_eff.max() / h
        offsets = np.arange(-math.floor(reach), math.ceil(reach) + 1)
        cols = np.floor(xs / h).astype(np.int64)[:, None] + offsets  # (K, W)
        rows = np.floor(zs / h).astype(np.int64)[:, None] + offsets
        dx = cols * h - xs[:, None]
        dz = rows * h - zs[:, None]
        rel = np.sqrt(dx[:, None, :] ** 2 + dz[:, :, None] ** 2) / r_eff[:, None, None]  # (K, W rows, W cols)
        bump = np.where(rel < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.minimum(rel, 1.0))), 0.0)
        values = bump * amounts[:, None, None]
        inside = ((rows >= 1) & (rows <= n - 2))[:, :, None] & ((cols >= 1) & (cols <= n - 2))[:, None, :]
        inside &= values != 0.0
        flat = (rows[:, :, None] * n + cols[:, None, :])[inside]
        values = values[inside]
        if self._mask is not None:
            values = values * self._mask.ravel()[flat]
        return flat, values

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
            a = _finite_array("mask", a)
            if np.any(a < 0):
                raise ValueError("a film-depth mask must be >= 0 mm")
            a = a > 0.0
        self._mask = a.astype(self.dtype)
        self._apply_mask_to_state()

    def shift(self, dx_cells: int, dz_cells: int):
        """Scroll the window by whole cells: new[iz, ix] = old[iz + dz, ix + dx]; cells that enter are at rest,
        edges stay 0, the mask scrolls with the water (entering cells count as water until a new mask)."""
        dx, dz = int(dx_cells), int(dz_cells)
        if dx == 0 and dz == 0:
            return
        if self._mask is not None:
            self._mask = _shifted(self._mask, dx, dz, 1.0)
        if self._asleep:
            return
        z, zp = _shifted(self._z, dx, dz, 0.0), _shifted(self._zp, dx, dz, 0.0)
        for a in (z, zp):
            a[0, :] = a[-1, :] = a[:, 0] = a[:, -1] = 0.0
        self._z, self._zp = z, zp


# --- float32 NumPy fast path ---------------------------------------------------------------------------------

class WaveSolverF32(WaveSolver):
    """The same solver on float32 arrays with in-place, allocation-free vectorised steps (the CPU fast path).

    Same interface as ``WaveSolver``; ``height`` is float32. Energy and the retime guard accumulate their sums
    in float64."""

    dtype = np.float32

    def _alloc(self):
        super()._alloc()
        self._scratch = np.zeros((self.n - 2, self.n - 2), np.float32)
        self._scratch4 = np.zeros((self.n - 2, self.n - 2), np.float32)

    def _advance(self, k: int, alpha: float, kc2: float):
        z, zp, s, t = self._z, self._zp, self._scratch, self._scratch4
        a, kk = np.float32(alpha), np.float32(kc2)
        mask = None if self._mask is None else self._mask[1:-1, 1:-1]
        for _ in range(k):
            zi, pi = z[1:-1, 1:-1], zp[1:-1, 1:-1]
            # The previous level becomes the new one, z + α(z − z⁻) + k(Σ − 4z), in the shader's order: Σ − 4z
            # is exactly 0 for a flat patch, so smooth (slow) modes keep their frequency in float32; folding
            # it into (1 − 4k)z + kΣ would detune them by the rounding of the coefficients.
            np.subtract(zi, pi, out=pi)
            pi *= a
            pi += zi
            np.add(z[:-2, 1:-1], z[2:, 1:-1], out=s)
            s += z[1:-1, :-2]
            s += z[1:-1, 2:]
            np.multiply(zi, np.float32(4.0), out=t)
            s -= t
            s *= kk
            pi += s
            if mask is not None:
                pi *= mask
            z, zp = zp, z
        self._z, self._zp = z, zp


# --- GPU path ----------------------------------------------------------------------------------------------

REDUCE_BLOCK = 8  # cells per side summed by one fragment of the reduction pass


class WaveSolverGPU(WaveSolver):
    """The same solver in fragment shaders (OpenGL 3.3): an RG32F texture (current, previous) ping-ponged
    through ``shaders/ripples_step.frag``; sources are summed on the CPU into a displacement texture and added
    by ``ripples_impulse.frag`` with additive blending. ``height`` reads the texture back (float32).

    ``WaveSolverGPU(ctx, n, cell_m, speed_m_s, damping_per_s=0.0, shaders=None, **kw)``. Passes leave
    blending disabled and the scissor reset."""

    dtype = np.float32

    def __init__(self, ctx, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0, *,
                 shaders=None, **kwargs):
        from rain_core.gl import ShaderLibrary

        self.ctx = ctx
        self.shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        super().__init__(n, cell_m, speed_m_s, damping_per_s, **kwargs)

    def _alloc(self):
        import moderngl

        from rain_core.gl import PingPong, float_target, fullscreen_triangle

        ctx, n = self.ctx, self.n
        self.state = PingPong(ctx, (n, n), components=2, dtype="f4", filter_linear=False)
        for target in self.state.targets:
            target.fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.mask_texture = ctx.texture((n, n), 1, np.full(n * n, 255, np.uint8).tobytes(), dtype="f1")
        self.source_texture = ctx.texture((n, n), 1, dtype="f4")
        nb = -(-n // REDUCE_BLOCK)
        self.reduce_target = float_target(ctx, (nb, nb), 4, "f4", filter_linear=False)
        for tex in (self.mask_texture, self.source_texture):
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        prog = self.shaders.program
        self._progs = {
            "step": prog("common/fullscreen.vert", "ripples/step.frag"),
            "retime": prog("common/fullscreen.vert", "ripples/step.frag", defines={"RIPPLES_RETIME": 1}),
            "reduce": prog("common/fullscreen.vert", "ripples/step.frag",
                           defines={"RIPPLES_REDUCE": 1, "RIPPLES_BLOCK": REDUCE_BLOCK}),
            "shift": prog("common/fullscreen.vert", "ripples/step.frag", defines={"RIPPLES_SHIFT": 1}),
            "impulse": prog("common/fullscreen.vert", "ripples/impulse.frag"),
        }
        self._vaos = {name: fullscreen_triangle(ctx, p) for name, p in self._progs.items()}
        for p in self._progs.values():
            self._uniforms(p, u_state=0, u_mask=1, u_source=2, u_n=n,
                           u_s2=self.speed_m_s ** 2, u_inv_h2=1.0 / self.cell_m ** 2)
        self._pending = np.zeros((n, n), np.float32)
        self._pending_box: list[int] | None = None  # [x0, z0, x1, z1) of pending sources

    @staticmethod
    def _uniforms(prog, **values):
        for name, value in values.items():
            if name in prog:  # the compiler drops uniforms a variant does not use
                prog[name].value = value

    def _draw(self, name: str, target, **uniforms):
        prog = self._progs[name]
        self._uniforms(prog, **uniforms)
        self.state.src.color.use(0)
        self.mask_texture.use(1)
        target.fbo.use()
        self._vaos[name].render(vertices=3)

    def _pass(self, name: str, **uniforms):
        """Run a full-grid pass from state.src into state.dst and swap."""
        self._draw(name, self.state.dst, **uniforms)
        self.state.swap()

    def _flush(self):
        """Add the pending source displacement to both stored levels (one blended, scissored pass)."""
        if self._pending_box is None:
            return
        import moderngl

        x0, z0, x1, z1 = self._pending_box
        region = np.ascontiguousarray(self._pending[z0:z1, x0:x1])
        self.source_texture.write(region.tobytes(), viewport=(x0, z0, x1 - x0, z1 - z0))
        self._pending[z0:z1, x0:x1] = 0.0
        self._pending_box = None
        fbo = self.state.src.fbo
        self.source_texture.use(2)
        self.mask_texture.use(1)
        fbo.use()
        fbo.scissor = (x0, z0, x1 - x0, z1 - z0)
        self.ctx.enable(moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        try:
            self._vaos["impulse"].render(vertices=3)
        finally:
            self.ctx.disable(moderngl.BLEND)
            fbo.scissor = None

    def _deposit(self, flat: np.ndarray, values: np.ndarray):
        n = self.n
        np.add.at(self._pending.ravel(), flat, values.astype(np.float32))
        rows, cols = np.divmod(flat, n)
        box = [int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1]
        if self._pending_box is not None:
            old = self._pending_box
            box = [min(old[0], box[0]), min(old[1], box[1]), max(old[2], box[2]), max(old[3], box[3])]
        self._pending_box = box

    def _get_state(self):
        self._flush()
        data = np.frombuffer(self.state.src.color.read(), np.float32).reshape(self.n, self.n, 2)
        return data[..., 0].astype(np.float64), data[..., 1].astype(np.float64)

    def _set_state(self, z, zp):
        self._pending[:] = 0.0
        self._pending_box = None
        data = np.stack([np.asarray(z, np.float32), np.asarray(zp, np.float32)], axis=-1)
        self.state.src.color.write(np.ascontiguousarray(data).tobytes())

    @property
    def height(self) -> np.ndarray:
        z, _ = self._get_state()
        return z.astype(np.float32)

    @property
    def texture(self):
        """The current state texture (RG32F: R height, G previous height, metres); changes every step."""
        self._flush()
        return self.state.src.color

    def _advance(self, k: int, alpha: float, kc2: float):
        self._flush()
        self._uniforms(self._progs["step"], u_alpha=alpha, u_k=kc2)
        for _ in range(k):
            self._pass("step")

    def _sums(self, dt_old, synced=None):
        self._flush()
        self._draw("reduce", self.reduce_target, u_dt_old=0.0 if dt_old is None else dt_old)
        sums = np.frombuffer(self.reduce_target.color.read(), np.float32).reshape(-1, 4).astype(np.float64)
        total = sums.sum(axis=0)
        return float(total[0]), float(total[1]), float(total[2])

    def _retime(self, dt_new: float):
        dt_old = self._dt
        lam = mu = 1.0
        if dt_old is not None and dt_new < dt_old:
            lam, mu = self._guard(dt_old, dt_new, self._sums(dt_old))
        self.retimes += dt_old is not None
        self._flush()
        self._pass("retime", u_dt_old=0.0 if dt_old is None else dt_old, u_dt_new=dt_new,
                   u_lambda=lam, u_mu=mu)
        self._dt = dt_new

    def energy(self) -> float:
        """Discrete energy (m⁴/s²) from GPU block sums: h²·[½Σu² + ½s²Σz·Az − (Δt²s⁴/8)Σ(Az)²], the same
        quantity as the reference's staggered form (equal algebraically, see the module docstring)."""
        k_sum, p_sum, r_sum = self._sums(self._dt)
        dt = self._dt or 0.0
        s2 = self.speed_m_s ** 2
        return self.cell_m ** 2 * (0.5 * k_sum + 0.5 * s2 * p_sum - dt * dt * s2 * s2 / 8.0 * r_sum)

    def _upload_mask(self):
        m = np.ones((self.n, self.n)) if self._mask is None else self._mask
        self.mask_texture.write((np.asarray(m) > 0.5).astype(np.uint8).__mul__(255).tobytes())

    def _apply_mask_to_state(self):
        self._flush()
        self._upload_mask()
        self._pass("shift", u_shift=(0, 0))

    def set_water_mask(self, mask):
        super().set_water_mask(mask)
        if mask is None:
            self._upload_mask()

    def shift(self, dx_cells: int, dz_cells: int):
        dx, dz = int(dx_cells), int(dz_cells)
        if dx == 0 and dz == 0:
            return
        self._flush()
        if self._mask is not None:
            self._mask = _shifted(self._mask, dx, dz, 1.0)
            self._upload_mask()
        if not self._asleep:
            self._pass("shift", u_shift=(dx, dz))

    def release(self):
        """Free the GL objects."""
        _unbind(self.ctx, [*self.state.targets, self.reduce_target])
        self.state.release()
        self.reduce_target.release()
        for obj in (self.mask_texture, self.source_texture, *self._vaos.values()):
            obj.release()


# --- backend choice ---------------------------------------------------------------------------------------

def _time_steps(solver: WaveSolver, steps: int, after=None) -> float:
    """Median ms per step of ``solver`` (one sub-step each), plus ``after()`` per step when given."""
    rng = np.random.default_rng(1)
    solver.sleep_energy = 0.0
    solver.reset(rng.standard_normal((solver.n, solver.n)) * 1e-3)
    dt = solver.dt_max
    samples = []
    for i in range(steps + 2):
        t0 = time.perf_counter()
        solver.step(dt)
        if after is not None:
            after()
        if i >= 2:  # the first steps compile, allocate and retime
            samples.append((time.perf_counter() - t0) * 1e3)
    samples.sort()
    return samples[len(samples) // 2]


def choose_backend(ctx, n: int, steps: int = 8, cell_m: float = 0.05,
                   speed_m_s: float = CAPILLARY_SPEED_M_S) -> tuple[str, dict[str, float]]:
    """Measure a few n×n steps of each fast path and return ("numpy32" | "gpu", timings in ms per step).

    The CPU path's cost includes uploading its height to a texture (the renderer needs it there); the GPU
    path's includes waiting for the GPU (ctx.finish). Without a context the answer is numpy32."""
    timings: dict[str, float] = {}
    cpu = WaveSolverF32(n, cell_m, speed_m_s)
    if ctx is None:
        timings["numpy32_ms"] = _time_steps(cpu, steps)
        return "numpy32", timings
    tex = ctx.texture((n, n), 1, dtype="f4")
    try:
        timings["numpy32_ms"] = _time_steps(cpu, steps, after=lambda: tex.write(cpu.height.tobytes()))
    finally:
        tex.release()
    gpu = WaveSolverGPU(ctx, n, cell_m, speed_m_s)
    try:
        timings["gpu_ms"] = _time_steps(gpu, steps, after=ctx.finish)
    finally:
        gpu.release()
    choice = "gpu" if timings["gpu_ms"] < timings["numpy32_ms"] else "numpy32"
    return choice, timings


def make_solver(backend: str, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0,
                ctx=None, **kwargs) -> WaveSolver:
    """A solver for a named backend ("numpy32", "gpu" (needs ctx), "reference")."""
    if backend == "reference":
        return WaveSolver(n, cell_m, speed_m_s, damping_per_s, **kwargs)
    if backend == "numpy32":
        return WaveSolverF32(n, cell_m, speed_m_s, damping_per_s, **kwargs)
    if backend == "gpu":
        if ctx is None:
            raise ValueError("backend 'gpu' needs an OpenGL context")
        return WaveSolverGPU(ctx, n, cell_m, speed_m_s, damping_per_s, **kwargs)
    raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")


# --- the world-anchored field around the car ---------------------------------------------------------------

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


class RippleField:
    """The ripple heightfield around the ego car, anchored to the world: cell (ix, iz) of the window lies at
    world (origin_x + ix·h, origin_z + iz·h) with the origin on a fixed world lattice, so when the car moves
    the window scrolls by whole cells, cells that enter are at rest and a wake stays where it was made.

    ``RippleField(ctx_or_None, n=512, extent_m=25.0, speed_m_s, damping_per_s, backend="auto")``; backend
    "auto" measures the fast paths with ``choose_backend`` (numpy32 without a context); the choice and its
    timings are in ``backend`` / ``backend_timings``. With a context, ``height_texture`` (R = height, m) and
    ``normal_texture`` (RG16F slopes dh/dx, dh/dz) feed the road's water normal. seed: the raindrop rng.
    """

    def __init__(self, ctx=None, n: int = 512, extent_m: float = 25.0, speed_m_s: float = CAPILLARY_SPEED_M_S,
                 damping_per_s: float = DEFAULT_DAMPING_PER_S, backend: str = "auto", *, seed: int = 0,
                 shaders=None, recenter_margin_cells: int = 4, max_drops_per_frame: int = 4096,
                 rain_gain: float = 1.0, wake_gain: float = 1.0, mask_refresh_s: float = 1.0,
                 reuse_tolerance: float = 0.25):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 8:
            raise ValueError(f"n must be an int >= 8 (cells per side), got {n!r}")
        extent = _finite("extent_m", extent_m, 1e-3, 1e5, "m")
        self.n = int(n)
        self.cell_m = extent / (self.n - 1)
        self.extent_m = extent
        self.ctx = ctx
        self.recenter_margin_cells = max(1, int(recenter_margin_cells))
        self.max_drops_per_frame = max(1, int(max_drops_per_frame))
        self.rain_gain = _finite("rain_gain", rain_gain, 0.0, 1e6)
        self.wake_gain = _finite("wake_gain", wake_gain, 0.0, 1e6)
        self.mask_refresh_s = _finite("mask_refresh_s", mask_refresh_s, 0.0, 1e6, "s")
        self.reuse_tolerance = _finite("reuse_tolerance", reuse_tolerance, 0.0, 0.5)
        self.rng = np.random.default_rng(seed)
        self.backend_timings: dict[str, float] = {}
        if backend == "auto":
            if ctx is None:
                backend = "numpy32"
            else:
                backend, self.backend_timings = choose_backend(ctx, self.n, cell_m=self.cell_m,
                                                               speed_m_s=speed_m_s)
        self.backend = backend
        if shaders is None and ctx is not None:
            from rain_core.gl import ShaderLibrary

            shaders = ShaderLibrary(ctx)
        extra = {"shaders": shaders} if backend == "gpu" else {}
        self.solver = make_solver(backend, self.n, self.cell_m, speed_m_s, damping_per_s, ctx=ctx, **extra)
        half = (self.n - 1) // 2
        self._anchor = (-half, -half)  # world lattice index of cell (0, 0); the window starts centred on 0
        self._centred = False
        self._water_cells: np.ndarray | None = None  # flat indices of water cells (None: all interior)
        self._film_fn: FilmDepthFn | None = None
        self._depth_mm: np.ndarray | None = None  # film depth of each cell from _film_fn (NaN: not yet asked)
        self._refresh_row = 0.0  # where the rolling re-evaluation of the film depth has got to (rows)
        self._dirty = True
        self._normals = self._height_tex = None
        if ctx is not None:
            import moderngl

            from rain_core.gl import float_target, fullscreen_triangle

            self._normals = float_target(ctx, (self.n, self.n), 2, "f2", filter_linear=True)
            self._normals_prog = shaders.program("common/fullscreen.vert", "ripples/normals.frag")
            self._normals_prog["u_height"].value = 0
            self._normals_prog["u_inv_2h"].value = 0.5 / self.cell_m
            self._normals_vao = fullscreen_triangle(ctx, self._normals_prog)
            if backend != "gpu":
                self._height_tex = ctx.texture((self.n, self.n), 1, dtype="f4")
                self._height_tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
                self._height_tex.repeat_x = self._height_tex.repeat_y = False

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
        x = _finite("x_m", x_m, unit="m")
        z = _finite("z_m", z_m, unit="m")
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
                self._depth_mm = _shifted(self._depth_mm, dx, dz, np.nan)
                if fill:
                    self._fill_unknown_depths()
            self._update_water_cells()
            self._dirty = True
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
        self._dirty = True

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
        x0, z0 = (_finite("p0_xz", v, unit="m") for v in p0_xz)
        x1, z1 = (_finite("p1_xz", v, unit="m") for v in p1_xz)
        speed = _finite("speed_m_s", speed_m_s, 0.0, 1e3, "m/s")
        depth_m = _finite("film_depth_mm", film_depth_mm, 0.0, 1e3, "mm") * 1e-3
        radius = 0.5 * _finite("tire_width_m", tire_width_m, 1e-3, 10.0, "m")
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
        rate = _finite("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        dt = _finite("dt_s", dt_s, 0.0, math.inf, "s")
        if rate == 0.0 or dt == 0.0 or self.rain_gain == 0.0:
            return 0
        from rain_core import physics

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
        diam = self._flux_weighted_diameters(physics, rate, drawn)
        speed = np.asarray(physics.terminal_velocity(diam), dtype=np.float64)
        momentum = RHO_WATER_KG_M3 * math.pi / 6.0 * (diam * 1e-3) ** 3 * speed  # kg·m/s
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
        pressing a dent by the raindrops' law (RAIN_DENT_M_PER_KG_M_S × wake_gain). Returns the dents laid."""
        impacts = np.asarray(list(impacts), dtype=np.float64).reshape(-1, 3)
        if len(impacts) == 0 or self.wake_gain == 0.0:
            return 0
        impacts = impacts[np.all(np.isfinite(impacts), axis=1)]
        ox, oz = self.origin_xz
        self.solver.add_impulses(impacts[:, 0] - ox, impacts[:, 1] - oz, radius_m,
                                 -self.wake_gain * RAIN_DENT_M_PER_KG_M_S * np.abs(impacts[:, 2]))
        return len(impacts)

    def _flux_weighted_diameters(self, physics, rate: float, count: int) -> np.ndarray:
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
            self._dirty = True
        return k

    def update(self, dt_s: float, center_xz=None, rate_mm_h: float = 0.0, wheels: Iterable = (),
               film_depth_fn: FilmDepthFn | None = None) -> dict:
        """One frame: recenter on center_xz (world m; None keeps the window), follow the water mask of
        film_depth_fn(x_m, z_m) -> mm (see ``refresh_water_mask``: evaluated in full the first time, then in
        strips and bands, so it may be a new function object every frame), lay raindrops for
        rate_mm_h (mm/h) and the wheel sweeps (``WheelSweep`` or 5-tuples in ``add_wheel_sweep`` order:
        p0, p1, speed, film depth mm, tyre width), then step by dt_s (s). Returns what it did."""
        dt = _finite("dt_s", dt_s, 0.0, math.inf, "s")
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

    # -- textures --

    def refresh_textures(self):
        """Bring height_texture and normal_texture up to date (done on access; needs a context)."""
        if self.ctx is None:
            raise ValueError("RippleField has no OpenGL context: there are no textures")
        if not self._dirty:
            return
        if self._height_tex is not None:
            self._height_tex.write(np.ascontiguousarray(self.solver.height, dtype=np.float32).tobytes())
            height = self._height_tex
        else:
            height = self.solver.texture
        height.use(0)
        self._normals.fbo.use()
        self._normals_vao.render(vertices=3)
        self._dirty = False

    @property
    def height_texture(self):
        """Texture whose R channel is the height in m (n×n, [iz, ix] = row, column). On the GPU backend it is
        the solver's state texture, a different object after each step: fetch it every frame."""
        self.refresh_textures()
        return self._height_tex if self._height_tex is not None else self.solver.texture

    @property
    def normal_texture(self):
        """RG16F texture of the slopes (dh/dx, dh/dz) of the height (dimensionless), linear filtering."""
        self.refresh_textures()
        return self._normals.color

    def water_normals_resource(self) -> dict:
        """What the road reads from ``rc.resources["water_normals"]``: the slope texture, the world (x, z) in m
        of the centre of its texel 0, and the extent in m from the first texel centre to the last."""
        return {"texture": self.normal_texture, "origin_xz_m": self.origin_xz, "extent_m": self.extent_m}

    def release(self):
        """Free the GL objects (if any)."""
        if self._normals is not None:
            _unbind(self.ctx, [self._normals])
            self._normals.release()
            self._normals_vao.release()
        if self._height_tex is not None:
            self._height_tex.release()
        if isinstance(self.solver, WaveSolverGPU):
            self.solver.release()


# --- far puddles: a tiled rain-ring normal map -------------------------------------------------------------

RAIN_TILE_CYCLE_S = 0.6  # s, life of one ring
RAIN_TILE_VISIBLE_D_MM = 1.0  # mm: drops from this diameter up make a ring visible from a car
RAIN_TILE_SLOPE_PER_MM = 0.5  # peak ring slope per mm of mean drop diameter


class RainRippleTexture:
    """A tiling, animated map of raindrop rings on standing water: RG16F slopes (dh/dx, dh/dz) over a square
    tile of ``tile_m`` metres, repeat-wrapped with mipmaps, for puddles beyond the simulated window. Rings get
    denser and stronger with the rain rate; without rain the map is flat.

    ``RainRippleTexture(ctx, size=256, tile_m=1.0, layers=4, seed=0)``; ``render(time_s, rate_mm_h)``
    redraws ``texture`` for that time (s) and rate (mm/h)."""

    def __init__(self, ctx, size: int = 256, tile_m: float = 1.0, layers: int = 4, seed: int = 0, shaders=None):
        import moderngl

        from rain_core.gl import ShaderLibrary, float_target, fullscreen_triangle

        if isinstance(size, bool) or not isinstance(size, int | np.integer) or not 8 <= size <= 4096:
            raise ValueError(f"size must be an int in [8, 4096] texels, got {size!r}")
        if not 1 <= int(layers) <= 8:
            raise ValueError(f"layers must be in [1, 8], got {layers!r}")
        self.ctx = ctx
        self.size = int(size)
        self.tile_m = _finite("tile_m", tile_m, 1e-3, 1e3, "m")
        self.layers = int(layers)
        self.seed = int(seed) & 0xFFFFFFFF
        shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        self.target = float_target(ctx, (self.size, self.size), 2, "f2", filter_linear=True)
        tex = self.target.color
        tex.repeat_x = tex.repeat_y = True
        self.target.fbo.clear(0.0, 0.0, 0.0, 0.0)
        tex.build_mipmaps()
        tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        self._prog = shaders.program("common/fullscreen.vert", "ripples/rain_tile.frag")
        self._vao = fullscreen_triangle(ctx, self._prog)
        self._prog["u_size"].value = (float(self.size), float(self.size))
        self._prog["u_cycle_s"].value = RAIN_TILE_CYCLE_S
        self._prog["u_layers"].value = self.layers
        self._prog["u_seed"].value = self.seed

    @property
    def texture(self):
        """The RG16F slope texture (dh/dx, dh/dz over the tile, dimensionless), repeat-wrapped."""
        return self.target.color

    def cells_per_side(self, layer: int) -> int:
        """Cells per tile side of a layer (matches ripples_rain_tile.frag)."""
        return 5 + 3 * layer

    def parameters(self, rate_mm_h: float) -> tuple[np.ndarray, float]:
        """(density per layer, peak slope) for a rate in mm/h. Rings per m² per s = the flux of drops of at
        least RAIN_TILE_VISIBLE_D_MM (flux × their number fraction, rain_core.physics), shared over the layers;
        a cell hosts a ring in a cycle with probability 1 − e^(−expected rings). The peak slope grows with the
        mean drop diameter 1/Λ(R) (bigger drops, stronger rings)."""
        rate = _finite("rate_mm_h", rate_mm_h, 0.0, 500.0, "mm/h")
        density = np.zeros(self.layers)
        if rate == 0.0:
            return density, 0.0
        from rain_core import physics

        visible = 1.0 - float(physics.drop_diameter_cdf(RAIN_TILE_VISIBLE_D_MM, rate))
        rings_m2_s = float(physics.flux_horizontal_per_m2_s(rate)) * visible
        for layer in range(self.layers):
            cell_m2 = (self.tile_m / self.cells_per_side(layer)) ** 2
            density[layer] = -math.expm1(-rings_m2_s * cell_m2 * RAIN_TILE_CYCLE_S / self.layers)
        mean_d_mm = 1.0 / float(physics.mp_slope_per_mm(rate))
        return density, RAIN_TILE_SLOPE_PER_MM * mean_d_mm

    def render(self, time_s: float, rate_mm_h: float):
        """Draw the rings at time_s (s) for rate_mm_h (mm/h); a flat map without rain."""
        t = _finite("time_s", time_s, 0.0, math.inf, "s")
        density, strength = self.parameters(rate_mm_h)
        fbo = self.target.fbo
        if strength == 0.0:
            fbo.clear(0.0, 0.0, 0.0, 0.0)
        else:
            self._prog["u_time"].value = t
            self._prog["u_strength"].value = strength
            self._prog["u_density"].value = tuple(density) + (0.0,) * (8 - self.layers)
            fbo.use()
            self._vao.render(vertices=3)
        self.texture.build_mipmaps()

    def release(self):
        """Free the GL objects."""
        _unbind(self.ctx, [self.target])
        self.target.release()
        self._vao.release()


# --- the effect: the field and the rain tiles driven by the frame ------------------------------------------

class RipplesEffect(Effect):
    """Interactive water (DESIGN §3): wakes of every wheel in the window and raindrop rings on the simulated field
    around the ego car, plus the tiled rain-ring map for puddles beyond it.

    It only runs where there is standing water (flood levels above 0) — a dry or merely wet road costs nothing —
    and the solver itself sleeps once the water has settled. It reads the road's ``film_depth_fn`` and the spray's
    ``droplet_impacts`` from ``rc.resources`` and publishes ``water_normals`` (the field's slopes) and
    ``rain_ripples`` (the tiled map) there for the road's water shading. Settings: ``settings.ripples`` and
    ``settings.quality.ripple_grid``."""

    name = "ripples"
    stages = ()

    def __init__(self, ctx, settings=None, seed: int = 0, backend: str = "auto"):
        self.ctx = ctx
        self.seed = int(seed)
        self.backend = backend
        self.field: RippleField | None = None
        self._config = None
        self.rain_tiles = RainRippleTexture(ctx, seed=self.seed) if ctx is not None else None
        self.last_report: dict = {}

    def _ensure_field(self, settings) -> RippleField:
        r = settings.ripples
        config = (settings.quality.ripple_grid, r.extent_m, r.speed_m_s, r.damping_per_s)
        if config != self._config:
            if self.field is not None:
                self.field.release()
            n, extent, speed, damping = config
            self.field = RippleField(self.ctx, n=n, extent_m=extent, speed_m_s=speed, damping_per_s=damping,
                                     backend=self.backend, seed=self.seed)
            self._config = config
        self.field.wake_gain = r.wheel_strength
        self.field.rain_gain = r.rain_strength
        return self.field

    def active(self, frame) -> bool:
        settings, weather = frame.settings, frame.weather
        if settings is None or weather is None or not settings.ripples.enabled:
            return False
        return max(weather.cracks, weather.puddles) > 0.0

    def wheel_sweeps(self, frame, field: RippleField) -> list[WheelSweep]:
        """The wheels whose contact path this frame lies in the window (world m, speeds m/s)."""
        ox, oz = field.origin_xz
        sweeps = []
        for vehicle in frame.vehicles:
            now = vehicle.wheel_contacts()
            before = getattr(vehicle, "previous_wheel_contacts", None)
            before = now if before is None else before
            xs, zs = np.concatenate([now[:, 0], before[:, 0]]), np.concatenate([now[:, 2], before[:, 2]])
            if xs.max() < ox or xs.min() > ox + field.extent_m or zs.max() < oz or zs.min() > oz + field.extent_m:
                continue
            speeds, widths = np.abs(vehicle.wheel_speeds()), vehicle.wheel_widths()
            for i in range(4):
                sweeps.append(WheelSweep((before[i, 0], before[i, 2]), (now[i, 0], now[i, 2]), float(speeds[i]),
                                         float(widths[i])))
        return sweeps

    def update(self, frame, rc) -> None:
        field = self._ensure_field(frame.settings)
        film_fn = rc.resources.get("film_depth_fn")
        if film_fn is None:  # the road effect is off: keep the water flat rather than guessing where it is
            return
        ego = frame.ego
        center = None if ego is None else (float(ego.position[0]), float(ego.position[2]))
        rate = frame.rain_rate_mm_h
        field.add_droplet_impacts(rc.resources.get("droplet_impacts", ()))
        self.last_report = field.update(frame.dt_s, center_xz=center, rate_mm_h=rate,
                                        wheels=self.wheel_sweeps(frame, field), film_depth_fn=film_fn)
        if self.ctx is not None:
            rc.resources["water_normals"] = field.water_normals_resource()
            if rate > 0.0 and self.rain_tiles is not None:
                self.rain_tiles.render(frame.time_s, rate)
                rc.resources["rain_ripples"] = {"texture": self.rain_tiles.texture, "tile_m": self.rain_tiles.tile_m}

    def describe(self) -> str:
        if self.field is None:
            return ""
        state = "asleep" if self.field.asleep else f"{self.last_report.get('substeps', 0)} sub-steps"
        return f"{self.field.backend} {self.field.n}², {state}"

    def release(self) -> None:
        if self.field is not None:
            self.field.release()
        if self.rain_tiles is not None and hasattr(self.rain_tiles, "release"):
            self.rain_tiles.release()
