"""The storm's schedule: published stroke statistics, a Poisson rate, and light that does not depend on how time
is stepped or on the frame rate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core.effects.lightning import schedule as sch
from rain_core.effects.lightning.bolt import bolt_segments
from rain_core.effects.lightning.storm import Storm
from rain_core.settings import Settings


def test_automatic_rate_only_in_convective_rain():
    assert sch.auto_flashes_per_min(0.0) == 0.0 and sch.auto_flashes_per_min(15.9) == 0.0
    assert 0.0 < sch.auto_flashes_per_min(16.0) <= sch.auto_flashes_per_min(50.0) <= 6.0


def test_strokes_follow_the_published_statistics():
    s = sch.FlashSchedule(30.0, 8000.0, seed=4)
    flashes = [f for b in range(20) for f in s.block(b)]
    assert len(flashes) > 100
    for f in flashes:
        assert 3 <= len(f.stroke_s) <= 5
        gaps = np.diff(f.stroke_s)
        assert np.all((gaps >= 0.040) & (gaps <= 0.080))
        assert f.stroke_cd[0] == sch.PEAK_CD and max(f.stroke_cd[1:]) <= 0.6 * sch.PEAK_CD
        assert sch.NEAR_M <= f.distance_m <= 8000.0


def test_flash_count_is_poisson_at_the_set_rate():
    s = sch.FlashSchedule(6.0, seed=9)
    n = sum(len(s.block(b)) for b in range(200))  # 200 minutes
    assert abs(n - 1200) < 4 * math.sqrt(1200)


def test_the_same_flashes_whatever_the_stepping():
    a = sch.FlashSchedule(10.0, seed=2)
    b = sch.FlashSchedule(10.0, seed=2)
    whole = {f.seed for f in a.flashes_between(0.0, 300.0)}
    stepped = set()
    t = 0.0
    while t < 300.0:
        stepped |= {f.seed for f in b.flashes_between(t, t + 1 / 30)}
        t += 1 / 30
    assert whole == stepped and whole


def test_shutter_light_is_frame_rate_independent():
    flash = sch.FlashSchedule(10.0, seed=5).block(0)[0]
    t0 = flash.start_s - 0.01
    for frames_per_s in (24.0, 30.0, 60.0, 240.0):
        dt = 1.0 / frames_per_s
        starts = t0 + dt * np.arange(int(1.5 / dt))
        total = float(np.sum(sch.mean_intensity_cd(flash, starts, starts + dt)) * dt)
        exact = sum(cd * (sch.STROKE_TAU_S + (sch.AFTERGLOW_SHARE * sch.AFTERGLOW_TAU_S if glow else 0.0))
                    for cd, glow in zip(flash.stroke_cd, flash.afterglow, strict=True))
        assert total == pytest.approx(exact, rel=1e-6)  # energy is conserved frame by frame


def test_bad_schedule_input_is_rejected():
    with pytest.raises(ValueError, match="flashes_per_min"):
        sch.FlashSchedule(-1.0)
    with pytest.raises(ValueError, match="far_m"):
        sch.FlashSchedule(1.0, far_m=10.0)


def test_bolt_runs_from_the_cloud_to_the_ground_and_branches():
    segments, weights = bolt_segments([0.0, 1500.0, 0.0], [100.0, 0.0, 50.0], seed=3)
    main = segments[weights == 1.0]
    np.testing.assert_allclose(main[0, 0], [0.0, 1500.0, 0.0])
    np.testing.assert_allclose(main[-1, 1], [100.0, 0.0, 50.0])
    np.testing.assert_allclose(main[1:, 0], main[:-1, 1])  # one connected channel
    assert (weights < 1.0).any() and weights.min() > 0.0
    again, _ = bolt_segments([0.0, 1500.0, 0.0], [100.0, 0.0, 50.0], seed=3)
    np.testing.assert_array_equal(segments, again)


def _storm_view(settings, t, eye=(0.0, 1.5, 0.0)):
    storm = Storm(seed=1)
    return storm, storm.frame_view(settings, t, 1 / 30, np.array(eye), settings.rain.rate_mm_h)


def test_storm_lights_only_during_flashes_and_gives_the_thunder_delay():
    s = Settings()
    s.rain.rate_mm_h = 40.0
    s.lightning.flashes_per_min = 10.0
    flashes = sch.FlashSchedule(10.0, s.lightning.max_distance_km * 1000.0, seed=1).block(0)
    flash = next(f for i, f in enumerate(flashes[:-1]) if flashes[i + 1].start_s > f.end_s + 1.0
                 and (i == 0 or flashes[i - 1].end_s < f.start_s - 1.0))  # a flash alone in its seconds
    storm, view = _storm_view(s, flash.start_s + 0.02)
    assert view is not None and view.flash == flash
    assert view.illuminance_lux((0.0, 1.5, 0.0)) > 0.0 and np.all(view.sky_cd_m2 > 0.0)
    assert f"{flash.distance_m / 1000.0:.1f} km" in storm.describe()
    _, between = _storm_view(s, flash.start_s - 1.0e-3)
    assert between is None
    s.lightning.enabled = False
    _, off = _storm_view(s, flash.start_s + 0.02)
    assert off is None


def test_sky_light_falls_with_the_square_of_the_distance():
    s = Settings()
    s.lightning.flashes_per_min = 10.0
    flash = sch.FlashSchedule(10.0, s.lightning.max_distance_km * 1000.0, seed=1).block(0)[0]
    _, near = _storm_view(s, flash.start_s + 0.02)
    top = near.top
    far_eye = top + (np.array([0.0, 1.5, 0.0]) - top) * 2.0
    _, far = _storm_view(s, flash.start_s + 0.02, eye=far_eye)
    # The anchor is the eye's ground point: the far eye sees the channel twice as far only if it stays put, so
    # compare against the formula directly.
    d_near = np.linalg.norm(near.top - np.array([0.0, 1.5, 0.0]))
    d_far = np.linalg.norm(far.top - far_eye)
    assert near.sky_cd_m2[0] / far.sky_cd_m2[0] == pytest.approx((d_far / d_near) ** 2, rel=1e-9)
