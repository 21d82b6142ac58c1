"""The Rain Manager: an ImGui window that shows and edits the settings live.

Widgets are generated from the settings declarations (type, range, unit, choices), and every edit goes through
``rain_core.settings.set_value``, the same validation as the CLI and scenario files. A refused value is shown in
red next to its widget instead of reaching the simulation.

It starts compact: docked to the window's left side at most ``MAX_WIDTH_FRACTION`` of its width, FPS and frame
ms in the title, the Rain section open and the groups Effects, View and quality, Performance collapsed. Tab
hides it, F1 shows the keys (``app.controls.KEY_HELP``).
"""

from __future__ import annotations

import functools
import time
from collections import deque

import numpy as np
from imgui_bundle import imgui

from app.controls import KEY_HELP, reset_to_lane
from app.imgui_layer import ImGuiLayer
from rain_core import jit, physics
from rain_core.gfx.driver import describe_driver
from rain_core.settings import SettingsError, all_fields, apply_rain_preset, field_info, get_value, set_value

# The sections in panel order: (settings section or None, title). A section is "wired" when an effect or the
# scene reads it; the others show what will arrive instead of controls that would do nothing.
SECTIONS = (
    ("rain", "Rain"), ("road", "Road"), ("wind", "Wind"), ("wipers", "Wipers"), ("camera", "Camera"),
    ("time_of_day", "Time of day"), ("traffic", "Traffic"), ("quality", "Quality"), ("ripples", "Ripples"),
    ("rainfall", "Rainfall"), ("spray", "Spray"), ("windshield", "Windshield"), ("atmosphere", "Atmosphere"),
    ("drips", "Drips"), ("lightning", "Lightning"), ("rainbow", "Rainbow"),
)
# The panel's groups, in the README's order (Rain first and open, then Effects, View and quality; Performance last).
GROUPS = (
    ("Effects", ("road", "wind", "wipers", "ripples", "rainfall", "spray", "windshield", "atmosphere",
                 "drips", "lightning", "rainbow")),
    ("View and quality", ("camera", "time_of_day", "traffic", "quality")),
)
SECTION_TITLES = dict(SECTIONS)
MAX_WIDTH_FRACTION = 0.25  # of the window's width
MAX_WIDTH_PX = 380.0  # wide windows need no wider panel
MIN_WIDGET_PX = 110.0  # a slider narrower than this hides its value under the grab
# Fields the generic widgets should not show (edited by dedicated widgets).
CUSTOM_FIELDS = {"rain.rate_mm_h", "rain.preset", "rain.wetness", "rain.cracks", "rain.puddles"}
LOG_FIELDS = {"rain.time_scale"}
# Settings that live in one section but belong on another effect's controls too (issue wording: the Ripples
# section has the grid resolution, Rainfall the budget and exposure, Windshield the texture resolution).
EXTRA_FIELDS = {"ripples": ("quality.ripple_grid",),
                "rainfall": ("quality.particle_budget", "camera.exposure_s"),
                "windshield": ("quality.windshield_resolution",)}


UNIT_SUFFIXES = ("_mm_h", "_m_s", "_per_km", "_deg", "_s", "_m")


@functools.cache  # (FieldInfo is frozen: the panel asks for each widget's label every frame)
def field_label(info) -> str:
    """"fov_deg" with unit "deg" → "fov (deg)": the unit is shown once, in brackets."""
    name = info.path.split(".")[1]
    for suffix in UNIT_SUFFIXES:
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    return ascii_text(name.replace("_", " ") + (f" ({info.unit})" if info.unit else ""))


# The default ImGui font has ASCII only: anything else would show as '?'.
_ASCII = {"→": "->", "←": "<-", "≈": "~", "…": "...", "×": "x", "β": "beta", "°": " deg", "≤": "<=", "≥": ">=",
          "−": "-", "–": "-", "—": "-", "²": "^2", "³": "^3", "µ": "u", "μ": "u", "·": "*", "±": "+/-", "½": "1/2",
          "‰": " per mille", "’": "'", "“": '"', "”": '"', "α": "alpha", "θ": "theta", "λ": "lambda"}


_ASCII_TABLE = str.maketrans(_ASCII)


def ascii_text(text: str) -> str:
    """``text`` with the usual symbols spelled in ASCII (→ "->", ≈ "~", × "x", …); anything else → '?'."""
    return str(text).translate(_ASCII_TABLE).encode("ascii", "replace").decode("ascii")


