"""A real window under Xvfb opens, renders frames with the Rain Manager and closes; the panel also renders
headlessly."""

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

pytestmark = pytest.mark.window


@pytest.fixture(scope="module")
def display():
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        pytest.skip("Xvfb is not installed (.ci/run installs it)")
    number = 90 + os.getpid() % 9
    proc = subprocess.Popen([xvfb, f":{number}", "-screen", "0", "640x480x24", "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.0)
    if proc.poll() is not None:
        pytest.skip("Xvfb could not start")
    yield f":{number}"
    proc.terminate()
    proc.wait(timeout=10)


def test_real_window_opens_renders_and_closes(display):
    env = dict(os.environ, DISPLAY=display)
    result = subprocess.run([sys.executable, "-m", "app", "--window", "pyglet", "--size", "320x200", "--frames", "4"],
                            env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr


def test_panel_draws_over_the_frame(gl_ctx, tmp_path):
    from app.panel import RainManagerPanel
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (640, 360), seed=2)
    scene.step(1 / 30)
    scene.render()
    before = scene.image().astype(int)
    panel = RainManagerPanel(gl_ctx, (640, 360), scene)
    for _ in range(3):  # the first frames lay the window out
        scene.render()
        panel.draw(1 / 30, scene.renderer.ldr)
    after = scene.image().astype(int)
    changed = np.abs(after - before).sum(axis=2) > 30
    assert changed[20:100, 20:100].mean() > 0.5  # the panel sits at the top left
    assert changed[:, 470:].mean() < 0.02  # and leaves the rest of the frame alone
    panel.layer.shutdown()
    scene.release()


def test_panel_edit_goes_through_validation(gl_ctx):
    from app.panel import RainManagerPanel
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (160, 120), seed=2)
    panel = RainManagerPanel(gl_ctx, (160, 120), scene)
    panel._set("rain.rate_mm_h", 12.0)
    assert scene.settings.rain.rate_mm_h == 12.0
    panel._set("rain.rate_mm_h", -1.0)
    assert scene.settings.rain.rate_mm_h == 12.0 and "rain.rate_mm_h" in panel.errors["rain.rate_mm_h"]
    panel.layer.shutdown()
    scene.release()


def test_panel_shows_every_section_with_water_on_the_road(gl_ctx):
    """All sections open (hydroplaning bar, ripple height view) draw without errors on a flooded road."""
    from app.panel import RainManagerPanel
    from rain_core.scene import Scene
    from rain_core.settings import Settings, set_value

    settings = Settings()
    for path, value in (("rain.puddles", 1.0), ("rain.cracks", 1.0), ("quality.ripple_grid", 64),
                        ("ripples.show_heights", True)):
        set_value(settings, path, value)
    scene = Scene(gl_ctx, (320, 240), settings=settings, seed=2)
    panel = RainManagerPanel(gl_ctx, (320, 240), scene, expand_all=True)
    for _ in range(3):
        scene.step(1 / 30)
        scene.render()
        panel.draw(1 / 30, scene.renderer.ldr)
    assert panel._height_view is not None and panel._height_view.size == (64, 64)
    assert not panel.errors
    panel.layer.shutdown()
    scene.release()


def test_performance_table_turns_gpu_timing_on_only_while_shown(gl_ctx):
    """GPU timer queries run only while the Performance section is drawn; CPU ms are there always."""
    from app.panel import RainManagerPanel
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (160, 90), seed=2, gpu_timing=False)
    scene.step(1 / 30)
    scene.render()
    assert scene.renderer.timing_source == "none"
    assert all(gpu is None for _n, ran, _c, gpu, _t in scene.renderer.pass_table() if ran)
    assert all(cpu >= 0.0 for _n, ran, cpu, _g, _t in scene.renderer.pass_table() if ran)
    panel = RainManagerPanel(gl_ctx, (160, 90), scene)
    for _ in range(3):  # the section is open by default; GPU ms arrive a frame after timing starts
        panel.draw(1 / 30, scene.renderer.ldr)
        scene.step(1 / 30)
        scene.render()
    assert scene.renderer.gpu_timing and scene.renderer.timing_source != "none"
    assert any(gpu is not None for _n, ran, _c, gpu, _t in scene.renderer.pass_table() if ran)
    panel.layer.shutdown()
    scene.renderer.gpu_timing = False  # what a closed section does
    scene.render()
    assert all(gpu is None for _n, ran, _c, gpu, _t in scene.renderer.pass_table() if ran)
    scene.release()


def test_effect_totals_sum_each_effects_passes():
    from app.panel import effect_totals

    table = [("rainfall.update", True, 1.0, 0.5, ""), ("scene", True, 2.0, 3.0, ""),
             ("rainfall.transparent", True, 0.5, 1.5, ""), ("spray", False, 0.0, None, ""),
             ("ripples.update", True, 0.25, None, "numpy32")]
    assert effect_totals(table) == [("rainfall", 1.5, 2.0), ("scene", 2.0, 3.0), ("ripples", 0.25, None)]
