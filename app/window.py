"""The interactive window: drive with WASD/arrows, R resets the car, C switches camera, Tab hides the Rain Manager,
F1 lists the keys, F12 saves a screenshot, Esc quits (``app.controls.KEY_HELP``)."""

from __future__ import annotations

import sys
import time
from datetime import datetime
from pathlib import Path

from app.cameras import CameraModes
from app.controls import KeyboardDriver, reset_to_lane
from app.recording import save_png
from rain_core import jit
from rain_core.car_mesh import DRIVER_EYE_LOCAL
from rain_core.gfx.driver import request_driver_thread
from rain_core.scene import Scene

KEY_NAMES = {"W": "up", "UP": "up", "S": "down", "DOWN": "down", "A": "left", "LEFT": "left", "D": "right",
             "RIGHT": "right"}


# The package each moderngl-window backend imports, and what to pip-install for it.
BACKEND_PACKAGES = {"pyglet": ("pyglet", "pyglet"), "glfw": ("glfw", "glfw"), "sdl2": ("sdl2", "pysdl2 pysdl2-dll"),
                    "pygame2": ("pygame", "pygame"), "pyqt5": ("PyQt5", "PyQt5"), "pyside2": ("PySide2", "PySide2"),
                    "tk": ("pyopengltk", "pyopengltk")}
DEFAULT_BACKEND = "pyglet"


def missing_backend_message(backend: str, exc: ImportError) -> str:
    """What to tell the user when a window backend's package cannot be imported."""
    module, pip_name = BACKEND_PACKAGES.get(backend, (getattr(exc, "name", None) or backend, backend))
    missing = getattr(exc, "name", None) or module
    return (f"rainroad: the window backend {backend!r} is not installed (cannot import {missing!r}).\n"
            f"  Install it with: python -m pip install {pip_name}\n"
            f"  or use the default backend: --window {DEFAULT_BACKEND}; without a display: "
            "python -m app --headless --screenshot out.png")


def create_window(backend: str, size: tuple[int, int], title: str = "Rainroad"):
    """A moderngl-window window of the given backend (pyglet, glfw, … or headless), GL 3.3 core, with Mesa's
    driver thread asked for (``request_driver_thread``) before its context."""
    import moderngl_window
    from moderngl_window.conf import settings as mglw_settings

    mglw_settings.WINDOW["class"] = f"moderngl_window.context.{backend}.Window"
    mglw_settings.WINDOW["gl_version"] = (3, 3)
    mglw_settings.WINDOW["size"] = tuple(size)
    mglw_settings.WINDOW["aspect_ratio"] = None
    mglw_settings.WINDOW["title"] = title
    mglw_settings.WINDOW["vsync"] = True
    mglw_settings.WINDOW["resizable"] = True
    if backend == "headless":
        mglw_settings.WINDOW["backend"] = "egl"
    request_driver_thread()
    return moderngl_window.create_window_from_settings()


