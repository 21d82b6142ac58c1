"""ImGuiLayer: draws ImGui 1.92+ (texture protocol) through ModernGL, headless under EGL."""

import ctypes

import moderngl
import numpy as np
import pytest
from imgui_bundle import imgui
from moderngl_window.context.base import BaseKeys, KeyModifiers

from app.imgui_layer import ImGuiLayer, build_key_map

W, H = 320, 240
WIN_POS = (20, 30)
WIN_SIZE = (200, 150)


@pytest.fixture(scope="module")
def ctx():
    context = moderngl.create_standalone_context(backend="egl")
    yield context
    context.release()


@pytest.fixture(autouse=True)
def current_ctx(ctx):
    # Creating another context (the moderngl-window test) makes it current; GL calls on `ctx` would then
    # silently go elsewhere, so every test makes `ctx` current first.
    with ctx:
        yield


@pytest.fixture(scope="module")
def fbo(ctx):
    # Module-scoped: releasing the framebuffer moderngl has bound would leave a dangling binding that the
    # next scope exit rebinds (GL_INVALID_OPERATION), so tests rebind this one before releasing their own.
    with ctx:  # module fixtures are set up before the autouse one that makes ctx current
        target = ctx.framebuffer(color_attachments=[ctx.texture((W, H), 4)])
    yield target
    with ctx:
        target.color_attachments[0].release()
        target.release()


def release_fbo(target, rebind):
    rebind.use()
    target.color_attachments[0].release()
    target.release()


@pytest.fixture
def layer(ctx):
    lay = ImGuiLayer(ctx, (W, H))
    yield lay
    lay.shutdown()


def read_rgba(fbo):
    """Framebuffer pixels as (H, W, 4) uint8, row 0 at the top (ImGui's orientation)."""
    w, h = fbo.size
    return np.frombuffer(fbo.read(components=4), dtype=np.uint8).reshape(h, w, 4)[::-1]


def rain_manager(value=0.5, pos=WIN_POS, size=WIN_SIZE):
    """The test panel; returns (slider value, whether the button was clicked, button rect min, max)."""
    imgui.set_next_window_pos(pos)
    imgui.set_next_window_size(size)
    imgui.begin("Rain Manager")
    imgui.text("Rain rate")
    _, value = imgui.slider_float("R [mm/h]", value, 0.0, 100.0)
    clicked = imgui.button("Wipers")
    rect_min, rect_max = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    imgui.end()
    return value, clicked, (rect_min.x, rect_min.y), (rect_max.x, rect_max.y)


def draw(ctx, layer, fbo, build=rain_manager, dt=1 / 60):
    layer.new_frame(dt)
    result = build()
    fbo.use()
    fbo.clear(0.0, 0.0, 0.0, 0.0)
    layer.render(fbo)
    return result


def test_window_pixels_inside_drawn_outside_black(ctx, layer, fbo):
    draw(ctx, layer, fbo)
    img = read_rgba(fbo)
    x0, y0 = WIN_POS
    x1, y1 = x0 + WIN_SIZE[0], y0 + WIN_SIZE[1]
    inside = img[y0 + 1 : y1 - 1, x0 + 1 : x1 - 1, :3].astype(int).sum(axis=2)
    assert (inside > 0).all()
    outside = img.copy()
    outside[y0 - 1 : y1 + 1, x0 - 1 : x1 + 1] = 0
    assert outside.max() == 0
    assert ctx.error == "GL_NO_ERROR"


def test_two_windows_two_draw_lists(ctx, layer, fbo):
    """Each window is its own draw list; both lists share one vertex/index buffer upload."""

    def panels():
        rain_manager()
        imgui.set_next_window_pos((240, 40))
        imgui.set_next_window_size((70, 60))
        imgui.begin("Stats")
        imgui.text("fps")
        imgui.end()

    layer.new_frame(1 / 60)
    panels()
    imgui.render()
    assert imgui.get_draw_data().cmd_lists_count >= 2
    draw(ctx, layer, fbo, panels)
    img = read_rgba(fbo)
    assert (img[42:98, 242:308, :3].astype(int).sum(axis=2) > 0).all()
    assert (img[32:178, 22:218, :3].astype(int).sum(axis=2) > 0).all()
    assert img[:, 222:238].max() == 0


