"""rain_core.physics against the published tables, exact closed forms, and its own input validation."""

import io
import math

import numpy as np
import pytest

from rain_core import physics as P

# Copies of /work/shared/reference/*.csv, kept here so the tests do not depend on the shared folder.
MARSHALL_PALMER_CSV = """rate_mm_h,diameter_mm,n_per_m3_mm
2,0.5,1360\n2,1.0,231\n2,1.5,40\n2,2.0,7\n2,2.5,1\n2,3.0,0
5,0.5,1854\n5,1.0,429\n5,1.5,99\n5,2.0,23\n5,2.5,5\n5,3.0,1
10,0.5,2260\n10,1.0,638\n10,1.5,180\n10,2.0,50\n10,2.5,14\n10,3.0,4
"""
GUNN_KINZER_CSV = """diameter_mm,velocity_m_s
0.078,0.18\n0.1,0.27\n0.2,0.72\n0.3,1.17\n0.4,1.62\n0.5,2.06\n0.6,2.47\n0.7,2.87\n0.8,3.27\n0.9,3.67
1.0,4.03\n1.2,4.64\n1.4,5.17\n1.6,5.65\n1.8,6.09\n2.0,6.49\n2.2,6.90\n2.4,7.27\n2.6,7.57\n2.8,7.82
3.0,8.06\n3.2,8.26\n3.4,8.44\n3.6,8.60\n3.8,8.72\n4.0,8.83\n4.2,8.92\n4.4,8.98\n4.6,9.03\n4.8,9.07
5.0,9.09\n5.2,9.12\n5.4,9.14\n5.6,9.16\n5.8,9.17
"""


def _csv(text):
    return np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1, ndmin=2)


# --- drop-size distribution ---


def test_marshall_palmer_reproduces_published_table():
    table = _csv(MARSHALL_PALMER_CSV)
    n = P.marshall_palmer(table[:, 1], table[:, 0])
    # The table is rounded to whole numbers and five cells used a differently rounded Λ: ±1 or 2 %.
    assert np.all((np.abs(n - table[:, 2]) <= 1.0) | (np.abs(n / np.maximum(table[:, 2], 1) - 1) <= 0.02))
    assert P.marshall_palmer(0.0, 3.0) == P.N0_MP


def test_marshall_palmer_broadcasts_and_is_zero_without_rain():
    d = np.linspace(0, 6, 7)
    out = P.marshall_palmer(d[:, None], np.array([0.0, 1.0, 10.0]))
    assert out.shape == (7, 3)
    assert np.all(out[:, 0] == 0.0)
    assert np.all(np.diff(out[:, 1]) < 0)  # fewer large drops
    assert isinstance(P.marshall_palmer(1.0, 1.0), float)


def test_rain_category_bands_and_presets():
    rates = [0.0, 0.1, 0.25, 0.99, 1.0, 3.9, 4.0, 16.0, 49.9, 50.0, 500.0]
    expected = ["none", "very light", "light", "light", "moderate", "moderate", "heavy", "very heavy",
                "very heavy", "extreme", "extreme"]
    assert [P.rain_category(r) for r in rates] == expected
    assert list(P.rain_category(np.array(rates))) == expected
    for name, rate in P.RAIN_PRESETS.items():
        band = "very light" if name == "drizzle" else name.replace("_", " ")
        assert P.rain_category(rate) == band
        assert P.preset_rate(name.replace("_", " ")) == rate
    with pytest.raises(ValueError, match="drizzle"):
        P.preset_rate("monsoon")


# --- terminal velocity ---


def test_terminal_velocity_within_2_percent_of_gunn_kinzer():
    table = _csv(GUNN_KINZER_CSV)
    d, v = table[:, 0], table[:, 1]
    sel = (d >= 0.1) & (d <= 5.8)
    err = P.terminal_velocity(d[sel]) / v[sel] - 1
    assert np.max(np.abs(err)) < 0.02


def test_terminal_velocity_between_points_leave_one_out():
    # Dropping a point doubles the local spacing; the interpolant must still land near it.
    loo = P.terminal_velocity_leave_one_out()
    d = P.GUNN_KINZER_D_MM
    assert np.nanmax(np.abs(loo[d >= 0.2])) < 0.01
    assert np.nanmax(np.abs(loo)) < 0.05


