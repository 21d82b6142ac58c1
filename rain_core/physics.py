"""Rain in physical units: drop sizes, fall speeds, fluxes, water content, extinction, tyre water.

Units (DESIGN §2): drop diameter D in **mm**, rain rate R in **mm/h**, everything else SI. Every public
function is vectorised over NumPy arrays (inputs broadcast), returns a Python float when all inputs are
scalars, and raises ``ValueError`` naming the argument and its allowed range for NaN, infinite, negative or
too-large input, so a NaN never comes out.

Sources
-------
* Drop sizes: Marshall & Palmer (1948), N(D) = N0·exp(−Λ·D), N0 = 8000 m⁻³ mm⁻¹, Λ = 4.1·R^−0.21 mm⁻¹.
* Fall speed: Gunn & Kinzer (1949) measurements (table below), interpolated by a monotone cubic (PCHIP); below
  their smallest drop (0.078 mm) Stokes' law v ∝ D² (Stokes gives 0.183 m/s at 0.078 mm, G&K measured 0.18);
  above 5.8 mm the speed is held at 9.17 m/s, since larger drops break up. The joins are C¹.
* Rain extinction: β = 0.312·R^0.67 km⁻¹ (Weber et al. 2015, as used by rain-augmentation work).
* Tyre water: M_w = v·b·WFD·ρ_w (Flintsch et al. 2012).

Drop-size range
---------------
The drops that effects draw, count and sample lie in [D_MIN_MM, D_MAX_MM] = [0.1, 6] mm: smaller drops are
sub-visual (and carry < 0.01 % of the water), larger ones break up in free fall.

R as given, N0 renormalised (the decision DESIGN §3 asks for)
------------------------------------------------------------
Marshall–Palmer is not self-consistent: the rate its drops carry, ∫N(D)·v(D)·(π/6)·D³ dD, is not the R put in
(``implied_rate_mm_h``; 1.17–1.19 × R from 0.5 to 10 mm/h, 1.09 × at 50, 1.03 × at 100, see
``python -m rain_core.bench physics``). R is what the user sets and what wets the road, so the *effects* keep
Λ(R) (the shape of the distribution) and rescale N0 to ``effective_n0(R)`` so that the drops in
[D_MIN_MM, D_MAX_MM] carry exactly R. Every derived quantity here (number density, fluxes, water content,
streak length weights) uses that renormalised distribution. ``marshall_palmer`` itself stays the published
formula with N0 = 8000 (it reproduces the published table).

Rates above ``R_MAX_MM_H`` = 500 mm/h are rejected everywhere: the world record one-hour rainfall is ~305 mm.

Finite out for every finite input accepted
------------------------------------------
Besides the rate, every argument whose size scales a result has a generous physical ceiling, so a product of
accepted inputs cannot overflow: speeds and velocity components ``MAX_SPEED_M_S`` (1000 m/s, three times the
speed of sound, far above any car or wind), areas ``MAX_AREA_M2`` (1 km²), exposures ``MAX_EXPOSURE_S`` (1 h),
the intercept ``MAX_N0`` and the splash inputs (tyre ≤ 5 m wide, film ≤ 1 m deep). Inside those ranges the
sums are arranged so no intermediate overflows or underflows into 0/0 (normals scaled before their length is
taken, the streak mean's weights taken relative to the smallest drop, the drop-size tail in closed form).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from rain_core import checks

# --- constants -------------------------------------------------------------------------------------------

N0_MP = 8000.0  # m⁻³ mm⁻¹, Marshall & Palmer's intercept
D_MIN_MM = 0.1  # mm, smallest drop the effects consider (sub-visual below)
D_MAX_MM = 6.0  # mm, largest stable drop (break-up above)
R_MAX_MM_H = 500.0  # mm/h, largest accepted rain rate
MAX_SPEED_M_S = 1000.0  # m/s, largest accepted speed or velocity component (3× the speed of sound)
MAX_AREA_M2 = 1e6  # m², largest accepted surface (1 km²)
MAX_EXPOSURE_S = 3600.0  # s, longest accepted exposure
MAX_N0 = 1e12  # m⁻³ mm⁻¹, largest accepted intercept (Marshall–Palmer's is 8000)
MAX_TIRE_WIDTH_M = 5.0  # m (the widest mining-truck tyres are ~1.5 m)
MAX_FILM_DEPTH_M = 1.0  # m; deeper is wading, not a film
RHO_WATER = 1000.0  # kg/m³
RHO_AIR = 1.2  # kg/m³, near sea level at 20 °C
G_M_S2 = 9.81  # m/s², standard gravity
# A clear day's aerial perspective: β = 3.912 / 40 km (meteorological visibility 40 km at 2% contrast).
CLEAR_AIR_EXTINCTION_PER_M = 3.912 / 40000.0  # 1/m

# Gunn & Kinzer (1949) Table 2, stagnant air at sea level (copy in /work/shared/reference/gunn_kinzer.csv).
GUNN_KINZER_D_MM = np.array([
    0.078, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 2.2, 2.4, 2.6, 2.8,
    3.0, 3.2, 3.4, 3.6, 3.8, 4.0, 4.2, 4.4, 4.6, 4.8, 5.0, 5.2, 5.4, 5.6, 5.8,
])
GUNN_KINZER_V_M_S = np.array([
    0.18, 0.27, 0.72, 1.17, 1.62, 2.06, 2.47, 2.87, 3.27, 3.67, 4.03, 4.64, 5.17, 5.65, 6.09, 6.49, 6.90,
    7.27, 7.57, 7.82, 8.06, 8.26, 8.44, 8.60, 8.72, 8.83, 8.92, 8.98, 9.03, 9.07, 9.09, 9.12, 9.14, 9.16,
    9.17,
])

# Six-band intensity scale (DESIGN §3): name, lower bound (inclusive), upper bound (exclusive), mm/h.
RAIN_CATEGORIES = (
    ("very light", 0.0, 0.25),
    ("light", 0.25, 1.0),
    ("moderate", 1.0, 4.0),
    ("heavy", 4.0, 16.0),
    ("very heavy", 16.0, 50.0),
    ("extreme", 50.0, math.inf),
)

# Named presets (mm/h). Each lies inside the band of the same name; light…very heavy sit at the geometric
# centre of their band (√(0.25·1) = 0.5, 2, 8, √(16·50) ≈ 28), drizzle inside "very light", extreme a
# cloudburst.
RAIN_PRESETS = {
    "drizzle": 0.2,
    "light": 0.5,
    "moderate": 2.0,
    "heavy": 8.0,
    "very_heavy": 28.0,
    "extreme": 80.0,
}

# --- validation ------------------------------------------------------------------------------------------


def _check_rate(rate_mm_h, name: str = "rate_mm_h", positive: bool = False):
    return checks.array(name, rate_mm_h, 0.0, R_MAX_MM_H, "mm/h", lo_open=positive)


def _out(x, *inputs):
    """A Python float when every input was a scalar, else the array."""
    if all(np.ndim(i) == 0 for i in inputs):
        return float(x)
    return x


def _out_shaped(x: np.ndarray):
    """For functions taking 3-vectors: a Python float when the broadcast batch shape is ()."""
    return float(x) if np.ndim(x) == 0 else x


# --- drop-size distribution ------------------------------------------------------------------------------


def mp_slope_per_mm(rate_mm_h):
    """Marshall–Palmer slope Λ = 4.1·R^−0.21 in mm⁻¹ (R in mm/h, > 0; Λ → ∞ as R → 0)."""
    r = _check_rate(rate_mm_h, positive=True)
    return _out(4.1 * r ** -0.21, rate_mm_h)


def marshall_palmer(d_mm, rate_mm_h):
    """Marshall–Palmer drop-size distribution N(D) in m⁻³ mm⁻¹ (drops per m³ of air per mm of diameter).

    d_mm: drop diameter in mm (≥ 0); rate_mm_h: rain rate in mm/h, in [0, 500]. R = 0 gives 0 (no rain).
    This is the published formula with N0 = 8000 m⁻³ mm⁻¹ (the effects use ``effective_n0``; see the module
    docstring).
    """
    d = checks.array("d_mm", d_mm, 0.0, math.inf, "mm")
    r = _check_rate(rate_mm_h)
    d, r = np.broadcast_arrays(d, r)
    out = np.zeros(d.shape)
    wet = r > 0
    with np.errstate(over="ignore"):  # Λ·D overflows for D near the float limit: e^(−inf) is the right 0
        out[wet] = N0_MP * np.exp(-4.1 * r[wet] ** -0.21 * d[wet])
    return _out(out, d_mm, rate_mm_h)


def rain_category(rate_mm_h):
    """Name of the six-band intensity class of a rain rate in mm/h (DESIGN §3), "none" for exactly 0.

    Bands include their lower bound: very light < 0.25 ≤ light < 1 ≤ moderate < 4 ≤ heavy < 16 ≤ very heavy
    < 50 ≤ extreme. Returns a str for a scalar, an array of str otherwise.
    """
    r = _check_rate(rate_mm_h)
    names = np.array(["none"] + [c[0] for c in RAIN_CATEGORIES], dtype=object)
    edges = np.array([c[2] for c in RAIN_CATEGORIES[:-1]])
    idx = np.where(r > 0, 1 + np.searchsorted(edges, r, side="right"), 0)
    out = names[idx]
    return str(out) if np.ndim(rate_mm_h) == 0 else out


def preset_rate(name: str) -> float:
    """Rain rate in mm/h of a named preset (drizzle, light, moderate, heavy, very_heavy, extreme).

    Spaces and hyphens stand for underscores ("very heavy"). Unknown names raise ValueError listing them.
    """
    key = str(name).strip().lower().replace(" ", "_").replace("-", "_")
    if key not in RAIN_PRESETS:
        raise ValueError(f"unknown rain preset {name!r}; choose from {', '.join(RAIN_PRESETS)}")
    return RAIN_PRESETS[key]


# --- terminal velocity -----------------------------------------------------------------------------------


def _pchip_slopes(x: np.ndarray, y: np.ndarray, d_first: float, d_last: float) -> np.ndarray:
    """Fritsch–Butland slopes (weighted harmonic mean of the secants): the cubic Hermite stays monotone."""
    h = np.diff(x)
    delta = np.diff(y) / h
    d = np.empty_like(y)
    w1 = 2 * h[1:] + h[:-1]
    w2 = h[1:] + 2 * h[:-1]
    same_sign = delta[:-1] * delta[1:] > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        harm = (w1 + w2) / (w1 / delta[:-1] + w2 / delta[1:])
    d[1:-1] = np.where(same_sign, harm, 0.0)
    d[0], d[-1] = d_first, d_last
    return d


def _hermite(x: np.ndarray, y: np.ndarray, d: np.ndarray, xq: np.ndarray) -> np.ndarray:
    """Evaluate the cubic Hermite interpolant (knots x, values y, slopes d) at xq inside [x0, xn]."""
    k = np.clip(np.searchsorted(x, xq, side="right") - 1, 0, len(x) - 2)
    h = x[k + 1] - x[k]
    t = (xq - x[k]) / h
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * y[k] + (t3 - 2 * t2 + t) * h * d[k]
            + (-2 * t3 + 3 * t2) * y[k + 1] + (t3 - t2) * h * d[k + 1])


def _gk_model(x: np.ndarray, y: np.ndarray):
    """Slopes for a G&K-style table: Stokes slope 2v/D at the first knot, 0 at the last (C¹ joins)."""
    return _pchip_slopes(x, y, 2.0 * y[0] / x[0], 0.0)


_GK_SLOPES = _gk_model(GUNN_KINZER_D_MM, GUNN_KINZER_V_M_S)


def _terminal_velocity_from(x: np.ndarray, y: np.ndarray, slopes: np.ndarray, d: np.ndarray) -> np.ndarray:
    inside = _hermite(x, y, slopes, np.clip(d, x[0], x[-1]))
    stokes = y[0] * (np.minimum(d, x[0]) / x[0]) ** 2  # only used below x[0]; the clip avoids overflow
    return np.where(d < x[0], stokes, np.where(d > x[-1], y[-1], inside))


def terminal_velocity(d_mm):
    """Terminal fall speed in m/s of a water drop of diameter d_mm (mm, ≥ 0) in still air at sea level.

    Monotone cubic through Gunn & Kinzer's measurements (exact at every tabulated point), Stokes' v ∝ D² below
    0.078 mm, constant 9.17 m/s above 5.8 mm (break-up). C¹, non-decreasing, 0 at D = 0.
    """
    d = checks.array("d_mm", d_mm, 0.0, math.inf, "mm")
    return _out(_terminal_velocity_from(GUNN_KINZER_D_MM, GUNN_KINZER_V_M_S, _GK_SLOPES, d), d_mm)


def terminal_velocity_leave_one_out() -> np.ndarray:
    """Relative error of the interpolant at each interior G&K point when that point is left out of the table.

    An honest estimate of the error *between* tabulated points (the full model is exact at them); the spacing
    doubles locally, so the true error between points is smaller. Returns an array aligned with
    GUNN_KINZER_D_MM; the two end points (which fix the Stokes and break-up joins) are NaN.
    """
    x, y = GUNN_KINZER_D_MM, GUNN_KINZER_V_M_S
    err = np.full(len(x), np.nan)
    for i in range(1, len(x) - 1):
        xs, ys = np.delete(x, i), np.delete(y, i)
        v = _terminal_velocity_from(xs, ys, _gk_model(xs, ys), np.array([x[i]]))[0]
        err[i] = v / y[i] - 1.0
    return err


def atlas_terminal_velocity(d_mm):
    """Atlas et al. (1973) fit v = 9.65 − 10.3·e^(−0.6·D) m/s (D in mm), clipped at 0; for comparison only."""
    d = checks.array("d_mm", d_mm, 0.0, math.inf, "mm")
    return _out(np.maximum(9.65 - 10.3 * np.exp(-0.6 * d), 0.0), d_mm)


# --- quadrature over the drop-size distribution -----------------------------------------------------------


@lru_cache(maxsize=8)
def _quadrature(d_lo: float, d_hi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes (mm), weights (mm) and fall speeds (m/s) on [d_lo, d_hi].

    Panels break at every G&K knot, so each panel integrates a cubic × exponential: 8 points per panel are
    accurate to ~1e-12 relative. d_hi = inf is cut at 30 mm, where exp(−Λ·D) < 1e-14 even at 500 mm/h.
    """
    hi = 30.0 if math.isinf(d_hi) else d_hi
    knots = np.concatenate([[d_lo], GUNN_KINZER_D_MM[(GUNN_KINZER_D_MM > d_lo) & (GUNN_KINZER_D_MM < hi)]])
    if hi > GUNN_KINZER_D_MM[-1]:
        tail = np.arange(GUNN_KINZER_D_MM[-1] + 1.0, hi, 1.0) if hi > 7 else np.array([])
        knots = np.concatenate([knots, tail])
    knots = np.concatenate([knots, [hi]])
    gx, gw = np.polynomial.legendre.leggauss(8)
    a, b = knots[:-1, None], knots[1:, None]
    nodes = (0.5 * (b - a) * gx + 0.5 * (a + b)).ravel()
    weights = (0.5 * (b - a) * gw).ravel()
    speeds = _terminal_velocity_from(GUNN_KINZER_D_MM, GUNN_KINZER_V_M_S, _GK_SLOPES, nodes)
    for arr in (nodes, weights, speeds):
        arr.flags.writeable = False
    return nodes, weights, speeds