class RainroadApp:
    """Connects a window's events to the scene, the driving input, the camera modes and the Rain Manager."""

    def __init__(self, wnd, settings, seed: int = 1, screenshot_dir: Path = Path("screenshots")):
        from app.panel import RainManagerPanel

        self.wnd = wnd
        self.ctx = wnd.ctx
        self.screenshot_dir = screenshot_dir
        # GPU timing starts off; the Rain Manager turns it on while its performance table is open.
        self.scene = Scene(self.ctx, self.render_size(settings), settings=settings, seed=seed, gpu_timing=False)
        # A cold start compiles the CPU kernels in a child process while the NumPy twins run (no frozen window).
        self.warmup = jit.WarmUp.start()
        if self.warmup is None:  # warm: every kernel loads now, not in the frame that first calls it
            jit.preload()
        self.driver = KeyboardDriver()
        self.cameras = CameraModes(settings.camera.mode)
        self.panel = RainManagerPanel(self.ctx, wnd.size, self.scene, framebuffer_size=wnd.buffer_size)
        self.panel.cameras = self.cameras
        self.panel.on_reset = self.reset_car
        self._keys = {getattr(wnd.keys, name, None): name
                      for name in (*KEY_NAMES, "C", "G", "R", "TAB", "F1", "F12", "ESCAPE")}
        self._keys.pop(None, None)
        self._last = time.perf_counter()
        wnd.render_func = self.render
        wnd.resize_func = self.resize
        wnd.key_event_func = self.key_event
        layer = self.panel.layer
        wnd.mouse_position_event_func = layer.mouse_position_event
        wnd.mouse_drag_event_func = self.mouse_drag_event
        wnd.mouse_press_event_func = layer.mouse_press_event
        wnd.mouse_release_event_func = layer.mouse_release_event
        wnd.mouse_scroll_event_func = layer.mouse_scroll_event
        wnd.unicode_char_entered_func = layer.unicode_char_entered

    def render_size(self, settings=None) -> tuple[int, int]:
        """The internal frame size: the window's pixels × quality.render_scale (presented scaled to the window)."""
        scale = (settings or self.scene.settings).quality.render_scale
        width, height = self.wnd.buffer_size
        return max(16, round(width * scale)), max(16, round(height * scale))

    def key_event(self, key, action, modifiers):
        self.panel.layer.key_event(key, action, modifiers, keys=self.wnd.keys)
        name = self._keys.get(key)
        pressed = action == self.wnd.keys.ACTION_PRESS
        if name is None:
            return
        if name in KEY_NAMES and not pressed:  # a release always counts, or a key pressed earlier would stick
            self.driver.release(KEY_NAMES[name], key)
            return
        if self.panel.layer.want_capture_keyboard and name != "F12":
            return
        if name in KEY_NAMES:
            self.driver.press(KEY_NAMES[name], key)
        elif pressed and name == "C":
            self.cameras.cycle(self.scene.ego)
            self.scene.settings.camera.mode = self.cameras.mode
        elif pressed and name == "G":
            self.cameras.toggle_glass(self.scene.ego)
            self.scene.settings.camera.mode = self.cameras.mode
        elif pressed and name == "R":
            self.reset_car()
        elif pressed and name == "TAB":
            self.panel.visible = not self.panel.visible
        elif pressed and name == "F1":
            self.panel.show_help = not self.panel.show_help
        elif pressed and name == "F12":
            self.screenshot()
        elif pressed and name == "ESCAPE":
            self.wnd.close()

    def reset_car(self):
        """R / the Rain Manager's button: the car back on its lane (``controls.reset_to_lane``)."""
        reset_to_lane(self.scene)
        self.driver.center()
        self.cameras.chase.reset()

    def mouse_drag_event(self, x, y, dx, dy):
        self.panel.layer.mouse_drag_event(x, y, dx, dy)
        if not self.panel.layer.want_capture_mouse and self.cameras.mode == "free":
            self.cameras.free.turn(dx, dy)

    def minimised(self) -> bool:
        return 0 in self.wnd.buffer_size or 0 in self.wnd.size

    def resize(self, width, height):
        if self.minimised():  # keep the old targets until the window comes back
            return
        self.panel.layer.resize(self.wnd.size, self.wnd.buffer_size)
        self.scene.renderer.resize(self.render_size())

    def screenshot(self) -> Path:
        stamp = datetime.now().strftime("%Y%m%d-%H%M%S-%f")
        path = save_png(self.scene.image(), self.screenshot_dir / f"rainroad-{stamp}.png")
        print(f"rainroad: screenshot {path}")
        return path

    def render(self, time_s: float, frame_time_s: float):
        if self.warmup is not None and self.warmup.poll():  # the kernels are compiled: they run from now on
            self.warmup = None
        now = time.perf_counter()
        dt = now - self._last
        self._last = now
        ego = self.scene.ego
        if self.cameras.mode == "free":
            self.cameras.free.move(dt, self.driver.held)
            drive = None  # the keys fly the camera; the car keeps its lane on autopilot
        else:
            drive = None if self.driver.autopilot else self.driver.update(dt, ego.speed_m_s)
        if self.minimised():
            return
        if self.render_size() != self.scene.renderer.size:  # quality.render_scale changed in the panel
            self.scene.renderer.resize(self.render_size())
        self.scene.step(dt, drive)
        self.scene.settings.camera.mode = self.cameras.mode
        view = self.scene.settings.camera
        camera = self.cameras.camera(ego, DRIVER_EYE_LOCAL, self.scene.last_dt_s, view.fov_deg, view=view)
        self.scene.render(camera)
        self.scene.renderer.present(self.wnd.fbo, (0, 0, *self.wnd.buffer_size))
        self.panel.draw(dt, self.wnd.fbo)


def run_window(args, settings, max_frames: int | None = None) -> int:
    try:
        wnd = create_window(args.window, args.size)
    except ImportError as exc:  # the backend's package is not installed: name it and how to get it
        print(missing_backend_message(args.window, exc), file=sys.stderr)
        return 1
    except Exception as exc:  # no display, no GL, unknown backend: say so instead of a traceback
        print(f"rainroad: could not open a window ({args.window}): {exc}\n"
              "  Without a display use the headless variant: python -m app --headless --screenshot out.png",
              file=sys.stderr)
        return 1
    app = RainroadApp(wnd, settings, seed=args.seed)
    frames = 0
    while not wnd.is_closing and (max_frames is None or frames < max_frames):
        wnd.clear()
        wnd.render(0.0, 0.0)
        wnd.swap_buffers()
        frames += 1
    app.panel.layer.shutdown()
    app.scene.release()
    wnd.destroy()
    return 0