def test_terminal_velocity_monotone_smooth_and_sane_outside():
    d = np.linspace(0.0, 8.0, 160_001)
    v = P.terminal_velocity(d)
    dv = np.diff(v)
    assert np.all(dv >= 0)
    assert np.all(dv[d[1:] < 5.8] > 0)
    # C¹: the slope never jumps (a kink at a knot or a join would jump by ~0.1–1 m/s per mm).
    slope = dv / np.diff(d)
    assert np.max(np.abs(np.diff(slope))) < 0.02
    assert P.terminal_velocity(0.0) == 0.0
    assert P.terminal_velocity(0.039) == pytest.approx(0.18 / 4)  # Stokes, v ∝ D²
    assert P.terminal_velocity(1e300) == pytest.approx(9.17)
    assert P.terminal_velocity(7.0) == pytest.approx(9.17)


# --- sampling ---


@pytest.mark.parametrize("rate", [0.2, 2.0, 25.0, 500.0])
def test_sampled_diameters_follow_truncated_distribution(rate):
    n = 20_000
    d = P.sample_drop_diameters(rate, n, np.random.default_rng(7))
    assert d.shape == (n,) and d.dtype == np.float64
    assert d.min() >= P.D_MIN_MM and d.max() <= P.D_MAX_MM
    # 1.95/√n is exceeded with probability < 0.1 % by exact samples.
    assert P.ks_distance(d, rate) < 1.95 / math.sqrt(n)
    # The truncated exponential's mean, in closed form.
    lam, a, b = 4.1 * rate**-0.21, P.D_MIN_MM, P.D_MAX_MM
    mean = a + 1 / lam - (b - a) * math.exp(-lam * (b - a)) / (1 - math.exp(-lam * (b - a)))
    assert d.mean() == pytest.approx(mean, rel=4 * d.std() / mean / math.sqrt(n))


def test_ks_distance_detects_the_wrong_distribution():
    d = P.sample_drop_diameters(2.0, 20_000, 1)
    assert P.ks_distance(d, 20.0) > 10 / math.sqrt(d.size)


def test_sampling_is_seeded_and_handles_edge_counts():
    a = P.sample_drop_diameters(5.0, 1000, np.random.default_rng(3))
    b = P.sample_drop_diameters(5.0, 1000, 3)
    assert np.array_equal(a, b)
    assert P.sample_drop_diameters(5.0, 0, 3).shape == (0,)
    with pytest.raises(ValueError, match="rate_mm_h"):
        P.sample_drop_diameters(0.0, 10, 3)
    with pytest.raises(ValueError, match="n must"):
        P.sample_drop_diameters(1.0, -1, 3)
    with pytest.raises(ValueError, match="n must"):
        P.sample_drop_diameters(1.0, 2.5, 3)
    with pytest.raises(ValueError, match="rng"):
        P.sample_drop_diameters(1.0, 5, None)


# --- derived quantities ---


def test_renormalised_distribution_carries_exactly_r_and_mp_does_not():
    rates = np.array([0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0])
    back = P.implied_rate_mm_h(rates, n0=P.effective_n0(rates))
    np.testing.assert_allclose(back, rates, rtol=1e-9)
    ratio = P.implied_rate_mm_h(rates, d_min_mm=0.0, d_max_mm=math.inf) / rates
    # DESIGN §3: about 1.09–1.19 × R from 50 to 1 mm/h.
    sel = (rates >= 1) & (rates <= 50)
    assert np.all((ratio[sel] > 1.08) & (ratio[sel] < 1.2))
    assert P.effective_n0(0.0) == 0.0


def _truncated_moment(k, lam, a=P.D_MIN_MM, b=P.D_MAX_MM):
    """∫_a^b D^k e^(−λD) dD in closed form, for k = 0 or 3."""

    def anti(d):
        if k == 0:
            return -math.exp(-lam * d) / lam
        return -math.exp(-lam * d) * (d**3 / lam + 3 * d**2 / lam**2 + 6 * d / lam**3 + 6 / lam**4)

    return anti(b) - anti(a)