# The rate's class, shown every frame: physics.rain_category's array path costs ~0.1 ms for one rate.
_rain_category = functools.lru_cache(maxsize=256)(physics.rain_category)


def preset_in_use(settings) -> str:
    """The rain preset shown: the one named in the settings, else the preset whose rate the current rate equals
    (the default 2 mm/h is "moderate"), else "custom"."""
    if settings.rain.preset in physics.RAIN_PRESETS:
        return settings.rain.preset
    rate = float(settings.rain.rate_mm_h)
    return next((name for name, r in physics.RAIN_PRESETS.items() if abs(r - rate) <= 1e-9 * max(r, 1.0)),
                "custom")


def frame_rows(pass_table, step_ms: float, panel_ms: float) -> list[tuple[str, float, float | None]]:
    """(row, CPU ms, GPU ms or None) of the Performance section's summary: the scene's step (``step_ms``: the ego
    car, the traffic, the weather), each effect and built-in pass (``effect_totals``), the Rain Manager itself
    (``panel_ms``, its last frame) and the frame's CPU in all."""
    rows = [("step: cars, weather", float(step_ms), None), *effect_totals(pass_table),
            ("Rain Manager (this panel)", float(panel_ms), None)]
    return [*rows, ("frame, CPU in all", sum(cpu for _, cpu, _ in rows), None)]


def effect_totals(pass_table) -> list[tuple[str, float, float | None]]:
    """(effect, CPU ms, GPU ms or None) per effect from a renderer's ``pass_table()``: an effect's passes
    ("rainfall.update", "rainfall.transparent") summed, a built-in pass ("scene", "shadow") on its own, skipped
    passes left out. GPU ms is None unless every pass of the effect has one."""
    totals: dict[str, list] = {}
    for name, ran, cpu_ms, gpu_ms, _note in pass_table:
        if not ran:
            continue
        row = totals.setdefault(name.split(".", 1)[0], [0.0, 0.0])
        row[0] += cpu_ms
        row[1] = None if (gpu_ms is None or row[1] is None) else row[1] + gpu_ms
    return [(name, cpu, gpu) for name, (cpu, gpu) in totals.items()]


