"""The atmosphere bench's skipped-lights table (``bench atmosphere``): against tracing every light, the skips
change no displayed value by more than a level, by day and at night, and by day the pixel's share skips more."""

from __future__ import annotations

from rain_core.bench.atmosphere import _scene, skip_rows
from rain_core.effects.atmosphere.scattering import SCATTER_SKIP, SCATTER_SKIP_RELATIVE


def test_skipped_lights_change_the_display_by_at_most_a_level(gl_ctx):
    scene, settings = _scene(gl_ctx, (128, 72), 22.0)
    effect = next(e for e in scene.renderer.effects if e.name == "atmosphere")
    try:
        rows = skip_rows(scene, settings, frames=1)
    finally:
        scene.release()
    assert [(r[0], r[1]) for r in rows] == [
        (hour, label) for hour in ("12 h", "22 h")
        for label in ("every light traced", "fixed budget", "fixed + share of the pixel's light")]
    for hour, label, ms, changed_pct, largest in rows:
        assert ms >= 0.0 and 0.0 <= changed_pct <= 100.0
        assert largest <= 1, (hour, label)
        if label == "every light traced":
            assert changed_pct == 0.0
    day = {label: changed for hour, label, _, changed, _ in rows if hour == "12 h"}
    assert day["fixed + share of the pixel's light"] > day["fixed budget"] + 0.2  # by day the share skips more
    # the effect's own budgets and the settings are put back
    assert (effect.scatter_skip, effect.scatter_skip_relative) == (SCATTER_SKIP, SCATTER_SKIP_RELATIVE)
    assert settings.time_of_day.hour == 22.0 and settings.camera.auto_exposure