@pytest.mark.parametrize("rate", [0.3, 4.0, 60.0])
def test_density_and_water_content_closed_forms(rate):
    lam, n0 = 4.1 * rate**-0.21, P.effective_n0(rate)
    assert P.number_density_per_m3(rate) == pytest.approx(n0 * _truncated_moment(0, lam), rel=1e-10)
    lwc = n0 * math.pi / 6 * _truncated_moment(3, lam) * 1e-3
    assert P.liquid_water_content_g_m3(rate) == pytest.approx(lwc, rel=1e-9)
    # Near the classic 0.089·R^0.84 g/m³, lowered by the renormalised N0 (~0.85–0.9).
    assert 0.75 < P.liquid_water_content_g_m3(rate) / (0.089 * rate**0.84) < 1.0


def test_surface_fluxes():
    r = 5.0
    horiz = P.flux_horizontal_per_m2_s(r)
    assert P.flux_on_surface_per_s(r, 1.0, (0, 1, 0)) == pytest.approx(horiz, rel=1e-12)
    assert P.flux_on_surface_per_s(r, 2.0, (0, 3, 0)) == pytest.approx(2 * horiz, rel=1e-12)
    assert P.flux_on_surface_per_s(r, 1.0, (0, -1, 0)) == 0.0  # underside of a still roof
    # A vertical plate moving at V sweeps V·A m³/s of air: it meets V·A·(number density) drops.
    v = 20.0
    plate = P.flux_on_surface_per_s(r, 1.5, (0, 0, -1), (0, 0, -v))
    assert plate == pytest.approx(v * 1.5 * P.number_density_per_m3(r), rel=1e-12)
    assert P.flux_on_surface_per_s(r, 1.5, (0, 0, 1), (0, 0, -v)) == 0.0  # the rear face stays dry
    # A tailwind at the car's speed: the front plate sees no drops.
    assert P.flux_on_surface_per_s(r, 1.5, (0, 0, -1), (0, 0, -v), (0, 0, -v)) == pytest.approx(0.0, abs=1e-9)
    # A windshield gets more drops the faster the car goes; batch shape follows the inputs.
    speeds = np.array([0.0, 10.0, 20.0, 30.0])
    vel = np.stack([np.zeros(4), np.zeros(4), -speeds], axis=-1)
    hits = P.flux_on_surface_per_s(r, 1.2, (0, 0.5, -1), vel)
    assert hits.shape == (4,) and np.all(np.diff(hits) > 0)
    with pytest.raises(ValueError, match="normal"):
        P.flux_on_surface_per_s(r, 1.0, (0, 0, 0))


def test_streak_length():
    r, t = 3.0, 0.05
    still = P.mean_streak_length_m(r, t)
    # Still camera, no wind: each drop moves at v(D), so the mean speed is flux / density.
    assert still == pytest.approx(t * P.flux_horizontal_per_m2_s(r) / P.number_density_per_m3(r), rel=1e-10)
    moving = P.mean_streak_length_m(r, t, (0, 0, -25.0))
    assert moving > 25.0 * t and moving < math.hypot(25.0, 9.17) * t
    assert P.mean_streak_length_m(0.0, t) == pytest.approx(t * P.terminal_velocity(P.D_MIN_MM))
    assert P.mean_streak_length_m(r, 0.0) == 0.0


def test_extinction_and_splash_flux():
    assert P.rain_extinction_per_km(1.0) == pytest.approx(0.312)
    assert P.rain_extinction_per_km(10.0) == pytest.approx(0.312 * 10**0.67)
    assert P.rain_extinction_per_km(0.0) == 0.0
    assert P.splash_water_flux(20.0, 0.2, 0.001) == pytest.approx(4.0)  # kg/s
    np.testing.assert_allclose(P.splash_water_flux(np.array([0.0, 10.0]), 0.25, 0.002), [0.0, 5.0])


# --- validation: every public function rejects NaN / negative / inf with the argument named ---