class RainManagerPanel:
    """Draws the Rain Manager for a ``Scene`` over a framebuffer."""

    def __init__(self, ctx, window_size, scene, framebuffer_size=None, expand_all: bool = False):
        self.layer = ImGuiLayer(ctx, tuple(window_size), framebuffer_size)
        self.expand_all = expand_all  # open every section (screenshots, tests)
        self.visible = True  # Tab
        self.show_help = False  # F1
        self.on_reset = None  # the app's reset (car, driving input, cameras); default: controls.reset_to_lane
        self.last_rect = None  # ((x, y), (w, h)) of the panel in the last frame, window pixels
        self.open_sections: list[str] = []  # titles of the headers open in the last frame
        self._label_w = 0.0  # px, the label column of the section being drawn
        self.scene = scene
        self.cameras = None  # the app's CameraModes, when there is a window
        self.errors: dict[str, str] = {}
        self.frame_ms = deque(maxlen=120)
        # The last draw's CPU time on this thread (ms: its widgets and its GL calls). Not wall time: drawn behind the
        # frame's draws, a write may wait for the GL driver's thread to take the frame in (~0.2 s on llvmpipe).
        self.own_cpu_ms = 0.0
        self._ctx = ctx
        self._height_view = None  # RGBA8 texture of the ripple heights, made when first shown
        self._driver: str | None = None  # the GL driver in words (describe_driver), for the performance section
        self.fields = {}
        for info in all_fields():
            self.fields.setdefault(info.path.split(".")[0], []).append(info)

    # --- editing --------------------------------------------------------------------------------------------
    def _set(self, path: str, value) -> None:
        try:
            set_value(self.scene.settings, path, value)
            self.errors.pop(path, None)
        except SettingsError as exc:
            self.errors[path] = str(exc)

    def _fit(self, label: str) -> str:
        """Size the next widget so its label fits beside it (labels are never cut): the section's label column
        when that leaves the widget MIN_WIDGET_PX, else this label's own width; a label too long for either goes
        on its own line above a full-width widget. Returns the label to give the widget."""
        text = label.split("##")[0]
        spacing = imgui.get_style().item_inner_spacing.x + 2.0
        avail = imgui.get_content_region_avail().x
        for label_w in (self._label_w, imgui.calc_text_size(text).x):
            if avail - label_w - spacing >= MIN_WIDGET_PX:
                imgui.set_next_item_width(avail - label_w - spacing)
                return label
        imgui.text(text)
        imgui.set_next_item_width(-1.0)
        return "##" + label

    def _field_widget(self, info, id_suffix: str = "") -> None:
        settings = self.scene.settings
        value = get_value(settings, info.path)
        label = field_label(info) + id_suffix  # "##…" keeps ImGui ids unique when a field shows twice
        if info.optional:
            auto = value is None
            changed, auto = imgui.checkbox(f"auto##{info.path}{id_suffix}", auto)
            if changed:
                self._set(info.path, None if auto else float(info.default if info.default is not None else 0.0))
            imgui.same_line()
            if auto:
                imgui.text_disabled(label)
                return
            value = get_value(settings, info.path)
        if info.kind != "bool":
            label = self._fit(label)
        if info.kind == "bool":
            changed, new = imgui.checkbox(label, bool(value))
        elif info.kind == "str" and info.choices:
            index = info.choices.index(value) if value in info.choices else 0
            changed, index = imgui.combo(label, index, list(info.choices))
            new = info.choices[index]
        elif info.kind == "int":
            lo, hi = info.range
            changed, new = imgui.slider_int(label, int(value), int(lo), int(min(hi, 10**6)))
        elif info.kind == "float":
            lo, hi = info.range
            flags = imgui.SliderFlags_.logarithmic.value if info.path in LOG_FIELDS else 0
            changed, new = imgui.slider_float(label, float(value), float(lo), float(hi), "%.3g", flags)
        else:
            imgui.text(f"{label}: {value}")
            return
        if imgui.is_item_hovered() and info.doc:
            imgui.set_tooltip(ascii_text(info.doc))
        if changed:
            self._set(info.path, new)
        if info.path in self.errors:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.errors[info.path])

    # --- sections -------------------------------------------------------------------------------------------
    def _rain_section(self) -> None:
        settings = self.scene.settings
        presets = list(physics.RAIN_PRESETS)
        current = preset_in_use(settings)
        index = presets.index(current) + 1 if current in presets else 0
        changed, index = imgui.combo(self._fit("preset"), index, ["custom", *presets])
        if changed and index > 0:
            try:
                apply_rain_preset(settings, presets[index - 1])
            except SettingsError as exc:
                self.errors["rain.preset"] = str(exc)
        rate = settings.rain.rate_mm_h
        changed, rate = imgui.slider_float(self._fit("rate (mm/h)"), rate, 0.0, 200.0, "%.2f",
                                           imgui.SliderFlags_.logarithmic.value)
        if changed:
            self._set("rain.rate_mm_h", rate)
            self._set("rain.preset", "custom")
        category = _rain_category(settings.rain.rate_mm_h) if settings.rain.rate_mm_h > 0 else "none"
        imgui.text(f"category: {category}")
        state = self.scene.weather_state
        imgui.separator_text("road water (auto = weather drives it)")
        for level in ("wetness", "cracks", "puddles"):
            imgui.progress_bar(float(getattr(state, level)), imgui.ImVec2(48, 0), f"{getattr(state, level):.2f}")
            imgui.same_line()
            self._field_widget(next(f for f in self.fields["rain"] if f.path == f"rain.{level}"))

    def _effect(self, name: str):
        return next((e for e in self.scene.effects if e.name == name), None)

    def _spray_section(self) -> None:
        spray = self._effect("spray")
        risk = float(getattr(spray, "ego_hydroplaning_risk", 0.0) or 0.0)
        imgui.text("hydroplaning risk (ego, worst wheel)")
        color = imgui.ImVec4(0.9, 0.25, 0.2, 1.0) if risk > 0.3 else imgui.ImVec4(0.3, 0.7, 0.3, 1.0)
        imgui.push_style_color(imgui.Col_.plot_histogram.value, color)
        imgui.progress_bar(risk, imgui.ImVec2(-1, 0), f"{risk:.2f}" + ("  grip going!" if risk > 0.3 else ""))
        imgui.pop_style_color()
        # What grip is left: the water's share lifted off, times the road's grip (road.friction_scale).
        grip = (1.0 - risk) * float(self.scene.settings.road.friction_scale)
        imgui.text(f"grip left {grip:.2f} (x road friction {self.scene.settings.road.friction_scale:.2f})")

    def _ripple_heights(self) -> None:
        """The simulated height field as a picture: red above rest, blue below, scaled to its largest swing."""
        ripples = self._effect("ripples")
        field = getattr(ripples, "field", None)
        if field is None or not self.scene.settings.ripples.show_heights:
            return
        step = max(1, field.n // 128)
        h = np.asarray(field.height)[::step, ::step]
        scale = max(float(np.abs(h).max()), 1e-9)
        v = np.clip(h / scale, -1.0, 1.0)
        rgba = np.empty((*h.shape, 4), np.uint8)
        rgba[..., 0] = (np.maximum(v, 0) * 255).astype(np.uint8)
        rgba[..., 1] = 40
        rgba[..., 2] = (np.maximum(-v, 0) * 255).astype(np.uint8)
        rgba[..., 3] = 255
        if self._height_view is None or self._height_view.size != (h.shape[1], h.shape[0]):
            if self._height_view is not None:
                self.layer.unregister_texture(self._height_view)
                self._height_view.release()
            self._height_view = self._ctx.texture((h.shape[1], h.shape[0]), 4)
        self._height_view.write(np.ascontiguousarray(rgba[::-1]).tobytes())
        ref = self.layer.register_texture(self._height_view)
        imgui.text(f"height field, ±{scale * 1000:.3f} mm, {field.extent_m:.0f} m across")
        imgui.image(ref, imgui.ImVec2(200, 200))

    def _performance_section(self) -> None:
        renderer = self.scene.renderer
        width, height = renderer.size
        imgui.text(f"render {width}x{height}   GPU timing: {renderer.timing_source}")
        imgui.text(f"CPU simulations: {jit.describe()}")
        if self._driver is None:  # (the context's strings: read once)
            self._driver = describe_driver(self._ctx)
        imgui.text_wrapped(f"GL: {self._driver}")
        imgui.text_disabled("GPU ms are timed only while this section is open (two frames late)")
        # Columns as wide as their text (no cut pass names); a table wider than the panel scrolls sideways.
        flags = (imgui.TableFlags_.borders.value | imgui.TableFlags_.row_bg.value
                 | imgui.TableFlags_.sizing_fixed_fit.value | imgui.TableFlags_.scroll_x.value)
        table = renderer.pass_table()
        line = imgui.get_text_line_height_with_spacing() + 2.0
        totals = frame_rows(table, self.scene.step_cpu_ms, self.own_cpu_ms)
        if imgui.begin_table("effects", 3, flags, imgui.ImVec2(0.0, line * (len(totals) + 2) + 14.0)):
            for title in ("effect", "CPU ms", "GPU ms"):
                imgui.table_setup_column(title)
            imgui.table_headers_row()
            for name, cpu_ms, gpu_ms in totals:
                imgui.table_next_row()
                for text in (name, f"{cpu_ms:.2f}", "-" if gpu_ms is None else f"{gpu_ms:.2f}"):
                    imgui.table_next_column()
                    imgui.text(text)
            imgui.end_table()
        if imgui.begin_table("passes", 5, flags, imgui.ImVec2(0.0, line * (len(table) + 2) + 14.0)):
            for title in ("pass", "ran", "CPU ms", "GPU ms", "note"):
                imgui.table_setup_column(title)
            imgui.table_headers_row()
            for name, ran, cpu_ms, gpu_ms, note in table:
                imgui.table_next_row()
                for text in (name, "yes" if ran else "skipped", f"{cpu_ms:.2f}" if ran else "-",
                             f"{gpu_ms:.2f}" if (ran and gpu_ms is not None) else "-", note):
                    imgui.table_next_column()
                    imgui.text(text)
            imgui.end_table()

    def fps_line(self) -> str:
        """"60.0 FPS  16.7 ms": the mean over the last frames drawn (empty before the first)."""
        if not self.frame_ms:
            return "- FPS"
        mean = sum(self.frame_ms) / len(self.frame_ms)
        return f"{1000.0 / max(mean, 1e-6):.1f} FPS  {mean:.1f} ms"

    @staticmethod
    def panel_width(window_width: float) -> float:
        """The docked panel's width (px) for a window that wide: a quarter of it, at most MAX_WIDTH_PX."""
        return float(min(MAX_WIDTH_FRACTION * window_width, MAX_WIDTH_PX))

    def reset_car(self) -> None:
        if self.on_reset is not None:
            self.on_reset()
        else:
            reset_to_lane(self.scene)

    def _header(self, title: str, default_open: bool, tree: bool = False) -> bool:
        """A collapsing header (or a tree node inside a group); remembers which are open."""
        if self.expand_all:
            imgui.set_next_item_open(True)
        flags = imgui.TreeNodeFlags_.default_open.value if default_open else 0
        opened = imgui.tree_node_ex(title, flags) if tree else imgui.collapsing_header(title, flags)
        if opened:
            self.open_sections.append(title)
        return opened

    def _section(self, section: str) -> None:
        """The widgets of one settings section, their labels in a column as wide as the longest."""
        effect = next((e for e in self.scene.effects if e.name == section), None)
        if effect is not None and effect.describe():
            imgui.push_text_wrap_pos(0.0)
            imgui.text_disabled(ascii_text(effect.describe()))
            imgui.pop_text_wrap_pos()
        infos = [i for i in self.fields.get(section, []) if i.path not in CUSTOM_FIELDS]
        extras = [field_info(path) for path in EXTRA_FIELDS.get(section, ())]
        labels = [field_label(i) for i in infos + extras] or [""]
        self._label_w = max(imgui.calc_text_size(t).x for t in labels)
        if section == "rain":
            self._rain_section()
        for info in infos:
            self._field_widget(info)
        for info in extras:
            self._field_widget(info, id_suffix=f"##{section}")
        if section == "spray":
            self._spray_section()
        elif section == "ripples":
            self._ripple_heights()
        if section == "camera" and self.cameras is not None:
            self.cameras.set_mode(self.scene.settings.camera.mode, self.scene.ego)

    def _help_window(self) -> None:
        io = imgui.get_io()
        imgui.set_next_window_pos(imgui.ImVec2(io.display_size.x * 0.5, io.display_size.y * 0.5),
                                  imgui.Cond_.always.value, imgui.ImVec2(0.5, 0.5))
        flags = imgui.WindowFlags_.always_auto_resize.value | imgui.WindowFlags_.no_collapse.value
        _, still_open = imgui.begin("Keys (F1 closes)", True, flags)
        if imgui.begin_table("keys", 2, imgui.TableFlags_.sizing_fixed_fit.value):
            for key, action in KEY_HELP:
                imgui.table_next_row()
                imgui.table_next_column()
                imgui.text(key)
                imgui.table_next_column()
                imgui.text(ascii_text(action))
            imgui.end_table()
        imgui.end()
        self.show_help = bool(still_open)

    def _main_window(self) -> bool:
        """The docked panel; returns whether the Performance section is open."""
        io = imgui.get_io()
        width = self.panel_width(io.display_size.x)
        imgui.set_next_window_pos(imgui.ImVec2(0, 0), imgui.Cond_.always.value)
        imgui.set_next_window_size(imgui.ImVec2(width, io.display_size.y), imgui.Cond_.always.value)
        flags = (imgui.WindowFlags_.no_move.value | imgui.WindowFlags_.no_resize.value
                 | imgui.WindowFlags_.no_collapse.value)
        # "###" keeps the window's id fixed while its title (the FPS) changes.
        imgui.begin(f"Rain Manager  {self.fps_line()}###Rain Manager", None, flags)
        pos, size = imgui.get_window_pos(), imgui.get_window_size()
        self.last_rect = ((pos.x, pos.y), (size.x, size.y))
        imgui.text(f"{self.fps_line()}  {self.scene.ego.speed_m_s * 3.6:.0f} km/h")
        if imgui.button("Reset car (R)"):
            self.reset_car()
        imgui.same_line()
        if imgui.button("Keys (F1)"):
            self.show_help = not self.show_help
        imgui.text_disabled("Tab hides this panel")
        if self._header("Rain", default_open=True):
            self._section("rain")
        for group, sections in GROUPS:
            if not self._header(group, default_open=False):
                continue
            for section in sections:
                if self._header(SECTION_TITLES[section], default_open=False, tree=True):
                    self._section(section)
                    imgui.tree_pop()
        performance = self._header("Performance", default_open=False)
        if performance:
            self._performance_section()
        imgui.end()
        return performance

    def draw(self, dt_s: float, fbo) -> None:
        """Build and draw one frame of the panel into ``fbo`` (nothing but the help, if open, while hidden)."""
        t0 = time.thread_time()
        self.frame_ms.append(dt_s * 1e3)
        self.open_sections = []
        layer = self.layer
        layer.new_frame(dt_s)
        performance = self._main_window() if self.visible else False
        if self.show_help:
            self._help_window()
        # GPU timer queries only while the table is on screen: they add work to every pass.
        self.scene.renderer.gpu_timing = performance
        layer.render(fbo)
        self.own_cpu_ms = (time.thread_time() - t0) * 1e3
