"""The Rain Manager: an ImGui window that shows and edits the settings live.

Widgets are generated from the settings declarations (type, range, unit, choices), and every edit goes through
``rain_core.settings.set_value``, the same validation as the CLI and scenario files. A refused value is shown in
red next to its widget instead of reaching the simulation.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from imgui_bundle import imgui

from app.imgui_layer import ImGuiLayer
from rain_core import physics
from rain_core.settings import SettingsError, all_fields, apply_rain_preset, field_info, get_value, set_value

# The sections in panel order: (settings section or None, title). A section is "wired" when an effect or the
# scene reads it; the others show what will arrive instead of controls that would do nothing.
SECTIONS = (
    ("rain", "Rain"), ("road", "Road"), ("wind", "Wind"), ("wipers", "Wipers"), ("camera", "Camera"),
    ("time_of_day", "Time of day"), ("traffic", "Traffic"), ("quality", "Quality"), ("ripples", "Ripples"),
    ("rainfall", "Rainfall"), ("spray", "Spray"), ("windshield", "Windshield"), ("atmosphere", "Atmosphere"),
)
# Fields the generic widgets should not show (edited by dedicated widgets).
CUSTOM_FIELDS = {"rain.rate_mm_h", "rain.preset", "rain.wetness", "rain.cracks", "rain.puddles"}
LOG_FIELDS = {"rain.time_scale"}
# Settings that live in one section but belong on another effect's controls too (issue wording: the Ripples
# section has the grid resolution, Rainfall the budget and exposure, Windshield the texture resolution).
EXTRA_FIELDS = {"ripples": ("quality.ripple_grid",),
                "rainfall": ("quality.particle_budget", "camera.exposure_s"),
                "windshield": ("quality.windshield_resolution",)}


UNIT_SUFFIXES = ("_mm_h", "_m_s", "_per_km", "_deg", "_s", "_m")


def field_label(info) -> str:
    """"fov_deg" with unit "deg" → "fov (deg)": the unit is shown once, in brackets."""
    name = info.path.split(".")[1]
    for suffix in UNIT_SUFFIXES:
        if name.endswith(suffix):
            name = name[: -len(suffix)]
            break
    return name.replace("_", " ") + (f" ({info.unit})" if info.unit else "")


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
        self.scene = scene
        self.cameras = None  # the app's CameraModes, when there is a window
        self.errors: dict[str, str] = {}
        self.frame_ms = deque(maxlen=120)
        self._ctx = ctx
        self._height_view = None  # RGBA8 texture of the ripple heights, made when first shown
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
            imgui.set_next_item_width(140)  # leave room for the label after the progress bar and checkbox
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
            imgui.set_tooltip(info.doc)
        if changed:
            self._set(info.path, new)
        if info.path in self.errors:
            imgui.text_colored(imgui.ImVec4(1.0, 0.35, 0.3, 1.0), self.errors[info.path])

    # --- sections -------------------------------------------------------------------------------------------
    def _rain_section(self) -> None:
        settings = self.scene.settings
        presets = list(physics.RAIN_PRESETS)
        current = settings.rain.preset
        index = presets.index(current) + 1 if current in presets else 0
        changed, index = imgui.combo("preset", index, ["custom", *presets])
        if changed and index > 0:
            try:
                apply_rain_preset(settings, presets[index - 1])
            except SettingsError as exc:
                self.errors["rain.preset"] = str(exc)
        rate = settings.rain.rate_mm_h
        changed, rate = imgui.slider_float("rate (mm/h)", rate, 0.0, 200.0, "%.2f",
                                           imgui.SliderFlags_.logarithmic.value)
        if changed:
            self._set("rain.rate_mm_h", rate)
            self._set("rain.preset", "custom")
        category = physics.rain_category(settings.rain.rate_mm_h) if settings.rain.rate_mm_h > 0 else "none"
        imgui.text(f"category: {category}")
        state = self.scene.weather_state
        imgui.separator_text("road water (auto = weather drives it)")
        for level in ("wetness", "cracks", "puddles"):
            imgui.progress_bar(float(getattr(state, level)), imgui.ImVec2(120, 0), f"{getattr(state, level):.2f}")
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
        if self.frame_ms:
            mean = sum(self.frame_ms) / len(self.frame_ms)
            width, height = renderer.size
            imgui.text(f"{1000.0 / max(mean, 1e-6):.1f} FPS  ({mean:.2f} ms/frame)  {width}x{height}")
        imgui.text(f"speed {self.scene.ego.speed_m_s * 3.6:.0f} km/h   GPU timing: {renderer.timing_source}")
        imgui.text_disabled("GPU ms are timed only while this section is open (one frame late)")
        flags = imgui.TableFlags_.borders.value | imgui.TableFlags_.row_bg.value
        table = renderer.pass_table()
        if imgui.begin_table("effects", 3, flags):
            for title in ("effect", "CPU ms", "GPU ms"):
                imgui.table_setup_column(title)
            imgui.table_headers_row()
            for name, cpu_ms, gpu_ms in effect_totals(table):
                imgui.table_next_row()
                for text in (name, f"{cpu_ms:.2f}", "-" if gpu_ms is None else f"{gpu_ms:.2f}"):
                    imgui.table_next_column()
                    imgui.text(text)
            imgui.end_table()
        if imgui.begin_table("passes", 5, flags):
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

    def draw(self, dt_s: float, fbo) -> None:
        """Build and draw one frame of the panel into ``fbo``."""
        self.frame_ms.append(dt_s * 1e3)
        layer = self.layer
        layer.new_frame(dt_s)
        imgui.set_next_window_pos(imgui.ImVec2(10, 10), imgui.Cond_.first_use_ever.value)
        imgui.set_next_window_size(imgui.ImVec2(440, 520), imgui.Cond_.first_use_ever.value)
        imgui.begin("Rain Manager")
        for section, title in SECTIONS:
            open_by_default = imgui.TreeNodeFlags_.default_open.value if section in ("rain", "camera") else 0
            if self.expand_all:
                imgui.set_next_item_open(True)
            if not imgui.collapsing_header(title, open_by_default):
                continue
            effect = next((e for e in self.scene.effects if e.name == section), None)
            if effect is not None and effect.describe():
                imgui.text_disabled(effect.describe())
            if section == "rain":
                self._rain_section()
            for info in self.fields.get(section, []):
                if info.path not in CUSTOM_FIELDS:
                    self._field_widget(info)
            for path in EXTRA_FIELDS.get(section, ()):
                self._field_widget(field_info(path), id_suffix=f"##{section}")
            if section == "spray":
                self._spray_section()
            elif section == "ripples":
                self._ripple_heights()
            if section == "camera" and self.cameras is not None:
                self.cameras.set_mode(self.scene.settings.camera.mode, self.scene.ego)
        performance = imgui.collapsing_header("Performance", imgui.TreeNodeFlags_.default_open.value)
        # GPU timer queries only while the table is on screen: they add work to every pass.
        self.scene.renderer.gpu_timing = performance
        if performance:
            self._performance_section()
        imgui.end()
        layer.render(fbo)
