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
    # Another run on this machine may hold a display number: try the next ones.
    for k in range(9):
        number = 90 + (os.getpid() + k) % 9
        proc = subprocess.Popen([xvfb, f":{number}", "-screen", "0", "640x480x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(1.0)
        if proc.poll() is None:
            break
    else:
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
    panel = RainManagerPanel(gl_ctx, (160, 90), scene, expand_all=True)
    for _ in range(4):  # the section shown (it starts collapsed); GPU ms arrive two frames after timing starts
        panel.draw(1 / 30, scene.renderer.ldr)
        scene.step(1 / 30)
        scene.render()
    assert scene.renderer.gpu_timing and scene.renderer.timing_source != "none"
    assert any(gpu is not None for _n, ran, _c, gpu, _t in scene.renderer.pass_table() if ran)
    assert scene.step_cpu_ms > 0.0 and panel.own_cpu_ms > 0.0  # the summary's step and panel rows
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


def test_frame_rows_add_the_step_and_the_panel_to_the_effects():
    from app.panel import frame_rows

    table = [("rainfall.update", True, 1.0, 0.5, ""), ("scene", True, 2.0, 3.0, ""), ("spray", False, 0.0, None, "")]
    rows = frame_rows(table, step_ms=0.25, panel_ms=0.5)
    assert rows == [("step: cars, weather", 0.25, None), ("rainfall", 1.0, 0.5), ("scene", 2.0, 3.0),
                    ("Rain Manager (this panel)", 0.5, None), ("frame, CPU in all", 3.75, None)]


def _panel_frame(gl_ctx, panel, scene, size):
    target = gl_ctx.framebuffer(color_attachments=[gl_ctx.texture(size, 4)])
    try:
        for _ in range(3):  # the first frames lay the window out
            panel.draw(1 / 30, target)
        return np.frombuffer(target.read(components=4), dtype=np.uint8).reshape(size[1], size[0], 4)[::-1]
    finally:
        scene.renderer.ldr.use()
        target.color_attachments[0].release()
        target.release()


def test_panel_starts_compact_and_docked_at_1280x720(gl_ctx):
    """Issue 17: Rain open, every other group collapsed, docked left at ≤ 25 % of the width, FPS in the title;
    Tab (``visible``) hides it; F1 (``show_help``) lists the keys."""
    from app.panel import RainManagerPanel
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (160, 90), seed=2, gpu_timing=False)
    scene.step(1 / 30)
    scene.render()
    panel = RainManagerPanel(gl_ctx, (1280, 720), scene)
    pixels = _panel_frame(gl_ctx, panel, scene, (1280, 720))
    (x, y), (w, h) = panel.last_rect
    assert (x, y) == (0.0, 0.0) and 0 < w <= 0.25 * 1280 and h == 720
    assert panel.open_sections == ["Rain"]
    assert not scene.renderer.gpu_timing  # Performance is collapsed
    drawn = pixels[..., 3] > 0
    assert drawn[:, : int(w)].mean() > 0.95 and not drawn[:, int(w) + 2:].any()
    assert "FPS" in panel.fps_line() and "ms" in panel.fps_line()
    panel.visible = False
    assert not _panel_frame(gl_ctx, panel, scene, (1280, 720))[..., 3].any()
    panel.show_help = True
    pixels = _panel_frame(gl_ctx, panel, scene, (1280, 720))
    assert pixels[350:370, 600:680, 3].any()  # the key list, centred
    assert panel.show_help
    panel.layer.shutdown()
    scene.release()


def test_panel_text_is_ascii_and_preset_shows_the_one_in_use():
    from app.panel import ascii_text, field_label, preset_in_use
    from rain_core import physics
    from rain_core.settings import Settings, all_fields, set_value

    for info in all_fields():  # the default font has ASCII only: no '?' for an arrow
        assert field_label(info).isascii()
        doc = info.doc or ""
        assert ascii_text(doc).isascii() and ascii_text(doc).count("?") == doc.count("?")  # nothing unknown
    assert ascii_text("0 clear … 1 dark, ≈ 3/β km, 2×") == "0 clear ... 1 dark, ~ 3/beta km, 2x"
    settings = Settings()
    assert settings.rain.rate_mm_h == physics.RAIN_PRESETS["moderate"] and preset_in_use(settings) == "moderate"
    set_value(settings, "rain.rate_mm_h", 3.3)
    assert preset_in_use(settings) == "custom"


def test_reset_puts_the_car_back_on_its_lane(gl_ctx):
    from app.controls import reset_to_lane
    from rain_core import layout
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, (64, 36), seed=2, gpu_timing=False)
    ego = scene.ego
    z = float(ego.position[2])
    ego.position = np.array([150.0, 0.0, z])  # far off the street, across it, stopped, steering
    ego.yaw, ego.speed_m_s, ego.steer_rad, ego.yaw_rate_rad_s = 1.4, 0.0, 0.4, 0.8
    reset_to_lane(scene)
    lane = scene.autopilot.lane_index
    assert ego.position[0] == layout.LANE_CENTRES_X[lane] and ego.position[2] == z
    assert ego.yaw == layout.LANE_YAW[lane] and ego.steer_rad == 0.0 and ego.yaw_rate_rad_s == 0.0
    assert ego.speed_m_s == scene.autopilot.target_speed_m_s
    np.testing.assert_allclose(ego.previous_wheel_contacts, ego.wheel_contacts())
    for _ in range(60):  # and it drives on along the lane
        scene.step(1 / 30)
    assert abs(ego.position[0] - layout.LANE_CENTRES_X[lane]) < 1.0 and ego.speed_m_s > 10.0
    scene.release()


