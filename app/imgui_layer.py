"""Dear ImGui on ModernGL, following the imgui-bundle >= 1.92 texture protocol.

moderngl-window 3.1.1's bundled integration (``moderngl_window.integrations.imgui_bundle``) uses the font
atlas / ``texture_id`` API that Dear ImGui 1.92 removed, so it fails with imgui-bundle >= 1.92. This layer
is a small renderer of our own: it declares ``ImGuiBackendFlags_RendererHasTextures`` and creates, updates
and destroys GPU textures when ImGui asks for them through ``imgui.get_platform_io().textures``, the same
protocol as Dear ImGui's ``imgui_impl_opengl3.cpp`` and imgui-bundle's ``python_backends``.

It owns its own ImGui context, draws into any ``moderngl.Framebuffer`` (a window's screen or an offscreen
target, so it runs headless under EGL), and takes input through methods with the same signatures as
``moderngl_window.WindowConfig``'s event methods, so an app can forward its events unchanged.

Coordinates: ``window_size`` and mouse positions are window coordinates (points, origin top-left, +y down);
``framebuffer_size`` is in pixels. On a high-DPI display the two differ and ImGui draws at the pixel scale.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Mapping
from typing import Any

import moderngl
import numpy as np
from imgui_bundle import imgui

from rain_core.gfx.driver import write_queued

_VERTEX_SHADER = """
#version 330
uniform mat4 ProjMtx;
in vec2 Position;
in vec2 UV;
in vec4 Color;
out vec2 Frag_UV;
out vec4 Frag_Color;
void main() {
    Frag_UV = UV;
    Frag_Color = Color;
    gl_Position = ProjMtx * vec4(Position.xy, 0.0, 1.0);
}
"""

_FRAGMENT_SHADER = """
#version 330
uniform sampler2D Texture;
in vec2 Frag_UV;
in vec4 Frag_Color;
out vec4 Out_Color;
void main() {
    Out_Color = Frag_Color * texture(Texture, Frag_UV.st);
}
"""

# moderngl-window 3 button ids -> ImGui mouse button index (0 left, 1 right, 2 middle).
_MOUSE_BUTTONS = {1: 0, 2: 1, 3: 2}

# Attribute names of moderngl_window.context.base.BaseKeys -> ImGui keys. A window class gives each name
# its library's key code; names it leaves "undefined" (all of them for the headless window) are skipped.
_KEY_NAMES: dict[str, imgui.Key] = {
    "ESCAPE": imgui.Key.escape,
    "SPACE": imgui.Key.space,
    "ENTER": imgui.Key.enter,
    "PAGE_UP": imgui.Key.page_up,
    "PAGE_DOWN": imgui.Key.page_down,
    "LEFT": imgui.Key.left_arrow,
    "RIGHT": imgui.Key.right_arrow,
    "UP": imgui.Key.up_arrow,
    "DOWN": imgui.Key.down_arrow,
    "LEFT_SHIFT": imgui.Key.left_shift,
    "RIGHT_SHIFT": imgui.Key.right_shift,
    "LEFT_CTRL": imgui.Key.left_ctrl,
    "TAB": imgui.Key.tab,
    "COMMA": imgui.Key.comma,
    "MINUS": imgui.Key.minus,
    "PERIOD": imgui.Key.period,
    "SLASH": imgui.Key.slash,
    "SEMICOLON": imgui.Key.semicolon,
    "EQUAL": imgui.Key.equal,
    "LEFT_BRACKET": imgui.Key.left_bracket,
    "RIGHT_BRACKET": imgui.Key.right_bracket,
    "BACKSLASH": imgui.Key.backslash,
    "BACKSPACE": imgui.Key.backspace,
    "INSERT": imgui.Key.insert,
    "DELETE": imgui.Key.delete,
    "HOME": imgui.Key.home,
    "END": imgui.Key.end,
    "CAPS_LOCK": imgui.Key.caps_lock,
    **{f"F{i}": getattr(imgui.Key, f"f{i}") for i in range(1, 13)},
    **{f"NUMBER_{i}": getattr(imgui.Key, f"_{i}") for i in range(10)},
    **{f"NUMPAD_{i}": getattr(imgui.Key, f"keypad{i}") for i in range(10)},
    **{chr(c): getattr(imgui.Key, chr(c).lower()) for c in range(ord("A"), ord("Z") + 1)},
}

_UNDEFINED_KEY = "undefined"
_INDEX_DTYPE = {2: np.uint16, 4: np.uint32}[imgui.INDEX_SIZE]
_MIN_DT_S = 1e-6


def build_key_map(keys: Any) -> dict[Any, imgui.Key]:
    """Map a moderngl-window ``keys`` class (e.g. ``wnd.keys``) to ImGui keys.

    Keys the window library leaves ``"undefined"``, unhashable codes, and codes that two different ImGui keys
    would share are left out, so an unknown key is ignored instead of being reported as the wrong one.
    """
    mapping: dict[Any, imgui.Key] = {}
    ambiguous: set[Any] = set()
    for name, imgui_key in _KEY_NAMES.items():
        code = getattr(keys, name, None)
        if code is None or (isinstance(code, str) and code == _UNDEFINED_KEY):
            continue
        try:
            hash(code)
        except TypeError:
            continue
        if code in mapping and mapping[code] != imgui_key:
            ambiguous.add(code)
        mapping[code] = imgui_key
    for code in ambiguous:
        del mapping[code]
    return mapping


def _validate_size(name: str, size: Any) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in size)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (width, height) pair of integers, got {size!r}") from None
    if w < 0 or h < 0:
        raise ValueError(f"{name} must be >= (0, 0), got {size!r}")
    return w, h


class ImGuiLayer:
    """An ImGui context plus a ModernGL renderer for it.

    Per frame: ``new_frame(dt_s)``, then any ``imgui.*`` calls, then ``render(fbo)``. The layer makes its own
    ImGui context current in every method, so several layers (e.g. one per test) can coexist.
    """

    def __init__(
        self,
        ctx: moderngl.Context,
        window_size: tuple[int, int],
        framebuffer_size: tuple[int, int] | None = None,
        *,
        keys: Any = None,
    ):
        """Create the ImGui context and the GL objects.

        Args:
            ctx: the ModernGL context to draw with (window or standalone; needs OpenGL >= 3.3).
            window_size: (width, height) of the window in points; mouse positions use the same space.
            framebuffer_size: (width, height) of the target in pixels; defaults to ``window_size``.
            keys: a moderngl-window keys class (``wnd.keys``) used by ``key_event``; may be given per call.
        """
        self.ctx = ctx
        self._window_size = _validate_size("window_size", window_size)
        self._framebuffer_size = _validate_size(
            "framebuffer_size", window_size if framebuffer_size is None else framebuffer_size
        )
        self._keys = keys
        self._key_maps: dict[int, dict[Any, imgui.Key]] = {}

        # create_context() restores the previously current context, so make ours current explicitly.
        self._imgui_ctx = imgui.create_context()
        imgui.set_current_context(self._imgui_ctx)
        self.io = imgui.get_io()
        # No imgui.ini in the working directory: the app owns its settings (TOML), not ImGui.
        self.io.set_ini_filename(None)
        # A thin slider grab: the default 12 px block hides the value printed under it in narrow sliders.
        imgui.get_style().grab_min_size = 5.0
        self.io.backend_flags |= (
            imgui.BackendFlags_.renderer_has_textures | imgui.BackendFlags_.renderer_has_vtx_offset
        )
        max_tex = int(ctx.info["GL_MAX_TEXTURE_SIZE"])
        platform_io = imgui.get_platform_io()
        platform_io.renderer_texture_max_width = max_tex
        platform_io.renderer_texture_max_height = max_tex
        self._apply_display_size()

        self._prog = ctx.program(vertex_shader=_VERTEX_SHADER, fragment_shader=_FRAGMENT_SHADER)
        self._prog["Texture"].value = 0
        self._vbo_capacity = 1 << 16
        self._ibo_capacity = 1 << 16
        self._vbo = ctx.buffer(reserve=self._vbo_capacity * imgui.VERTEX_SIZE, dynamic=True)
        # All draw lists go into one buffer with indices rebased to it, so indices are always 32-bit here.
        self._ibo = ctx.buffer(reserve=self._ibo_capacity * 4, dynamic=True)
        self._vao = ctx.vertex_array(
            self._prog,
            [(self._vbo, "2f 2f 4f1", "Position", "UV", "Color")],
            index_buffer=self._ibo,
            index_element_size=4,
        )

        self._textures: dict[int, moderngl.Texture] = {}  # created on ImGui's request, keyed by ImTextureID
        self._user_textures: dict[int, moderngl.Texture] = {}  # registered by the app for imgui.image()
        self._stats = {"textures_created": 0, "texture_updates": 0, "textures_destroyed": 0, "draw_calls": 0}
        self._alive = True

    # ------------------------------------------------------------------ frame

    def new_frame(self, dt_s: float) -> None:
        """Start an ImGui frame; ``dt_s`` is the time since the last frame in seconds (clamped to >= 1e-6 s)."""
        self._activate()
        dt = float(dt_s)
        # ImGui asserts on delta_time <= 0; a paused clock or the first frame may report 0.
        self.io.delta_time = dt if math.isfinite(dt) and dt > _MIN_DT_S else _MIN_DT_S
        self._apply_display_size()
        imgui.new_frame()

    def render(self, fbo: moderngl.Framebuffer | None = None) -> None:
        """End the frame (``imgui.render()``) and draw it into ``fbo`` (default: the context's current one).

        Handles ImGui's texture requests first. Blending is straight alpha over what is already in ``fbo``.
        The enable flags (blend, depth test, cull face, ...), the bound framebuffer, ``fbo``'s viewport and
        scissor and ``ctx.wireframe`` are restored afterwards; moderngl cannot read back the blend function,
        so it is left at moderngl's initial ``DEFAULT_BLENDING`` / ``FUNC_ADD``.
        """
        self._activate()
        imgui.render()
        draw_data = imgui.get_draw_data()
        self._update_textures()

        target = fbo if fbo is not None else self.ctx.fbo
        if target is None:
            raise ValueError("render() needs a framebuffer: pass fbo=, or bind one first (standalone contexts)")

        self._stats["draw_calls"] = 0
        scale_x, scale_y = draw_data.framebuffer_scale.x, draw_data.framebuffer_scale.y
        fb_w = int(draw_data.display_size.x * scale_x)
        fb_h = int(draw_data.display_size.y * scale_y)
        if fb_w <= 0 or fb_h <= 0 or draw_data.total_idx_count == 0:
            return

        items = self._upload(draw_data, fb_w, fb_h)
        if not items:
            return
        self._set_projection(draw_data)

        prev_viewport = target.viewport
        prev_scissor = target.scissor
        prev_wireframe = self.ctx.wireframe
        # The scope sets exactly BLEND on (depth test, cull face off) and rebinds the previous framebuffer
        # with the previous enable flags on exit.
        with self.ctx.scope(target, enable_only=moderngl.BLEND):
            try:
                self.ctx.blend_equation = moderngl.FUNC_ADD
                # Separate alpha factors keep the target's alpha meaningful (as imgui_impl_opengl3 does).
                self.ctx.blend_func = (
                    moderngl.SRC_ALPHA,
                    moderngl.ONE_MINUS_SRC_ALPHA,
                    moderngl.ONE,
                    moderngl.ONE_MINUS_SRC_ALPHA,
                )
                self.ctx.wireframe = False
                target.viewport = (0, 0, fb_w, fb_h)
                for first, count, tex_id, scissor in items:
                    self._texture_for(tex_id).use(0)
                    target.scissor = scissor
                    self._vao.render(moderngl.TRIANGLES, vertices=count, first=first)
                    self._stats["draw_calls"] += 1
            finally:
                if tuple(prev_scissor) == (0, 0, target.width, target.height):
                    target.scissor = None  # moderngl reports a disabled scissor as the full framebuffer
                else:
                    target.scissor = prev_scissor
                target.viewport = prev_viewport
                self.ctx.wireframe = prev_wireframe
                self.ctx.blend_func = moderngl.DEFAULT_BLENDING
                self.ctx.blend_equation = moderngl.FUNC_ADD

    def resize(self, window_size: tuple[int, int], framebuffer_size: tuple[int, int] | None = None) -> None:
        """Set the window size (points) and framebuffer size (pixels, default = window size)."""
        self._window_size = _validate_size("window_size", window_size)
        self._framebuffer_size = _validate_size(
            "framebuffer_size", window_size if framebuffer_size is None else framebuffer_size
        )
        self._activate()
        self._apply_display_size()

    # ------------------------------------------------------------------ textures

    @property
    def textures(self) -> Mapping[int, moderngl.Texture]:
        """The live textures ImGui asked for (font atlas pages), keyed by ImTextureID (= GL name)."""
        return dict(self._textures)

    @property
    def stats(self) -> dict[str, int]:
        """Counters: textures created / updated / destroyed so far, and draw calls in the last render()."""
        return dict(self._stats)

    def register_texture(self, texture: moderngl.Texture) -> imgui.ImTextureRef:
        """Make an app texture drawable with ``imgui.image(ref, size)``; returns its ImTextureRef."""
        self._user_textures[texture.glo] = texture
        return imgui.ImTextureRef(texture.glo)

    def unregister_texture(self, texture: moderngl.Texture) -> None:
        """Forget a texture given to ``register_texture`` (does not release it)."""
        self._user_textures.pop(texture.glo, None)

    # ------------------------------------------------------------------ input (WindowConfig signatures)

    def mouse_position_event(self, x: float, y: float, dx: float, dy: float) -> None:
        """Mouse moved to (x, y) in window coordinates (points)."""
        self._activate()
        self.io.add_mouse_pos_event(float(x), float(y))

    def mouse_drag_event(self, x: float, y: float, dx: float, dy: float) -> None:
        """Mouse moved with a button held; button state comes from the press/release events."""
        self._activate()
        self.io.add_mouse_pos_event(float(x), float(y))

    def mouse_press_event(self, x: float, y: float, button: int) -> None:
        """Button pressed at (x, y); moderngl-window ids 1 left, 2 right, 3 middle (others ignored)."""
        self._mouse_button(x, y, button, True)

    def mouse_release_event(self, x: float, y: float, button: int) -> None:
        """Button released at (x, y); moderngl-window ids 1 left, 2 right, 3 middle (others ignored)."""
        self._mouse_button(x, y, button, False)

    def mouse_scroll_event(self, x_offset: float, y_offset: float) -> None:
        """Wheel scrolled; offsets in wheel steps (y > 0 scrolls up, x > 0 scrolls left)."""
        self._activate()
        self.io.add_mouse_wheel_event(float(x_offset), float(y_offset))

    def key_event(self, key: Any, action: Any, modifiers: Any, keys: Any = None) -> None:
        """Key pressed or released. ``keys`` is the window's keys class (default: the one given at init).

        Modifier state (ctrl/shift/alt) is forwarded even for keys ImGui does not know; unknown keys and
        actions other than press/release are ignored.
        """
        self._activate()
        keys = keys if keys is not None else self._keys
        io = self.io
        io.add_key_event(imgui.Key.mod_ctrl, bool(getattr(modifiers, "ctrl", False)))
        io.add_key_event(imgui.Key.mod_shift, bool(getattr(modifiers, "shift", False)))
        io.add_key_event(imgui.Key.mod_alt, bool(getattr(modifiers, "alt", False)))
        if keys is None:
            return
        if action == keys.ACTION_PRESS:
            down = True
        elif action == keys.ACTION_RELEASE:
            down = False
        else:
            return
        key_map = self._key_maps.get(id(keys))
        if key_map is None:
            key_map = self._key_maps[id(keys)] = build_key_map(keys)
        try:
            imgui_key = key_map.get(key)
        except TypeError:  # unhashable key code
            return
        if imgui_key is not None:
            io.add_key_event(imgui_key, down)

    def unicode_char_entered(self, char: str) -> None:
        """Text typed (one or more characters)."""
        self._activate()
        for c in char:
            self.io.add_input_character(ord(c))

    @property
    def want_capture_mouse(self) -> bool:
        """True when ImGui uses the mouse (over a window or dragging a widget); the app should ignore it."""
        return bool(self.io.want_capture_mouse)

    @property
    def want_capture_keyboard(self) -> bool:
        """True when ImGui uses the keyboard (e.g. a text field is active); the app should ignore it."""
        return bool(self.io.want_capture_keyboard)

    # ------------------------------------------------------------------ teardown

    def shutdown(self) -> None:
        """Release every GL object and texture this layer made and destroy its ImGui context (idempotent)."""
        if not self._alive:
            return
        self._activate()
        for tex in imgui.get_platform_io().textures:
            if tex.ref_count == 1 and tex.status != imgui.ImTextureStatus.destroyed:
                self._destroy_texture(tex)
        for texture in self._textures.values():
            texture.release()
        self._textures.clear()
        self._user_textures.clear()
        self.io.backend_flags &= ~(
            imgui.BackendFlags_.renderer_has_textures | imgui.BackendFlags_.renderer_has_vtx_offset
        )
        for obj in (self._vao, self._vbo, self._ibo, self._prog):
            obj.release()
        imgui.destroy_context(self._imgui_ctx)
        self._imgui_ctx = None
        self._alive = False

    @property
    def alive(self) -> bool:
        """False after ``shutdown()``."""
        return self._alive

    # ------------------------------------------------------------------ internals

    def _activate(self) -> None:
        if not self._alive:
            raise RuntimeError("ImGuiLayer was shut down")
        imgui.set_current_context(self._imgui_ctx)

    def _apply_display_size(self) -> None:
        w, h = self._window_size
        fw, fh = self._framebuffer_size
        self.io.display_size = (float(w), float(h))
        self.io.display_framebuffer_scale = (fw / w, fh / h) if w > 0 and h > 0 else (1.0, 1.0)

    def _mouse_button(self, x: float, y: float, button: int, down: bool) -> None:
        self._activate()
        self.io.add_mouse_pos_event(float(x), float(y))
        index = _MOUSE_BUTTONS.get(button)
        if index is not None:
            self.io.add_mouse_button_event(index, down)

    def _texture_for(self, tex_id: int) -> moderngl.Texture:
        texture = self._textures.get(tex_id) or self._user_textures.get(tex_id)
        if texture is None:
            raise KeyError(f"ImGui drew with texture id {tex_id}, which is neither an ImGui texture nor "
                           "registered with register_texture()")
        return texture

    def _update_textures(self) -> None:
        for tex in imgui.get_platform_io().textures:
            status = tex.status
            if status == imgui.ImTextureStatus.want_create:
                self._create_texture(tex)
            elif status == imgui.ImTextureStatus.want_updates:
                self._apply_texture_updates(tex)
            elif status == imgui.ImTextureStatus.want_destroy and tex.unused_frames > 0:
                # unused_frames > 0: the draw data just rendered no longer samples it (as imgui_impl_opengl3).
                self._destroy_texture(tex)

    def _create_texture(self, tex: imgui.ImTextureData) -> None:
        if tex.format != imgui.ImTextureFormat.rgba32:
            # We never ask for Alpha8 (io.fonts.tex_desired_format stays RGBA32).
            raise ValueError(f"unsupported ImGui texture format {tex.format!r}; only RGBA32 is handled")
        pixels = np.ascontiguousarray(tex.get_pixels_array())
        texture = self.ctx.texture((tex.width, tex.height), 4, data=pixels)
        # ImGui samples its atlas bilinearly and expects clamping at the edges.
        texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
        texture.repeat_x = False
        texture.repeat_y = False
        self._textures[texture.glo] = texture
        tex.set_tex_id(texture.glo)
        tex.set_status(imgui.ImTextureStatus.ok)
        self._stats["textures_created"] += 1

    def _apply_texture_updates(self, tex: imgui.ImTextureData) -> None:
        texture = self._textures[tex.tex_id]
        pixels = np.asarray(tex.get_pixels_array()).reshape(tex.height, tex.width, 4)
        for r in tex.updates:
            block = np.ascontiguousarray(pixels[r.y : r.y + r.h, r.x : r.x + r.w])
            texture.write(block, viewport=(r.x, r.y, r.w, r.h))
        tex.set_status(imgui.ImTextureStatus.ok)
        self._stats["texture_updates"] += 1

    def _destroy_texture(self, tex: imgui.ImTextureData) -> None:
        texture = self._textures.pop(tex.tex_id, None)
        if texture is not None:
            texture.release()
        tex.set_tex_id(0)  # ImTextureID_Invalid
        tex.set_status(imgui.ImTextureStatus.destroyed)
        self._stats["textures_destroyed"] += 1

    def _upload(self, draw_data: imgui.ImDrawData, fb_w: int, fb_h: int) -> list[tuple]:
        """Copy every draw list into the shared buffers; return (first index, count, tex id, scissor) items.

        moderngl has no glDrawElementsBaseVertex, so each list's indices are rebased onto its place in the
        shared vertex buffer plus the command's vtx_offset (which honours RendererHasVtxOffset).
        """
        off_x, off_y = draw_data.display_pos.x, draw_data.display_pos.y
        sx, sy = draw_data.framebuffer_scale.x, draw_data.framebuffer_scale.y
        vtx_chunks: list[bytes] = []
        idx_chunks: list[np.ndarray] = []
        items: list[tuple] = []
        vtx_base = 0
        idx_base = 0
        for draw_list in draw_data.cmd_lists:
            n_vtx = draw_list.vtx_buffer.size()
            n_idx = draw_list.idx_buffer.size()
            if n_vtx == 0 or n_idx == 0:
                continue
            vtx_chunks.append(ctypes.string_at(draw_list.vtx_buffer.data_address(), n_vtx * imgui.VERTEX_SIZE))
            raw = ctypes.string_at(draw_list.idx_buffer.data_address(), n_idx * imgui.INDEX_SIZE)
            idx = np.frombuffer(raw, dtype=_INDEX_DTYPE).astype(np.uint32)
            idx += np.uint32(vtx_base)
            for cmd in draw_list.cmd_buffer:
                count = cmd.elem_count
                if count == 0:
                    continue
                start = cmd.idx_offset
                if cmd.vtx_offset:
                    idx[start : start + count] += np.uint32(cmd.vtx_offset)
                clip = cmd.clip_rect
                x0 = max((clip.x - off_x) * sx, 0.0)
                y0 = max((clip.y - off_y) * sy, 0.0)
                x1 = min((clip.z - off_x) * sx, float(fb_w))
                y1 = min((clip.w - off_y) * sy, float(fb_h))
                if x1 <= x0 or y1 <= y0:
                    continue
                # GL's scissor origin is bottom-left, ImGui's clip origin top-left.
                scissor = (int(x0), int(fb_h - y1), int(x1 - x0), int(y1 - y0))
                items.append((idx_base + start, count, cmd.get_tex_id(), scissor))
            idx_chunks.append(idx)
            vtx_base += n_vtx
            idx_base += n_idx
        if not items:
            return items

        if vtx_base > self._vbo_capacity:
            self._vbo_capacity = 1 << (vtx_base - 1).bit_length()
        if idx_base > self._ibo_capacity:
            self._ibo_capacity = 1 << (idx_base - 1).bit_length()
        # Orphaning gives the driver fresh storage, so this frame's upload never waits on last frame's draw; the
        # writes go in pieces Mesa's driver thread queues (one larger write had the main thread do the frame's draws
        # not yet handed over: ~5 ms of its CPU a frame in the window on llvmpipe).
        self._vbo.orphan(self._vbo_capacity * imgui.VERTEX_SIZE)
        self._ibo.orphan(self._ibo_capacity * 4)
        write_queued(self._vbo, b"".join(vtx_chunks))
        write_queued(self._ibo, np.concatenate(idx_chunks))
        return items

    def _set_projection(self, draw_data: imgui.ImDrawData) -> None:
        left = draw_data.display_pos.x
        right = left + draw_data.display_size.x
        top = draw_data.display_pos.y
        bottom = top + draw_data.display_size.y
        # Column-major orthographic projection mapping ImGui's top-left origin to GL clip space.
        self._prog["ProjMtx"].value = (
            2.0 / (right - left), 0.0, 0.0, 0.0,
            0.0, 2.0 / (top - bottom), 0.0, 0.0,
            0.0, 0.0, -1.0, 0.0,
            (right + left) / (left - right), (top + bottom) / (bottom - top), 0.0, 1.0,
        )
