"""The rainbow's optics against published values: the Airy function (DLMF), water's index (Quan & Fry), the
rainbow angles (Descartes), Airy's theory against geometric optics, the colour order and Alexander's dark band."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.rainbow import optics

# Ai(z), DLMF §9 / Abramowitz & Stegun table 10.11.
AIRY_TABLE = [(0.0, 0.3550280539), (1.0, 0.1352924163), (2.0, 0.0349241304), (5.0, 1.083444281e-4),
              (-1.0, 0.5355608833), (-2.0, 0.2274074282), (-5.0, 0.3507610090), (-10.0, 0.0402412385),
              (-2.338107410, 0.0), (-4.087949444, 0.0)]


@pytest.mark.parametrize("z,ai", AIRY_TABLE)
def test_airy_function_matches_the_table(z, ai):
    assert optics.airy_ai(np.array([z]))[0] == pytest.approx(ai, abs=5e-6)


def test_airy_function_is_continuous_where_its_pieces_meet():
    for z in (-8.0, 4.0):
        a, b = optics.airy_ai(np.array([z - 1e-9, z + 1e-9]))
        assert abs(a - b) < 5e-6


def test_water_index_of_refraction():
    assert optics.water_refractive_index(589.3) == pytest.approx(1.3330, abs=5e-4)  # sodium D line, 20 °C
    n = optics.water_refractive_index(np.array([400.0, 500.0, 600.0, 700.0]))
    assert np.all(np.diff(n) < 0)  # normal dispersion: blue bends more
    assert n[0] - n[-1] == pytest.approx(0.0135, abs=0.002)


def test_descartes_ray_is_stationary_and_its_curvature_matches_finite_differences():
    n = 1.333
    for k in (1, 2):
        b, d_r, h = optics.rainbow_ray(n, k)
        e = 1e-4
        d = optics.deviation_rad(np.array([b - e, b, b + e]), n, k)
        assert abs(d[2] - d[0]) / (2 * e) < 1e-5  # dD/db = 0 (to the O(e²) of the difference)
        assert (d[0] - 2 * d[1] + d[2]) / (e * e) / 2 == pytest.approx(h, rel=1e-4)
        assert h > 0  # a minimum of deviation: light only on one side (the dark band is the other)


def test_rainbow_angles_are_the_published_ones():
    # Primary: red ≈ 42.3–42.5°, violet ≈ 40.6°; secondary: red ≈ 50.1–50.4°, violet ≈ 53.5° (Minnaert; Lee).
    p = optics.rainbow_angle_deg(np.array([400.0, 700.0]), 1)
    s = optics.rainbow_angle_deg(np.array([400.0, 700.0]), 2)
    assert p[0] == pytest.approx(40.6, abs=0.3) and p[1] == pytest.approx(42.4, abs=0.3)
    assert s[0] == pytest.approx(53.5, abs=0.3) and s[1] == pytest.approx(50.3, abs=0.3)


def test_airy_intensity_averages_to_geometric_optics_on_the_lit_side():
    # Far from the caustic, Airy's supernumeraries average out to the geometric d²·G/√ε.
    d_mm, lam = 2.0, 550.0
    n = optics.water_refractive_index(lam)
    b, d_r, h = optics.rainbow_ray(n, 1)
    g = b * optics.rainbow_transmission(n, 1) / (4 * math.sqrt(h) * abs(math.sin(d_r)))
    eps = np.linspace(math.radians(2.0), math.radians(4.0), 20001)
    airy = optics.drop_cross_section_sr(math.pi - d_r - eps, d_mm, lam, 1)
    geometric = d_mm**2 * g / np.sqrt(eps)
    assert airy.mean() == pytest.approx(geometric.mean(), rel=0.02)


def test_cie_fit_peaks_where_the_eye_is_most_sensitive():
    lam = np.arange(380.0, 781.0, 1.0)
    y = optics.cie_xyz_bar(lam)[:, 1]
    assert lam[y.argmax()] == pytest.approx(555.0, abs=8.0) and y.max() == pytest.approx(1.0, abs=0.03)


def test_flat_spectrum_is_grey():
    w = optics.rgb_weights(optics.WAVELENGTHS_NM)
    np.testing.assert_allclose(w.sum(axis=0), 1.0, atol=1e-12)


def _peak_deg(theta_deg, values):
    return theta_deg[np.argmax(values)]


def test_colour_order_and_alexanders_dark_band():
    theta = np.linspace(35.0, 58.0, 921)
    p = optics.bow_phase_rgb(np.radians(theta), rate_mm_h=4.0)
    primary, secondary = theta < 46.5, theta > 46.5
    # Primary: red outside (larger θ) of blue; secondary: reversed.
    assert _peak_deg(theta[primary], p[primary, 0]) > _peak_deg(theta[primary], p[primary, 2]) + 0.5
    assert _peak_deg(theta[secondary], p[secondary, 0]) < _peak_deg(theta[secondary], p[secondary, 2]) - 0.5
    # The secondary is dimmer (one more internal reflection), the dark band darker than inside the primary.
    lum = p @ np.array([0.2126, 0.7152, 0.0722])
    assert lum[secondary].max() < 0.6 * lum[primary].max()
    band = (theta > 44.5) & (theta < 48.5)
    inside = (theta > 36.0) & (theta < 38.0)
    assert lum[band].max() < 0.1 * lum[inside].mean()


def test_phase_function_scale_is_physical():
    # A phase function over the extinction: the bow's peak is of the order of an isotropic 1/(4π) and the
    # light it sends into the whole 30–62° span is a few per cent of what the rain extinguishes.
    theta = np.radians(np.linspace(30.0, 62.0, 2001))
    p = optics.bow_phase_rgb(theta, rate_mm_h=4.0).mean(axis=1)
    share = np.trapezoid(p * 2 * math.pi * np.sin(theta), theta)
    assert 0.005 < share < 0.1
    assert 0.01 < p.max() < 0.5


def test_sun_disc_smooths_but_keeps_the_energy():
    k = optics.sun_disc_kernel(math.radians(32.0) / 383)
    assert k.sum() == pytest.approx(1.0) and len(k) > 3
    lut = optics.bow_lut(4.0, samples=384)
    assert lut.shape == (384, 3) and np.all(np.isfinite(lut)) and lut.min() >= 0.0
    assert np.all(lut[0] == 0.0)  # faded to nothing at the table's inner end: no edge in the sky


def test_rate_must_be_positive():
    with pytest.raises(ValueError, match="rate_mm_h"):
        optics.bow_phase_rgb(0.7, rate_mm_h=0.0)
