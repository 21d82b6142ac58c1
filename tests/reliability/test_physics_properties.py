"""Property-based tests of the public physics functions (issue 18): random valid inputs give finite outputs in
their documented range; NaN, infinite, negative or too-large inputs raise ValueError naming the argument.

Huge *finite* inputs (up to the largest float) once returned inf or NaN (issue 18); the tests at the end state the
contract — a finite result, or a ValueError naming an argument — with the inputs that used to fail as explicit
``@example``s, so they are checked the same way every run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from rain_core import physics as P

R_MAX = P.R_MAX_MM_H
F_MAX = float(np.finfo(np.float64).max)

rates = st.floats(0.0, R_MAX)
positive_rates = st.floats(0.0, R_MAX, exclude_min=True)
diameters = st.floats(0.0, F_MAX)  # any finite diameter ≥ 0
moderate = st.floats(0.0, P.MAX_AREA_M2)
vectors = st.tuples(*[st.floats(-P.MAX_SPEED_M_S, P.MAX_SPEED_M_S)] * 3)
any_vectors = st.tuples(*[st.floats(-F_MAX, F_MAX)] * 3)
normals = st.tuples(*[st.floats(-1e3, 1e3)] * 3).filter(lambda n: math.hypot(*n) > 1e-6)
BAD_NUMBERS = st.sampled_from([math.nan, math.inf, -math.inf]) | st.floats(max_value=-1e-300)


def _not_a_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return True
    return False


# Numeric strings ("1", ["0"]) are refused too: see test_numeric_strings_are_refused.
NON_NUMERIC_TEXT = st.text(max_size=5).filter(_not_a_number)
WRONG_TYPES = NON_NUMERIC_TEXT | st.lists(NON_NUMERIC_TEXT, min_size=1, max_size=2) | st.dictionaries(
    st.text(max_size=2), st.integers(), min_size=1, max_size=2)


def finite(x) -> bool:
    return bool(np.all(np.isfinite(np.asarray(x, dtype=np.float64))))


def finite_or_value_error(fn, *args, **kwargs) -> None:
    """The contract at any finite input: a finite result, or a ValueError (naming an argument)."""
    try:
        out = fn(*args, **kwargs)
    except ValueError as exc:
        assert any(name in str(exc) for name in fn.__code__.co_varnames[:fn.__code__.co_argcount]), str(exc)
        return
    with np.errstate(all="ignore"):
        assert finite(out), f"{fn.__name__}{args} → {out}"
    assert np.all(np.asarray(out) >= 0), f"{fn.__name__}{args} → {out}"


# --- valid inputs: finite, in range ---------------------------------------------------------------------


@given(r=positive_rates)
def test_mp_slope(r):
    lam = P.mp_slope_per_mm(r)
    assert math.isfinite(lam) and lam > 0


@given(d=diameters, r=rates)
def test_marshall_palmer(d, r):
    n = P.marshall_palmer(d, r)
    assert math.isfinite(n) and 0 <= n <= P.N0_MP


@given(r=rates)
def test_rain_category_and_rate_functions(r):
    assert isinstance(P.rain_category(r), str)
    for fn in (P.effective_n0, P.number_density_per_m3, P.flux_horizontal_per_m2_s, P.liquid_water_content_g_m3,
               P.rain_extinction_per_km, P.implied_rate_mm_h):
        out = fn(r)
        assert math.isfinite(out) and out >= 0, (fn.__name__, r, out)
    if r >= 1e-6:  # below, exp(−Λ·D) underflows and the renormalisation is 0/0-guarded to 0
        assert P.implied_rate_mm_h(r, n0=P.effective_n0(r)) == pytest.approx(r, rel=1e-9)


@given(rs=st.lists(rates, min_size=1, max_size=6))
def test_rate_functions_vectorise(rs):
    arr = np.array(rs)
    for fn in (P.effective_n0, P.number_density_per_m3, P.flux_horizontal_per_m2_s, P.rain_extinction_per_km):
        out = fn(arr)
        assert out.shape == arr.shape and finite(out) and np.all(out >= 0)
        np.testing.assert_allclose(out, [fn(r) for r in rs], rtol=1e-12)


@given(d=diameters)
def test_terminal_velocities(d):
    v = P.terminal_velocity(d)
    assert math.isfinite(v) and 0 <= v <= P.GUNN_KINZER_V_M_S[-1] + 1e-12
    a = P.atlas_terminal_velocity(d)
    assert math.isfinite(a) and 0 <= a <= 9.65


@given(r=rates, n0=st.floats(0.0, P.MAX_N0), lo=st.floats(0.0, P.D_MAX_MM), width=st.floats(0.0, 20.0),
       open_top=st.booleans())
def test_implied_rate_moderate_inputs(r, n0, lo, width, open_top):
    out = P.implied_rate_mm_h(r, n0=n0, d_min_mm=lo, d_max_mm=math.inf if open_top else lo + width)
    assert math.isfinite(out) and out >= 0


@given(r=rates, area=moderate, normal=normals, velocity=vectors, wind=vectors)
def test_flux_on_surface_moderate_inputs(r, area, normal, velocity, wind):
    out = P.flux_on_surface_per_s(r, area, normal, velocity, wind)
    assert math.isfinite(out) and out >= 0
    scaled = P.flux_on_surface_per_s(r, area, tuple(3.0 * c for c in normal), velocity, wind)
    assert scaled == pytest.approx(out, rel=1e-9, abs=1e-300)  # any length of normal


@given(r=rates, exposure=st.floats(0.0, P.MAX_EXPOSURE_S), camera=vectors, wind=vectors)
def test_mean_streak_length_moderate_inputs(r, exposure, camera, wind):
    out = P.mean_streak_length_m(r, exposure, camera, wind)
    assert math.isfinite(out) and out >= 0


@given(v=st.floats(0.0, P.MAX_SPEED_M_S), b=st.floats(0.0, P.MAX_TIRE_WIDTH_M), h=st.floats(0.0, P.MAX_FILM_DEPTH_M))
def test_splash_water_flux_moderate_inputs(v, b, h):
    out = P.splash_water_flux(v, b, h)
    assert math.isfinite(out) and out >= 0


@given(d=diameters, r=positive_rates)
def test_drop_diameter_cdf(d, r):
    c = P.drop_diameter_cdf(d, r)
    assert 0.0 <= c <= 1.0


@given(r=positive_rates, n=st.integers(0, 200), seed=st.integers(0, 2**32 - 1))
def test_sampled_diameters_are_in_range(r, n, seed):
    d = P.sample_drop_diameters(r, n, seed)
    assert d.shape == (n,) and np.all((d >= P.D_MIN_MM) & (d <= P.D_MAX_MM))
    if n:
        assert 0.0 <= P.ks_distance(d, r) <= 1.0


# --- invalid inputs: ValueError naming the argument --------------------------------------------------------

VALID_ARGS = {
    P.mp_slope_per_mm: {"rate_mm_h": 5.0},
    P.marshall_palmer: {"d_mm": 1.0, "rate_mm_h": 5.0},
    P.rain_category: {"rate_mm_h": 5.0},
    P.terminal_velocity: {"d_mm": 1.0},
    P.atlas_terminal_velocity: {"d_mm": 1.0},
    P.implied_rate_mm_h: {"rate_mm_h": 5.0, "n0": 8000.0, "d_min_mm": 0.1, "d_max_mm": 6.0},
    P.effective_n0: {"rate_mm_h": 5.0},
    P.number_density_per_m3: {"rate_mm_h": 5.0},
    P.flux_horizontal_per_m2_s: {"rate_mm_h": 5.0},
    P.flux_on_surface_per_s: {"rate_mm_h": 5.0, "area_m2": 1.0, "normal": (0.0, 1.0, 0.0),
                              "surface_velocity_m_s": (0.0, 0.0, 10.0), "wind_m_s": (1.0, 0.0, 0.0)},
    P.liquid_water_content_g_m3: {"rate_mm_h": 5.0},
    P.mean_streak_length_m: {"rate_mm_h": 5.0, "exposure_s": 0.02, "camera_velocity_m_s": (0.0, 0.0, 10.0),
                             "wind_m_s": (1.0, 0.0, 0.0)},
    P.rain_extinction_per_km: {"rate_mm_h": 5.0},
    P.splash_water_flux: {"speed_m_s": 10.0, "tire_width_m": 0.2, "film_depth_m": 0.001},
    P.drop_diameter_cdf: {"d_mm": 1.0, "rate_mm_h": 5.0},
    P.ks_distance: {"samples_mm": [1.0, 2.0], "rate_mm_h": 5.0},
}
CASES = [(fn, arg) for fn, kwargs in VALID_ARGS.items() for arg in kwargs]
VECTOR_ARGS = {"normal", "surface_velocity_m_s", "wind_m_s", "camera_velocity_m_s"}


def test_valid_args_table_is_valid_and_complete():
    public = {name for name in dir(P) if not name.startswith("_") and callable(getattr(P, name))
              and getattr(getattr(P, name), "__module__", None) == P.__name__}
    covered = {fn.__name__ for fn in VALID_ARGS} | {"preset_rate", "sample_drop_diameters",
                                                    "terminal_velocity_leave_one_out"}
    assert public <= covered, public - covered
    for fn, kwargs in VALID_ARGS.items():
        out = fn(**kwargs)
        assert isinstance(out, str) or finite(out)


def bad_values(fn, arg) -> st.SearchStrategy:
    if arg in VECTOR_ARGS:
        bad = st.sampled_from([math.nan, math.inf, -math.inf])
        vectors_with_a_bad_entry = st.tuples(bad, st.floats(-1.0, 1.0), st.floats(-1.0, 1.0)).flatmap(st.permutations)
        return vectors_with_a_bad_entry | WRONG_TYPES | st.just((1.0, 2.0))  # (None is the default wind)
    options = [BAD_NUMBERS, WRONG_TYPES, st.none()]
    if "rate" in arg:
        options.append(st.floats(min_value=R_MAX, exclude_min=True, allow_infinity=False))
    return st.one_of(options)


@pytest.mark.parametrize("fn, arg", CASES, ids=[f"{fn.__name__}-{arg}" for fn, arg in CASES])
@given(data=st.data())
def test_invalid_inputs_raise_value_error_naming_the_argument(fn, arg, data):
    value = data.draw(bad_values(fn, arg), label=arg)
    if arg == "d_max_mm" and value == math.inf:
        return  # d_max_mm = inf is documented as allowed
    kwargs = dict(VALID_ARGS[fn], **{arg: value})
    with pytest.raises(ValueError) as exc:
        fn(**kwargs)
    assert arg in str(exc.value), str(exc.value)


@pytest.mark.parametrize("value", [math.nan, math.inf, -1.0, 0.0, 500.5, "heavy", None])
def test_sample_drop_diameters_refuses_bad_rates(value):
    with pytest.raises(ValueError, match="rate_mm_h"):
        P.sample_drop_diameters(value, 5, 0)


@pytest.mark.parametrize("n", [-1, 2.0, True, "3", None])
def test_sample_drop_diameters_refuses_bad_counts(n):
    with pytest.raises(ValueError, match="n "):
        P.sample_drop_diameters(5.0, n, 0)


# --- huge finite inputs (issue 18): a finite result or a ValueError naming the argument --------------------


@given(v=diameters, b=diameters, h=diameters)
@example(v=1e308, b=1e308, h=1.0)
@example(v=1e200, b=1e200, h=0.0)
def test_splash_water_flux_any_finite_input(v, b, h):
    finite_or_value_error(P.splash_water_flux, v, b, h)


@given(r=rates, area=diameters, normal=normals, velocity=any_vectors)
@example(r=500.0, area=F_MAX, normal=(0.0, 1.0, 0.0), velocity=(0.0, 0.0, 0.0))
@example(r=500.0, area=1.0, normal=(0.0, 1.0, 0.0), velocity=(0.0, F_MAX, 0.0))
def test_flux_on_surface_any_finite_input(r, area, normal, velocity):
    finite_or_value_error(P.flux_on_surface_per_s, r, area, normal, velocity)


@given(normal=any_vectors.filter(lambda n: math.hypot(*n) > 1e-6) | st.tuples(*[st.floats(-1e-300, 1e-300)] * 3))
@example(normal=(0.0, F_MAX, 0.0))
@example(normal=(F_MAX, F_MAX, -F_MAX))
@example(normal=(0.0, 5e-324, 0.0))
def test_flux_on_surface_any_normal_length(normal):
    """Any finite non-zero normal is a direction: the flux equals that through its unit vector."""
    if not any(normal):
        with pytest.raises(ValueError, match="normal"):
            P.flux_on_surface_per_s(5.0, 1.0, normal)
        return
    n = np.array(normal)
    n = n / np.abs(n).max()
    unit = n / np.linalg.norm(n)
    out = P.flux_on_surface_per_s(5.0, 1.0, normal, (0.0, 0.0, -20.0))
    assert out == pytest.approx(P.flux_on_surface_per_s(5.0, 1.0, unit, (0.0, 0.0, -20.0)), rel=1e-9, abs=1e-300)


@given(r=rates, exposure=diameters, camera=any_vectors)
@example(r=500.0, exposure=F_MAX, camera=(0.0, 0.0, 0.0))
@example(r=5.0, exposure=0.0, camera=(F_MAX, F_MAX, 0.0))
@example(r=0.0, exposure=1.0, camera=(F_MAX, 0.0, 0.0))
@example(r=500.0, exposure=P.MAX_EXPOSURE_S, camera=(P.MAX_SPEED_M_S, -P.MAX_SPEED_M_S, P.MAX_SPEED_M_S))
def test_mean_streak_length_any_finite_input(r, exposure, camera):
    finite_or_value_error(P.mean_streak_length_m, r, exposure, camera)


@given(r=rates, n0=diameters, lo=st.floats(0.0, 1e3), hi=st.just(math.inf) | st.floats(0.0, F_MAX))
@example(r=500.0, n0=F_MAX, lo=0.1, hi=math.inf)
@example(r=500.0, n0=8000.0, lo=40.0, hi=math.inf)
@example(r=500.0, n0=8000.0, lo=0.1, hi=1e12)  # once allocated 7 TiB of quadrature nodes
@example(r=500.0, n0=P.MAX_N0, lo=0.0, hi=F_MAX)
def test_implied_rate_any_finite_input(r, n0, lo, hi):
    finite_or_value_error(P.implied_rate_mm_h, r, n0, lo, max(lo, hi))


def test_implied_rate_tail_is_exact():
    """Above 5.8 mm the closed form agrees with brute-force quadrature, and the tail keeps shrinking."""
    lam = 4.1 * 50.0**-0.21
    d = np.linspace(5.8, 60.0, 2_000_001)
    brute = np.trapezoid(d**3 * np.exp(-lam * d), d) * P.GUNN_KINZER_V_M_S[-1] * 8000.0 * P._VOLUME_FLUX_TO_MM_H
    assert P.implied_rate_mm_h(50.0, 8000.0, 5.8, math.inf) == pytest.approx(brute, rel=1e-9)
    far = [P.implied_rate_mm_h(500.0, 8000.0, lo, math.inf) for lo in (10.0, 20.0, 40.0, 80.0)]
    assert all(a >= b >= 0 for a, b in zip(far, far[1:], strict=False))
    assert far[2] > 0  # drops above 40 mm at 500 mm/h carry almost nothing, but not a negative amount


@given(r=st.floats(0.0, 1e-6, exclude_min=True))
@example(r=3.172481815796753e-32)
@example(r=5e-324)
def test_mean_streak_length_at_tiny_rates(r):
    """As R → 0 every drop is among the smallest, so the streak tends to the smallest drop's (within the
    quadrature's resolution: its first node lies just above D_MIN_MM, where v(D) is steep, ~3 % faster)."""
    out = P.mean_streak_length_m(r, 0.02)
    assert math.isfinite(out)
    assert 0.95 * P.mean_streak_length_m(0.0, 0.02) <= out <= P.mean_streak_length_m(1e-6, 0.02) * (1 + 1e-12)
    if r < 1e-20:  # Λ > 6·10⁴ mm⁻¹: the drops all sit at the smallest size
        assert out == pytest.approx(P.mean_streak_length_m(0.0, 0.02), rel=0.05)