def _mp_shape(r: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """exp(−Λ(R)·D) at the nodes, shape r.shape + nodes.shape; 0 for R = 0."""
    with np.errstate(divide="ignore"):
        lam = np.where(r > 0, 4.1 * np.where(r > 0, r, 1.0) ** -0.21, np.inf)
    return np.exp(-lam[..., None] * nodes)


# mm³ · m⁻³ · m/s → mm/h: (π/6)·D³ [mm³] · 1e-9 [m³/mm³] · [m/s] · 1000 [mm/m] · 3600 [s/h]
_VOLUME_FLUX_TO_MM_H = math.pi / 6.0 * 1e-9 * 1000.0 * 3600.0


def _cube_moment_tail(lam: np.ndarray, a: float, b: float) -> np.ndarray:
    """∫_a^b D³·e^(−Λ·D) dD in mm⁴ for Λ > 0 (finite, may be huge) and a ≤ b (b may be inf), closed form.

    The antiderivative is −e^(−Λ·D)·(D³/Λ + 3D²/Λ² + 6D/Λ³ + 6/Λ⁴). Λ ≥ Λ(500 mm/h) ≈ 1.1 mm⁻¹, so above
    1000 mm e^(−Λ·D) is 0 in float64: the limits are cut there, which keeps D³ finite and the result exact.
    """
    def antiderivative(d: float) -> np.ndarray:
        d = min(d, 1000.0)
        return -np.exp(-lam * d) * (d**3 / lam + 3.0 * d**2 / lam**2 + 6.0 * d / lam**3 + 6.0 / lam**4)
    return np.maximum(antiderivative(b) - antiderivative(a), 0.0)


def implied_rate_mm_h(rate_mm_h, n0=N0_MP, d_min_mm=D_MIN_MM, d_max_mm=D_MAX_MM):
    """Rain rate in mm/h carried by a Marshall–Palmer distribution, ∫N(D)·v(D)·(π/6)·D³ dD on [d_min, d_max].

    rate_mm_h sets Λ (mm/h, [0, 500]); n0 the intercept in m⁻³ mm⁻¹ ([0, MAX_N0], default Marshall–Palmer's
    8000); d_min_mm/d_max_mm the diameter range in mm (d_max_mm may be inf). With ``n0=effective_n0(R)`` and
    the default range it returns R itself; with the default n0 it measures Marshall–Palmer's self-consistency.
    Below the last Gunn & Kinzer point (5.8 mm) the integral is Gauss–Legendre quadrature; above it the fall
    speed is constant, so that part is exact in closed form for any upper limit. R = 0 carries no water.
    """
    r = _check_rate(rate_mm_h)
    n0a = checks.array("n0", n0, 0.0, MAX_N0, "m⁻³ mm⁻¹")
    lo = float(checks.array("d_min_mm", d_min_mm, 0.0, math.inf, "mm"))
    if isinstance(d_max_mm, float | int) and d_max_mm == math.inf:
        hi = math.inf
    else:
        hi = float(checks.array("d_max_mm", d_max_mm, lo, math.inf, "mm"))
    wet = r > 0
    safe = np.where(wet, r, 1.0)  # R = 0 (Λ = ∞) is masked below: e^(−∞·0) would be NaN at a node at D = 0
    integral = np.zeros(np.shape(r))
    d_break = float(GUNN_KINZER_D_MM[-1])
    if lo < d_break:
        nodes, weights, speeds = _quadrature(lo, min(hi, d_break))
        integral = integral + (_mp_shape(safe, nodes) * (speeds * nodes**3 * weights)).sum(axis=-1)
    if hi > d_break:
        lam = 4.1 * safe**-0.21
        integral = integral + float(GUNN_KINZER_V_M_S[-1]) * _cube_moment_tail(lam, max(lo, d_break), hi)
    return _out(n0a * np.where(wet, integral, 0.0) * _VOLUME_FLUX_TO_MM_H, rate_mm_h, n0)


def effective_n0(rate_mm_h):
    """Intercept N0 in m⁻³ mm⁻¹ that makes the drops in [D_MIN_MM, D_MAX_MM] carry exactly R (mm/h, [0, 500]).

    N0_eff = 8000 · R / implied_rate_mm_h(R); 0 when R = 0. This is the distribution every effect uses.
    """
    r = _check_rate(rate_mm_h)
    implied = np.asarray(implied_rate_mm_h(r))
    n0 = np.where(r > 0, N0_MP * r / np.where(implied > 0, implied, 1.0), 0.0)
    return _out(n0, rate_mm_h)


def _effective_moments(r: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """N_eff(D) at the nodes for rates r: shape r.shape + nodes.shape, m⁻³ mm⁻¹."""
    return np.asarray(effective_n0(r))[..., None] * _mp_shape(r, nodes)


def number_density_per_m3(rate_mm_h):
    """Drops per m³ of air with diameter in [D_MIN_MM, D_MAX_MM], for a rain rate in mm/h ([0, 500]).

    Closed form of ∫N_eff(D) dD = N0_eff/Λ·(e^(−Λ·D_min) − e^(−Λ·D_max)).
    """
    r = _check_rate(rate_mm_h)
    n0 = np.asarray(effective_n0(r))
    safe = np.where(r > 0, r, 1.0)
    lam = 4.1 * safe**-0.21
    out = np.where(r > 0, n0 / lam * (np.exp(-lam * D_MIN_MM) - np.exp(-lam * D_MAX_MM)), 0.0)
    return _out(out, rate_mm_h)


def flux_horizontal_per_m2_s(rate_mm_h):
    """Drops hitting a still horizontal surface per m² per second, ∫N_eff(D)·v(D) dD; R in mm/h, [0, 500]."""
    r = _check_rate(rate_mm_h)
    nodes, weights, speeds = _quadrature(D_MIN_MM, D_MAX_MM)
    return _out((_effective_moments(r, nodes) * (speeds * weights)).sum(axis=-1), rate_mm_h)


def flux_on_surface_per_s(rate_mm_h, area_m2, normal, surface_velocity_m_s=(0.0, 0.0, 0.0), wind_m_s=None):
    """Drops per second hitting one face of a flat surface (e.g. a windshield) moving through the rain.

    rate_mm_h: rain rate in mm/h ([0, 500]); area_m2: face area in m² ([0, MAX_AREA_M2]); normal: outward
    normal of the exposed face, (..., 3), any finite non-zero length (+Y up, world frame); surface_velocity_m_s:
    the surface's velocity in m/s, (..., 3); wind_m_s: horizontal wind velocity in m/s, (..., 3), default none
    (velocity components within ±MAX_SPEED_M_S).

    A drop of diameter D moves with the wind horizontally and falls at v(D): v_rain = wind − v(D)·ŷ. Relative
    to the surface it moves at u = v_rain − v_surface and strikes the face when u·n̂ < 0, so the count is
    area · ∫N_eff(D)·max(0, −u(D)·n̂) dD. Drops hitting the back face are not counted (pass −normal for them).
    Inputs broadcast; the result has their common batch shape.
    """
    r = _check_rate(rate_mm_h)
    area = checks.array("area_m2", area_m2, 0.0, MAX_AREA_M2, "m²")
    n = checks.vec3("normal", normal, "any length")
    vs = checks.vec3("surface_velocity_m_s", surface_velocity_m_s, max_abs=MAX_SPEED_M_S)
    w = checks.vec3("wind_m_s", (0.0, 0.0, 0.0) if wind_m_s is None else wind_m_s, max_abs=MAX_SPEED_M_S)
    # Scale by the largest component before taking the length: |n|² overflows above ~1e154 (and underflows
    # below ~1e-162), which would turn a valid normal into 0 or 0/0.
    biggest = np.abs(n).max(axis=-1, keepdims=True)
    if (biggest == 0).any():
        raise ValueError("normal must be a non-zero 3-vector")
    n = n / biggest
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    a = ((w - vs) * n).sum(axis=-1)  # the D-independent part of u·n̂ (m/s)
    ny = n[..., 1]
    r, area, a, ny = np.broadcast_arrays(r, area, a, ny)
    nodes, weights, speeds = _quadrature(D_MIN_MM, D_MAX_MM)
    closing = np.maximum(speeds * ny[..., None] - a[..., None], 0.0)  # −u·n̂ for each D (m/s)
    out = area * (_effective_moments(r, nodes) * closing * weights).sum(axis=-1)
    return _out_shaped(out)


def liquid_water_content_g_m3(rate_mm_h):
    """Liquid water content of the air in g/m³ (∫N_eff(D)·(π/6)·D³ dD), R in mm/h ([0, 500]).

    For reference, untruncated Marshall–Palmer gives 0.089·R^0.84 g/m³; the renormalised distribution is
    ~10 % lower because its N0 is scaled down to carry exactly R.
    """
    r = _check_rate(rate_mm_h)
    nodes, weights, _ = _quadrature(D_MIN_MM, D_MAX_MM)
    mm3_per_m3 = (_effective_moments(r, nodes) * (math.pi / 6.0 * nodes**3 * weights)).sum(axis=-1)
    return _out(mm3_per_m3 * 1e-3, rate_mm_h)  # 1 mm³/m³ = 1e-9 m³/m³ = 1e-3 g/m³


def mean_streak_length_m(rate_mm_h, exposure_s, camera_velocity_m_s=(0.0, 0.0, 0.0),
                         wind_m_s=(0.0, 0.0, 0.0)):
    """Mean length in m of the streak a drop draws during an exposure, averaged over the drops in the air.

    rate_mm_h: mm/h ([0, 500]); exposure_s: shutter or retinal persistence time in s ([0, MAX_EXPOSURE_S],
    ~0.06–0.2 s for the eye); camera_velocity_m_s and wind_m_s: (..., 3) in m/s (world frame, +Y up; components
    within ±MAX_SPEED_M_S).

    A drop of diameter D moves at u(D) = wind − v(D)·ŷ − v_camera relative to the camera, so its streak is
    |u(D)|·exposure long (in world metres, before projection). This returns the number-weighted mean,
    exposure · ∫N_eff(D)·|u(D)| dD / ∫N_eff(D) dD over [D_MIN_MM, D_MAX_MM]. At R = 0 it is the limit
    R → 0, where every drop has D_MIN_MM (a streak length is a property of a drop, not of how many there are).
    """
    r = _check_rate(rate_mm_h)
    t = checks.array("exposure_s", exposure_s, 0.0, MAX_EXPOSURE_S, "s")
    c = (checks.vec3("wind_m_s", wind_m_s, max_abs=MAX_SPEED_M_S)
         - checks.vec3("camera_velocity_m_s", camera_velocity_m_s, max_abs=MAX_SPEED_M_S))
    r, t, cx, cy, cz = np.broadcast_arrays(r, t, c[..., 0], c[..., 1], c[..., 2])
    nodes, weights, speeds = _quadrature(D_MIN_MM, D_MAX_MM)
    speed = np.sqrt(cx[..., None] ** 2 + cz[..., None] ** 2 + (cy[..., None] - speeds) ** 2)
    # Weights relative to the smallest node, e^(−Λ·(D − D₀)): the mean is unchanged, and at a tiny rate
    # (Λ ≳ 7000 mm⁻¹) the first weight stays 1 where e^(−Λ·D) would underflow at every node (0/0).
    safe = np.where(r > 0, r, 1.0)
    shape = np.exp(-(4.1 * safe[..., None] ** -0.21) * (nodes - nodes[0])) * weights
    mean = (shape * speed).sum(axis=-1) / shape.sum(axis=-1)
    v_min = float(terminal_velocity(D_MIN_MM))
    at_dmin = np.sqrt(cx**2 + cz**2 + (cy - v_min) ** 2)
    out = t * np.where(r > 0, mean, at_dmin)
    return _out_shaped(out)


def rain_extinction_per_km(rate_mm_h):
    """Extinction coefficient of rain in km⁻¹, β = 0.312·R^0.67 (Weber et al. 2015), R in mm/h ([0, 500]).

    Meteorological visibility is 3.912/β km. Geometric optics on Marshall–Palmer gives 0.365·R^0.63 km⁻¹;
    the two agree within ~20 % from 1 to 50 mm/h.
    """
    r = _check_rate(rate_mm_h)
    return _out(0.312 * r**0.67, rate_mm_h)


def splash_water_flux(speed_m_s, tire_width_m, film_depth_m):
    """Water a tyre meets per second in kg/s: M_w = v·b·WFD·ρ_w (Flintsch et al. 2012).

    speed_m_s: vehicle speed in m/s ([0, MAX_SPEED_M_S]); tire_width_m: tyre width b in m ([0, 5]);
    film_depth_m: water film depth under the tyre in m ([0, 1]; puddles are ≤ 0.01 m). ρ_w = 1000 kg/m³.
    """
    v = checks.array("speed_m_s", speed_m_s, 0.0, MAX_SPEED_M_S, "m/s")
    b = checks.array("tire_width_m", tire_width_m, 0.0, MAX_TIRE_WIDTH_M, "m")
    h = checks.array("film_depth_m", film_depth_m, 0.0, MAX_FILM_DEPTH_M, "m")
    return _out(v * b * h * RHO_WATER, speed_m_s, tire_width_m, film_depth_m)


# --- sampling --------------------------------------------------------------------------------------------


def drop_diameter_cdf(d_mm, rate_mm_h):
    """CDF of the drop diameter (d_mm in mm) under the distribution truncated to [D_MIN_MM, D_MAX_MM].

    rate_mm_h in (0, 500] mm/h. 0 below D_MIN_MM, 1 above D_MAX_MM. This is the law that
    ``sample_drop_diameters`` draws from.
    """
    d = checks.array("d_mm", d_mm, 0.0, math.inf, "mm")
    r = _check_rate(rate_mm_h, positive=True)
    lam = 4.1 * r**-0.21
    x = np.clip(d, D_MIN_MM, D_MAX_MM) - D_MIN_MM
    out = np.expm1(-lam * x) / np.expm1(-lam * (D_MAX_MM - D_MIN_MM))
    return _out(np.clip(out, 0.0, 1.0), d_mm, rate_mm_h)


def sample_drop_diameters(rate_mm_h, n, rng) -> np.ndarray:
    """Draw n drop diameters in mm from the Marshall–Palmer distribution truncated to [D_MIN_MM, D_MAX_MM].

    rate_mm_h: rain rate in mm/h, in (0, 500] (there are no drops to draw at 0); n: count (int ≥ 0);
    rng: np.random.Generator (or an int seed). Exact inverse-CDF sampling of the truncated exponential, one
    uniform per drop: D = D_min − ln(1 − u·(1 − e^(−Λ·(D_max − D_min))))/Λ. Returns float64, shape (n,).
    """
    r = float(_check_rate(rate_mm_h, positive=True)) if np.ndim(rate_mm_h) == 0 else None
    if r is None:
        raise ValueError(f"rate_mm_h must be a scalar in (0, 500] mm/h, got shape {np.shape(rate_mm_h)}")
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 0:
        raise ValueError(f"n must be an int >= 0, got {n!r}")
    if not isinstance(rng, np.random.Generator):
        if isinstance(rng, bool) or not isinstance(rng, int | np.integer):
            raise ValueError(f"rng must be a numpy.random.Generator or an int seed, got {rng!r}")
        rng = np.random.default_rng(int(rng))
    lam = 4.1 * r**-0.21
    u = rng.random(int(n))
    # −expm1(−Λ·W) = 1 − e^(−Λ·W); log1p keeps the small-u end exact.
    d = D_MIN_MM - np.log1p(u * np.expm1(-lam * (D_MAX_MM - D_MIN_MM))) / lam
    return np.clip(d, D_MIN_MM, D_MAX_MM)


def ks_distance(samples_mm, rate_mm_h) -> float:
    """Kolmogorov–Smirnov distance sup|F_n − F| between drop diameters (mm) and the truncated law at R (mm/h).

    For n exact samples its mean is ≈ 0.87/√n; above 1.95/√n happens with probability < 0.1 %.
    """
    x = np.sort(checks.array("samples_mm", samples_mm, 0.0, math.inf, "mm").ravel())
    if x.size == 0:
        raise ValueError("samples_mm must not be empty")
    f = np.asarray(drop_diameter_cdf(x, rate_mm_h))
    i = np.arange(1, x.size + 1)
    return float(max((i / x.size - f).max(), (f - (i - 1) / x.size).max()))