def test_clip_rects_cut_content_at_the_window_edge(ctx, layer, fbo):
    def clipped():
        imgui.set_next_window_pos((20, 30))
        imgui.set_next_window_size((100, 60))
        imgui.begin("Clip", flags=imgui.WindowFlags_.no_scrollbar)
        for i in range(20):
            imgui.text(f"{i} " + "W" * 60)
        imgui.end()

    draw(ctx, layer, fbo, clipped)
    img = read_rgba(fbo)
    assert img[30:90, 20:120].max() > 0
    outside = img.copy()
    outside[29:91, 19:121] = 0
    assert outside.max() == 0


def test_blends_over_existing_content(ctx, layer, fbo):
    """A half-transparent panel background lets a red frame underneath show through."""

    def translucent_panel():
        imgui.push_style_color(imgui.Col_.window_bg, (0.2, 0.2, 0.2, 0.5))
        rain_manager()
        imgui.pop_style_color()

    draw(ctx, layer, fbo, translucent_panel)
    over_black = read_rgba(fbo)[160, 100].astype(int)
    layer.new_frame(1 / 60)
    translucent_panel()
    fbo.use()
    fbo.clear(1.0, 0.0, 0.0, 1.0)
    layer.render(fbo)
    over_red = read_rgba(fbo)[160, 100].astype(int)
    assert abs(over_black[0] - 0.1 * 255) <= 2  # 0.2 grey at 50 % over black
    assert abs(over_red[0] - (0.5 + 0.1) * 255) <= 2  # red shows through at 50 %
    assert abs(over_red[1] - over_black[1]) <= 1


def test_font_atlas_created_once_over_many_frames(ctx, layer, fbo):
    draw(ctx, layer, fbo)
    draw(ctx, layer, fbo)  # a window's first frame differs slightly (appearing state); compare from the 2nd
    atlas = imgui.get_io().fonts.tex_data
    assert atlas.status == imgui.ImTextureStatus.ok
    assert atlas.tex_id in layer.textures
    assert layer.textures[atlas.tex_id].size == (atlas.width, atlas.height)
    first = read_rgba(fbo)
    for _ in range(5):
        draw(ctx, layer, fbo)
        assert ctx.error == "GL_NO_ERROR"
    assert layer.stats["textures_created"] == 1
    assert layer.stats["draw_calls"] >= 1
    assert len(layer.textures) == 1
    np.testing.assert_array_equal(read_rgba(fbo), first)


def test_button_click_by_simulated_mouse(ctx, layer, fbo):
    _, clicked, rmin, rmax = draw(ctx, layer, fbo)
    assert not clicked
    cx, cy = (rmin[0] + rmax[0]) / 2, (rmin[1] + rmax[1]) / 2
    # One event kind per frame: ImGui's trickled input queue would spread them anyway.
    layer.mouse_position_event(cx, cy, 0, 0)
    assert not draw(ctx, layer, fbo)[1]
    assert layer.want_capture_mouse
    layer.mouse_press_event(cx, cy, 1)
    assert not draw(ctx, layer, fbo)[1]
    layer.mouse_release_event(cx, cy, 1)
    assert draw(ctx, layer, fbo)[1]
    assert not draw(ctx, layer, fbo)[1]  # a click is reported once


def test_right_button_does_not_click_and_outside_is_not_captured(ctx, layer, fbo):
    _, _, rmin, rmax = draw(ctx, layer, fbo)
    cx, cy = (rmin[0] + rmax[0]) / 2, (rmin[1] + rmax[1]) / 2
    layer.mouse_position_event(cx, cy, 0, 0)
    draw(ctx, layer, fbo)
    layer.mouse_press_event(cx, cy, 2)
    draw(ctx, layer, fbo)
    layer.mouse_release_event(cx, cy, 2)
    assert not draw(ctx, layer, fbo)[1]
    layer.mouse_position_event(300, 220, 0, 0)
    draw(ctx, layer, fbo)
    assert not layer.want_capture_mouse