_CALLS = {
    "marshall_palmer/d": (lambda x: P.marshall_palmer(x, 1.0), "d_mm"),
    "marshall_palmer/r": (lambda x: P.marshall_palmer(1.0, x), "rate_mm_h"),
    "terminal_velocity": (P.terminal_velocity, "d_mm"),
    "rain_category": (P.rain_category, "rate_mm_h"),
    "sample": (lambda x: P.sample_drop_diameters(x, 10, 0), "rate_mm_h"),
    "cdf": (lambda x: P.drop_diameter_cdf(x, 1.0), "d_mm"),
    "number_density": (P.number_density_per_m3, "rate_mm_h"),
    "flux_horizontal": (P.flux_horizontal_per_m2_s, "rate_mm_h"),
    "flux_surface/r": (lambda x: P.flux_on_surface_per_s(x, 1.0, (0, 1, 0)), "rate_mm_h"),
    "flux_surface/area": (lambda x: P.flux_on_surface_per_s(1.0, x, (0, 1, 0)), "area_m2"),
    "flux_surface/vel": (lambda x: P.flux_on_surface_per_s(1.0, 1.0, (0, 1, 0), (x, 0, 0)), "surface_velocity"),
    "lwc": (P.liquid_water_content_g_m3, "rate_mm_h"),
    "streak/r": (lambda x: P.mean_streak_length_m(x, 0.02), "rate_mm_h"),
    "streak/t": (lambda x: P.mean_streak_length_m(1.0, x), "exposure_s"),
    "extinction": (P.rain_extinction_per_km, "rate_mm_h"),
    "implied": (P.implied_rate_mm_h, "rate_mm_h"),
    "n0": (P.effective_n0, "rate_mm_h"),
    "splash/v": (lambda x: P.splash_water_flux(x, 0.2, 0.001), "speed_m_s"),
    "splash/b": (lambda x: P.splash_water_flux(10.0, x, 0.001), "tire_width_m"),
    "splash/h": (lambda x: P.splash_water_flux(10.0, 0.2, x), "film_depth_m"),
}
_NEGATIVE_OK = {"flux_surface/vel"}  # a velocity component may be negative


@pytest.mark.parametrize("bad", [math.nan, -1.0, math.inf, -math.inf, "x"])
@pytest.mark.parametrize("case", sorted(_CALLS))
def test_bad_inputs_raise_value_error_naming_the_argument(case, bad):
    fn, arg = _CALLS[case]
    if bad == -1.0 and case in _NEGATIVE_OK:
        assert np.all(np.isfinite(fn(bad)))
        return
    with pytest.raises(ValueError, match=arg):
        fn(bad)


@pytest.mark.parametrize("case", sorted(set(_CALLS) - {"sample", "flux_surface/vel"}))
def test_bad_entry_inside_an_array_is_found(case):
    fn, arg = _CALLS[case]
    with pytest.raises(ValueError, match=arg):
        fn(np.array([0.5, 1.0, np.nan]))


def test_rates_above_the_maximum_are_rejected_and_extremes_are_finite():
    with pytest.raises(ValueError, match="500"):
        P.number_density_per_m3(501.0)
    extremes = np.array([0.0, 1e-6, P.R_MAX_MM_H])
    for fn in (P.number_density_per_m3, P.flux_horizontal_per_m2_s, P.liquid_water_content_g_m3,
               P.effective_n0, P.rain_extinction_per_km, lambda r: P.mean_streak_length_m(r, 0.1)):
        out = fn(extremes)
        assert np.all(np.isfinite(out)) and np.all(out >= 0)
    assert np.all(np.isfinite(P.marshall_palmer(np.array([0.0, 1e6]), np.array([[0.0], [1e-6], [500.0]]))))


def test_benchmark_quick_run_writes_tables(tmp_path, capsys):
    from rain_core.bench import physics as bench

    assert bench.main(["--quick", "--out", str(tmp_path)]) == 0
    md = (tmp_path / "physics.md").read_text()
    for heading in ("Terminal velocity", "Self-consistency", "Drop-size sampling"):
        assert heading in md
    assert (tmp_path / "physics.png").stat().st_size > 0