@given(width=st.floats(0.0, 1e-300))
@example(width=0.0)
@example(width=5e-324)
def test_implied_rate_at_a_zero_diameter(width):
    assert P.implied_rate_mm_h(0.0, 8000.0, 0.0, width) == 0.0
    finite_or_value_error(P.implied_rate_mm_h, 1.0, 8000.0, 0.0, width)


@pytest.mark.parametrize("call", [
    lambda: P.terminal_velocity("1"),
    lambda: P.rain_extinction_per_km("5"),
    lambda: P.splash_water_flux(["10"], 0.2, 0.001),
    lambda: P.flux_on_surface_per_s(5.0, "1", (0.0, 1.0, 0.0)),
    lambda: P.flux_on_surface_per_s(5.0, 1.0, ("0", "1", "0")),
    lambda: P.flux_on_surface_per_s(5.0, 1.0, (0.0, 1.0, 0.0), [0.0, b"1", 0.0]),
    lambda: P.sample_drop_diameters("5", 3, 0),
    lambda: P.ks_distance([1.0, "2"], 5.0),
], ids=["terminal_velocity", "rain_extinction_per_km", "splash_water_flux", "flux_on_surface_per_s",
        "normal", "wind_bytes", "sample_drop_diameters", "ks_distance_mixed"])
def test_numeric_strings_are_refused(call):
    with pytest.raises(ValueError, match="must be"):
        call()