def test_drag_moves_slider(ctx, layer, fbo):
    value = 0.5

    def panel():
        nonlocal value
        value, _, _, _ = rain_manager(value)
        return value

    layer.new_frame(1 / 60)
    imgui.set_next_window_pos(WIN_POS)
    imgui.set_next_window_size(WIN_SIZE)
    imgui.begin("Rain Manager")
    imgui.text("Rain rate")
    imgui.slider_float("R [mm/h]", value, 0.0, 100.0)
    smin, smax = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    imgui.end()
    layer.render(fbo)
    y = (smin.y + smax.y) / 2
    layer.mouse_position_event(smin.x + 2, y, 0, 0)
    draw(ctx, layer, fbo, panel)
    layer.mouse_press_event(smin.x + 2, y, 1)
    draw(ctx, layer, fbo, panel)
    layer.mouse_drag_event(smax.x - 2, y, smax.x - smin.x - 4, 0)
    draw(ctx, layer, fbo, panel)
    layer.mouse_release_event(smax.x - 2, y, 1)
    draw(ctx, layer, fbo, panel)
    assert value > 90.0


def test_scroll_wheel_scrolls_window(ctx, layer, fbo):
    scroll = []

    def long_panel():
        imgui.set_next_window_pos(WIN_POS)
        imgui.set_next_window_size(WIN_SIZE)
        imgui.begin("Log")
        for i in range(60):
            imgui.text(f"line {i}")
        scroll.append(imgui.get_scroll_y())
        imgui.end()

    draw(ctx, layer, fbo, long_panel)
    layer.mouse_position_event(WIN_POS[0] + 50, WIN_POS[1] + 60, 0, 0)
    draw(ctx, layer, fbo, long_panel)
    layer.mouse_scroll_event(0.0, -3.0)
    for _ in range(3):
        draw(ctx, layer, fbo, long_panel)
    assert scroll[0] == 0.0
    assert scroll[-1] > 0.0


class FakeKeys(BaseKeys):
    """Key codes like a real window library's (the headless window leaves them all 'undefined')."""

    ACTION_PRESS = 1
    ACTION_RELEASE = 0
    BACKSPACE = 259
    A = 65
    TAB = 258
    LEFT = 263
    RIGHT = 263  # a library that reuses a code: ambiguous, must be dropped


def test_build_key_map_skips_undefined_and_ambiguous():
    key_map = build_key_map(FakeKeys)
    assert key_map[65] == imgui.Key.a
    assert key_map[259] == imgui.Key.backspace
    assert 263 not in key_map
    assert "undefined" not in key_map
    assert build_key_map(BaseKeys) == {}


def test_text_input_keys_and_modifiers(ctx, fbo):
    layer = ImGuiLayer(ctx, (W, H), keys=FakeKeys)
    text = ""

    def panel():
        nonlocal text
        imgui.set_next_window_pos(WIN_POS)
        imgui.set_next_window_size(WIN_SIZE)
        imgui.begin("Rain Manager")
        _, text = imgui.input_text("Preset", text)
        rmin, rmax = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        imgui.end()
        return (rmin.x + rmax.x) / 2, (rmin.y + rmax.y) / 2

    try:
        cx, cy = draw(ctx, layer, fbo, panel)
        assert not layer.want_capture_keyboard
        layer.mouse_position_event(cx, cy, 0, 0)
        draw(ctx, layer, fbo, panel)
        layer.mouse_press_event(cx, cy, 1)
        draw(ctx, layer, fbo, panel)
        layer.mouse_release_event(cx, cy, 1)
        draw(ctx, layer, fbo, panel)
        assert layer.want_capture_keyboard
        layer.unicode_char_entered("hi")
        for _ in range(3):
            draw(ctx, layer, fbo, panel)
        assert text == "hi"
        layer.key_event(FakeKeys.BACKSPACE, FakeKeys.ACTION_PRESS, KeyModifiers())
        draw(ctx, layer, fbo, panel)
        layer.key_event(FakeKeys.BACKSPACE, FakeKeys.ACTION_RELEASE, KeyModifiers())
        draw(ctx, layer, fbo, panel)
        assert text == "h"
        mods = KeyModifiers()
        mods.ctrl = True
        layer.key_event(FakeKeys.A, FakeKeys.ACTION_PRESS, mods)
        layer.new_frame(1 / 60)
        assert imgui.get_io().key_ctrl
        assert imgui.is_key_down(imgui.Key.a)
        imgui.end_frame()
    finally:
        layer.shutdown()