def test_help_lists_the_keys_and_default_backend_and_missing_backend_names_the_package(monkeypatch, capsys):
    import app.window as window
    from app.cli import build_parser
    from app.controls import KEY_HELP

    text = build_parser().format_help()
    for key, _action in KEY_HELP:
        assert key in text
    assert all(k in dict(KEY_HELP) for k in ("R", "Tab", "F1", "F12", "Esc"))
    assert "default: pyglet" in " ".join(text.split())

    def no_glfw(backend, size, title="Rainroad"):
        raise ModuleNotFoundError("No module named 'glfw'", name="glfw")

    monkeypatch.setattr(window, "create_window", no_glfw)
    args = build_parser().parse_args(["--window", "glfw"])
    assert window.run_window(args, None) == 1
    err = capsys.readouterr().err
    assert "'glfw' is not installed" in err and "pip install glfw" in err


def test_keys_r_tab_f1_in_the_app(gl_ctx):
    """The window's key handler: R resets the car, Tab hides and shows the panel, F1 toggles the key list."""
    from types import SimpleNamespace

    from moderngl_window.context.base import KeyModifiers

    from app.window import RainroadApp
    from rain_core import layout
    from rain_core.settings import Settings

    class Keys:  # a backend's key constants (pyglet's need a display)
        ACTION_PRESS, ACTION_RELEASE = "press", "release"
        W, UP, S, DOWN, A, LEFT, D, RIGHT, C, R, TAB, F1, F12, ESCAPE = range(100, 114)

    wnd = SimpleNamespace(ctx=gl_ctx, size=(160, 90), buffer_size=(160, 90), keys=Keys, close=lambda: None)
    app = RainroadApp(wnd, Settings(), seed=2)
    try:
        def press(key):
            app.key_event(key, Keys.ACTION_PRESS, KeyModifiers())
            app.key_event(key, Keys.ACTION_RELEASE, KeyModifiers())

        app.scene.ego.position[0] = 40.0
        app.driver.state.steer = 1.0
        press(Keys.R)
        assert app.scene.ego.position[0] == layout.LANE_CENTRES_X[app.scene.autopilot.lane_index]
        assert app.driver.state.steer == 0.0
        press(Keys.TAB)
        assert not app.panel.visible
        press(Keys.TAB)
        assert app.panel.visible
        press(Keys.F1)
        assert app.panel.show_help
        press(Keys.F1)
        assert not app.panel.show_help
        assert app.panel.on_reset == app.reset_car  # the panel's button does the same as R
    finally:
        app.panel.layer.shutdown()
        app.scene.release()