def test_headless_keys_are_ignored(ctx, layer, fbo):
    from moderngl_window.context.headless.keys import Keys

    layer.key_event(Keys.A, Keys.ACTION_PRESS, KeyModifiers(), keys=Keys)
    layer.key_event(Keys.ESCAPE, Keys.ACTION_PRESS, KeyModifiers())  # no keys known at all
    draw(ctx, layer, fbo)
    assert ctx.error == "GL_NO_ERROR"


def test_new_glyph_sizes_update_and_grow_the_atlas(ctx, fbo):
    """Text at new sizes makes ImGui request texture updates, then a bigger atlas and the old one destroyed.

    The updated atlas must draw exactly what an atlas baked with those glyphs from the start draws.
    """

    def text_at(size):
        def build():
            imgui.set_next_window_pos((0, 0))
            imgui.set_next_window_size((W, H))
            imgui.begin("Text", flags=imgui.WindowFlags_.no_decoration)
            imgui.push_font(None, size)
            imgui.text("Rain 0123 WXYZ")
            imgui.pop_font()
            imgui.end()

        return build

    grown = ImGuiLayer(ctx, (W, H))
    fresh = ImGuiLayer(ctx, (W, H))
    try:
        for size in (13.0, 30.0, 45.0):
            draw(ctx, grown, fbo, text_at(size))
        updated = read_rgba(fbo)
        assert grown.stats["texture_updates"] >= 1
        draw(ctx, fresh, fbo, text_at(45.0))
        assert fresh.stats["texture_updates"] == 0
        np.testing.assert_array_equal(updated, read_rgba(fbo))

        for size in range(60, 200, 20):
            draw(ctx, grown, fbo, text_at(float(size)))
            for tex in imgui.get_platform_io().textures:
                if tex.status != imgui.ImTextureStatus.ok:  # answered: destroyed, with no id left
                    assert tex.status == imgui.ImTextureStatus.destroyed
                    assert tex.tex_id == 0
        for _ in range(3):
            draw(ctx, grown, fbo, text_at(13.0))
        stats = grown.stats
        assert stats["textures_created"] >= 2
        assert stats["textures_destroyed"] == stats["textures_created"] - 1
        assert len(grown.textures) == 1
        assert ctx.error == "GL_NO_ERROR"
    finally:
        grown.shutdown()
        fresh.shutdown()


def test_registered_user_texture_is_drawn(ctx, layer, fbo):
    red = ctx.texture((4, 4), 4, data=np.tile(np.array([255, 0, 0, 255], np.uint8), 16).tobytes())
    ref = layer.register_texture(red)

    def panel():
        imgui.set_next_window_pos((0, 0))
        imgui.set_next_window_size((W, H))
        imgui.begin("Image", flags=imgui.WindowFlags_.no_decoration)
        imgui.set_cursor_pos((100, 100))
        imgui.image(ref, (40, 40))
        imgui.end()

    draw(ctx, layer, fbo, panel)
    img = read_rgba(fbo)
    assert (img[105:135, 105:135] == np.array([255, 0, 0, 255], np.uint8)).all()
    layer.unregister_texture(red)
    layer.new_frame(1 / 60)
    panel()
    with pytest.raises(KeyError, match="register_texture"):
        layer.render(fbo)
    red.release()


def _gl_query(ctx):
    """glIsEnabled / glGetIntegerv from the context's own loader (moderngl cannot read enable flags)."""
    loader = getattr(ctx.mglo, "_context", None)
    if loader is None or not hasattr(loader, "load"):
        pytest.skip("this moderngl build does not expose its GL loader")
    is_enabled = ctypes.CFUNCTYPE(ctypes.c_ubyte, ctypes.c_uint)(loader.load("glIsEnabled"))
    get_integerv = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.POINTER(ctypes.c_int))(
        loader.load("glGetIntegerv")
    )

    def get_ints(pname, n):
        out = (ctypes.c_int * n)()
        get_integerv(pname, out)
        return list(out)

    return is_enabled, get_ints


GL_BLEND, GL_DEPTH_TEST, GL_CULL_FACE, GL_SCISSOR_TEST = 0x0BE2, 0x0B71, 0x0B44, 0x0C11
GL_SCISSOR_BOX, GL_VIEWPORT, GL_FRAMEBUFFER_BINDING = 0x0C10, 0x0BA2, 0x8CA6


def test_render_restores_gl_state(ctx, layer, fbo):
    is_enabled, get_ints = _gl_query(ctx)
    other = ctx.framebuffer(color_attachments=[ctx.texture((64, 32), 4)])
    try:
        for scissor in (None, (5, 6, 7, 8)):
            other.use()
            ctx.enable_only(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
            fbo.viewport = (10, 20, 100, 50)
            fbo.scissor = scissor
            layer.new_frame(1 / 60)
            rain_manager()
            layer.render(fbo)  # into fbo while `other` stays bound
            # Drawn despite the depth test / culling enabled beforehand (ImGui turns them off for itself).
            assert read_rgba(fbo)[WIN_POS[1] + 100, WIN_POS[0] + 100, :3].sum() > 0
            assert get_ints(GL_FRAMEBUFFER_BINDING, 1) == [other.glo]
            assert is_enabled(GL_DEPTH_TEST) and is_enabled(GL_CULL_FACE)
            assert not is_enabled(GL_BLEND)
            assert not is_enabled(GL_SCISSOR_TEST)
            assert fbo.viewport == (10, 20, 100, 50)
            fbo.use()
            assert get_ints(GL_VIEWPORT, 4) == [10, 20, 100, 50]
            if scissor is None:
                assert not is_enabled(GL_SCISSOR_TEST)
            else:
                assert is_enabled(GL_SCISSOR_TEST)
                assert get_ints(GL_SCISSOR_BOX, 4) == list(scissor)
            assert not ctx.wireframe
            assert ctx.error == "GL_NO_ERROR"
    finally:
        fbo.viewport = (0, 0, W, H)
        fbo.scissor = None
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        release_fbo(other, fbo)


def test_vertices_go_in_writes_mesas_driver_thread_queues(ctx, layer, fbo, monkeypatch):
    # Drawn behind the frame's draws, a write too large for the driver thread's queue waited for it to do them:
    # ~5 ms of the main thread a frame in the window on llvmpipe (python -m rain_core.bench panel).
    from rain_core.gfx.driver import QUEUED_WRITE_BYTES

    sizes = []
    write = moderngl.Buffer.write

    def spy(self, data, offset=0):
        sizes.append(memoryview(data).nbytes)
        return write(self, data, offset=offset)

    monkeypatch.setattr(moderngl.Buffer, "write", spy)

    def many_widgets():
        imgui.set_next_window_pos((0, 0))
        imgui.set_next_window_size((W, H))
        imgui.begin("More")
        for k in range(40):
            imgui.text(f"line {k} of text to draw")
        imgui.end()

    draw(ctx, layer, fbo, build=many_widgets)
    assert sum(sizes) > 4 * QUEUED_WRITE_BYTES  # several pieces' worth of vertices
    assert max(sizes) <= QUEUED_WRITE_BYTES
    assert (read_rgba(fbo)[..., 3] > 0).mean() > 0.9  # and drawn


def test_render_without_framebuffer_target_raises(ctx, layer, monkeypatch):
    monkeypatch.setattr(ctx, "fbo", None)  # a standalone context before any framebuffer.use()
    layer.new_frame(1 / 60)
    with pytest.raises(ValueError, match="framebuffer"):
        layer.render()


def test_framebuffer_scale_and_resize(ctx, fbo):
    big = ctx.framebuffer(color_attachments=[ctx.texture((2 * W, 2 * H), 4)])
    lay = ImGuiLayer(ctx, (W // 2, H // 2))
    try:
        # Half-size window in points on a full-size framebuffer: everything drawn at 2x pixel scale.
        lay.resize((W, H), (2 * W, 2 * H))
        assert tuple(lay.io.display_size) == (W, H)
        draw(ctx, lay, big)
        img = read_rgba(big)
        x0, y0 = 2 * WIN_POS[0], 2 * WIN_POS[1]
        x1, y1 = x0 + 2 * WIN_SIZE[0], y0 + 2 * WIN_SIZE[1]
        assert (img[y0 + 2 : y1 - 2, x0 + 2 : x1 - 2, :3].astype(int).sum(axis=2) > 0).all()
        assert img[: y0 - 2].max() == 0 and img[y1 + 2 :].max() == 0
        assert img[:, : x0 - 2].max() == 0 and img[:, x1 + 2 :].max() == 0

        lay.resize((W, H))
        draw(ctx, lay, fbo)
        img = read_rgba(fbo)
        assert img[WIN_POS[1] + 20, WIN_POS[0] + 20, :3].sum() > 0
        assert img[WIN_POS[1] + WIN_SIZE[1] + 5 :].max() == 0
        with pytest.raises(ValueError, match="window_size"):
            lay.resize((-1, 10))
        lay.resize((0, 0))  # minimised window: nothing to draw, no error
        draw(ctx, lay, fbo)
        assert read_rgba(fbo).max() == 0
        assert ctx.error == "GL_NO_ERROR"
    finally:
        lay.shutdown()
        release_fbo(big, fbo)


def test_zero_or_bad_dt_is_clamped(ctx, layer, fbo):
    for dt in (0.0, -1.0, float("nan")):
        draw(ctx, layer, fbo, dt=dt)
        assert imgui.get_io().delta_time > 0.0


def test_shutdown_releases_everything(ctx, fbo):
    lay = ImGuiLayer(ctx, (W, H))
    draw(ctx, lay, fbo)
    textures = list(lay.textures.values())
    assert textures
    lay.shutdown()
    assert not lay.alive
    assert lay.textures == {}
    assert all(isinstance(t.mglo, moderngl.InvalidObject) for t in textures)
    with pytest.raises(RuntimeError, match="shut down"):
        lay.new_frame(1 / 60)
    lay.shutdown()  # idempotent
    again = ImGuiLayer(ctx, (W, H))  # a fresh context works after the old one is gone
    try:
        draw(ctx, again, fbo)
        assert read_rgba(fbo).max() > 0
    finally:
        again.shutdown()


def test_two_layers_keep_separate_contexts(ctx, fbo):
    a = ImGuiLayer(ctx, (W, H))
    b = ImGuiLayer(ctx, (W, H))
    try:
        draw(ctx, a, fbo)
        draw(ctx, b, fbo, lambda: None)
        assert read_rgba(fbo).max() == 0  # b has no windows: a's panel did not leak into it
        draw(ctx, a, fbo)
        assert read_rgba(fbo).max() > 0
    finally:
        a.shutdown()
        b.shutdown()


def test_with_moderngl_window_headless_window(monkeypatch):
    import moderngl_window
    from moderngl_window.conf import settings

    monkeypatch.setitem(settings.WINDOW, "class", "moderngl_window.context.headless.Window")
    monkeypatch.setitem(settings.WINDOW, "backend", "egl")
    monkeypatch.setitem(settings.WINDOW, "size", (W, H))
    monkeypatch.setitem(settings.WINDOW, "aspect_ratio", None)
    monkeypatch.setitem(settings.WINDOW, "vsync", False)
    wnd = moderngl_window.create_window_from_settings()
    lay = ImGuiLayer(wnd.ctx, wnd.size, wnd.buffer_size, keys=wnd.keys)
    try:
        for _ in range(2):
            wnd.clear(0.0, 0.0, 0.0, 0.0)
            lay.new_frame(1 / 60)
            rain_manager()
            lay.render()  # into the window's framebuffer, bound by wnd.clear()
            wnd.swap_buffers()
        lay.key_event(wnd.keys.A, wnd.keys.ACTION_PRESS, KeyModifiers())  # headless keys: "undefined"
        img = read_rgba(wnd.fbo)
        x0, y0 = WIN_POS
        assert img[y0 + 10, x0 + 10, :3].sum() > 0
        assert img[y0 + WIN_SIZE[1] + 5 :].max() == 0
        assert lay.stats["textures_created"] == 1
        assert wnd.ctx.error == "GL_NO_ERROR"
    finally:
        lay.shutdown()
        wnd.destroy()
