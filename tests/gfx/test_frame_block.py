"""The frame block (shaders/common/frame.glsl): the Python std140 layout is the one GL uses, every program of a
frame reads it, programs with their own lights still get plain uniforms (the rain's hold theirs in its own block),
and renderers sharing a context or a shader library do not see each other's values."""

import dataclasses

import moderngl
import numpy as np
import pytest

from rain_core.effects.rainfall.rain_block import RAIN_FRAME_BYTES
from rain_core.effects.road import RoadEffect
from rain_core.gfx import frame_block
from rain_core.gfx.frame_block import BLOCK_BYTES, BLOCK_BYTES_OWN_LIGHTS, BLOCK_WORDS, FRAME_BLOCK_LAYOUT
from rain_core.gfx.renderer import Renderer
from rain_core.gfx.uniforms import OwnedUniforms, owned_uniforms
from rain_core.paths import SHADERS_DIR
from rain_core.scene import Scene
from rain_core.settings import Settings, set_value

SIZE = (96, 54)


def _random_values(rng) -> dict:
    values = {}
    for name, (_offset, count, kind) in FRAME_BLOCK_LAYOUT.items():
        if kind == "i":
            values[name] = int(rng.integers(1, 32))
        elif kind == "b":
            values[name] = rng.uniform(-100.0, 100.0, count).astype(np.float32).tobytes()
        else:
            v = rng.uniform(-100.0, 100.0, count)
            values[name] = float(v[0]) if count == 1 else tuple(float(x) for x in v)
    return values


def _pack_numpy(values: dict) -> bytes:
    """The frame block packed by NumPy assignments (what ``pack`` did before it used struct): the twin."""
    words = np.zeros(BLOCK_WORDS, np.float32)
    for name, value in values.items():
        slot = FRAME_BLOCK_LAYOUT.get(name)
        if slot is None:
            continue
        offset, count, kind = slot
        if kind == "b":
            src = np.frombuffer(value if isinstance(value, bytes) else np.ascontiguousarray(value, np.float32),
                                np.float32)
            words[offset:offset + min(src.size, count)] = src[:count]
        elif kind == "i":
            words[offset:offset + 1].view(np.int32)[0] = int(value)
        else:
            words[offset:offset + count] = value
    return words.tobytes()


@pytest.mark.filterwarnings("ignore:overflow encountered in cast")
@pytest.mark.parametrize("seed", range(5))
def test_pack_gives_numpy_float32_bytes(seed):
    rng = np.random.default_rng(seed)
    values = _random_values(rng)
    # Values as the renderer passes them: float64 arrays, NumPy scalars, a number for a vec3, short light bytes,
    # an overflow (inf in float32), a NaN, a name outside the block.
    values["u_camera_pos"] = rng.normal(0.0, 1e3, 3)
    values["u_exposure"] = np.float64(rng.uniform(0.0, 1e-3))
    values["u_sun_illum"] = float(rng.uniform(0.0, 1e5))
    values["u_light_pos"] = values["u_light_pos"][: 4 * 4 * 3]
    values["u_view_proj"] = rng.normal(size=(4, 4)).T.copy()
    values["u_night"] = 1e39
    values["u_time"] = float("nan")
    values["u_not_in_block"] = (1.0, 2.0)
    assert frame_block.pack(values) == _pack_numpy(values)


@pytest.mark.parametrize("seed", range(5))
def test_pack_changes_equals_a_full_pack(seed):
    """FrameBlocks.pack repacks only entries that are not the same objects as last time: every sequence of
    views (a light list shorter than the last, a new name, a name gone, values equal but new objects) gives the
    bytes of a full pack."""
    rng = np.random.default_rng(seed)
    blocks = frame_block.FrameBlocks.__new__(frame_block.FrameBlocks)
    blocks._packed = None
    values = _random_values(rng)
    for step in range(12):
        values = dict(values)
        for name in rng.choice(list(FRAME_BLOCK_LAYOUT), size=int(rng.integers(0, 6)), replace=False):
            values[name] = _random_values(rng)[name]
        if step % 3 == 1:  # fewer lights: the tail of the slots must be 0 again
            values["u_light_pos"] = values["u_light_pos"][: 16 * int(rng.integers(0, 8))]
        if step % 4 == 2:
            values.pop("u_shadow_matrix", None)
        if step % 4 == 3:
            values["u_shadow_matrix"] = rng.normal(size=(4, 4))
        assert blocks.pack(values) == frame_block.pack(values)
        assert blocks.pack(values) == frame_block.pack(values)  # the same dict again


def _readback_shader() -> str:
    """A fragment shader writing word i of the block (read by member name) into pixel x = i."""
    branches = []
    for name, (offset, count, kind) in FRAME_BLOCK_LAYOUT.items():
        if kind == "i":
            branches.append(f"if (i == {offset}) v = float({name});")
        elif name.startswith("u_light_"):  # vec4[MAX_LIGHTS]
            branches.append(f"if (i >= {offset} && i < {offset + count}) "
                            f"v = {name}[(i - {offset}) / 4][(i - {offset}) % 4];")
        elif kind == "b":  # mat4: column-major words
            branches.append(f"if (i >= {offset} && i < {offset + 16}) "
                            f"v = {name}[(i - {offset}) / 4][(i - {offset}) % 4];")
        elif count == 1:
            branches.append(f"if (i == {offset}) v = {name};")
        else:
            branches.append(f"if (i >= {offset} && i < {offset + count}) v = {name}[i - {offset}];")
    body = "\n    ".join(branches)
    return ("#version 330 core\n#include \"common/frame.glsl\"\nout vec4 f_color;\nvoid main() {\n"
            f"    int i = int(gl_FragCoord.x);\n    float v = -1.0e30;\n    {body}\n    f_color = vec4(v);\n}}\n")


def test_python_layout_is_the_std140_layout_gl_reads(gl_ctx, shaders, tmp_path):
    (tmp_path / "readback.frag").write_text(_readback_shader())
    source = shaders.preprocess(str(tmp_path / "readback.frag")).text
    prog = gl_ctx.program(vertex_shader=shaders.preprocess("common/fullscreen.vert").text, fragment_shader=source)
    assert prog["FrameBlock"].size == BLOCK_BYTES
    values = _random_values(np.random.default_rng(3))
    data = frame_block.pack(values)
    assert len(data) == BLOCK_BYTES
    buffer = gl_ctx.buffer(data)
    target = gl_ctx.texture((BLOCK_WORDS, 1), 4, dtype="f4")
    fbo = gl_ctx.framebuffer(color_attachments=[target])
    vao = gl_ctx.vertex_array(prog, [])
    try:
        buffer.bind_to_uniform_block(frame_block.BINDING)
        prog["FrameBlock"].binding = frame_block.BINDING
        fbo.use()
        gl_ctx.disable(moderngl.BLEND)
        vao.render(moderngl.TRIANGLES, vertices=3)
        got = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).reshape(-1, 4)[:, 0]
    finally:
        gl_ctx.detect_framebuffer(0).use()
        for obj in (vao, fbo, target, buffer, prog):
            obj.release()
    expected = np.frombuffer(data, np.float32).copy()
    for name, (offset, _count, kind) in FRAME_BLOCK_LAYOUT.items():
        if kind == "i":  # an int member: the shader wrote float(int)
            expected[offset] = float(values[name])
    members = np.zeros(BLOCK_WORDS, bool)  # std140 padding words are not members
    for offset, count, _ in FRAME_BLOCK_LAYOUT.values():
        members[offset:offset + count] = True
    np.testing.assert_array_equal(got[members], expected[members])
    unpacked = frame_block.unpack(data)
    assert unpacked["u_light_count"] == values["u_light_count"]
    assert unpacked["u_exposure"] == pytest.approx(values["u_exposure"], rel=1e-6)


def _own_lights_program(ctx) -> moderngl.Program:
    """A program that declares the frame's lights plainly (FRAME_OWN_LIGHTS, its own declarations) and reads them."""
    frame_glsl = (SHADERS_DIR / "common" / "frame.glsl").read_text()
    vertex = ("#version 330 core\n#define FRAME_OWN_LIGHTS\n" + frame_glsl
              + "uniform int u_light_count;\nuniform vec4 u_light_pos[MAX_LIGHTS];\n"
                "uniform vec4 u_light_dir[MAX_LIGHTS];\nuniform vec4 u_light_color[MAX_LIGHTS];\n"
              + "void main() { int i = u_light_count - 1;"  # indexed at run time: every array whole
                " gl_Position = u_view_proj * u_light_pos[i] + u_light_dir[i] + u_light_color[i]; }\n")
    return ctx.program(vertex_shader=vertex, fragment_shader="#version 330 core\nout vec4 c;\n"
                                                             "void main() { c = vec4(1.0); }\n")


def test_scene_programs_read_the_block_and_rainfall_keeps_its_own_lights(gl_ctx):
    settings = Settings()
    set_value(settings, "rain.rate_mm_h", 8.0)
    scene = Scene(gl_ctx, SIZE, settings=settings, seed=1)
    own = _own_lights_program(gl_ctx)
    try:
        scene.step(1 / 30)
        frame = scene.render()
        renderer = scene.renderer
        for prog in (renderer.scene.scene_prog, renderer.scene.sky_prog):
            assert prog["FrameBlock"].size == BLOCK_BYTES
            assert prog.get("u_view_proj", None) is None and prog.get("u_light_pos", None) is None
        # The rain's programs keep their own light list (the lights that reach its boxes): not the frame block's,
        # and not plain uniforms either, but members of the rain's own per-frame block (rain_frame.glsl).
        rainfall = next(e for e in scene.effects if e.name == "rainfall")
        streak = rainfall.record_prog  # the streaks' drop work: their frame values
        assert streak["FrameBlock"].size == BLOCK_BYTES_OWN_LIGHTS  # FRAME_OWN_LIGHTS: no lights in the block
        assert streak.get("u_light_pos", None) is None and streak.get("u_light_count", None) is None
        assert streak["RainFrame"].size == RAIN_FRAME_BYTES
        rc = renderer.render_context(frame)
        held = rainfall._frame_buffer.read()
        rc.set_frame_uniforms(streak)  # binds the frame block; the rain's lights are not its to write
        assert rainfall._frame_buffer.read() == held
        # set_frame_uniforms writes the frame's lights into a program that declares them plainly
        assert own["FrameBlock"].size == BLOCK_BYTES_OWN_LIGHTS
        rc.set_frame_uniforms(own)
        assert own["u_light_count"].value == rc.lights[3]
        assert own["u_light_pos"].read() == rc.lights[0]
        assert own["u_light_color"].read() == rc.lights[2]
        # and binds a buffer holding this context's block
        rc.set_frame_uniforms(renderer.scene.scene_prog)
        values = frame_block.unpack(renderer.frame_blocks.read_bound())
        assert values["u_light_count"] == rc.lights[3]
        assert values["u_time"] == pytest.approx(frame.time_s, rel=1e-6)
        np.testing.assert_allclose(values["u_camera_pos"], rc.camera_position, rtol=1e-6)
        # the shadow's uniforms (frame uniforms added after the context was made) reach the block too
        rc.uniforms["u_shadow_params"] = (1.0, 0.25, 0.5)
        rc.set_frame_uniforms(renderer.scene.scene_prog)
        assert frame_block.unpack(renderer.frame_blocks.read_bound())["u_shadow_params"] == (1.0, 0.25, 0.5)
    finally:
        own.release()
        scene.release()


def _scene(gl_ctx, hour: float) -> Scene:
    """No effects: their simulations step at every render, so only the built-in scene draws the same twice."""
    settings = Settings()
    set_value(settings, "time_of_day.hour", hour)
    return Scene(gl_ctx, SIZE, settings=settings, seed=2, gpu_timing=False, effects=[])


def test_two_renderers_on_one_context_alternate_without_mixing_their_frames(gl_ctx):
    noon, night = _scene(gl_ctx, 12.0), _scene(gl_ctx, 22.0)
    try:
        for scene in (noon, night):
            scene.step(1 / 30)
        f_noon, f_night = noon.frame(), night.frame()
        noon.renderer.render(f_noon)
        first = noon.renderer.hdr_image()
        night.renderer.render(f_night)
        other = night.renderer.hdr_image()
        noon.renderer.render(f_noon)
        again = noon.renderer.hdr_image()
        np.testing.assert_array_equal(again, first)
        assert np.abs(other - first).max() > 0.01
    finally:
        noon.release()
        night.release()


def test_plain_values_follow_each_new_dict_and_its_names(gl_ctx):
    """A view's values are a new dict every frame: a program's plain pairs follow the values and the names as they
    come and go, while dicts of the same names share one names tuple (FrameBlocks.keys_of)."""

    class Program:  # what _ProgramInfo asks of a moderngl program
        glo = 1
        get = {"u_time": "time uniform", "u_shadow_map": "shadow uniform"}.get

    blocks = frame_block.FrameBlocks(gl_ctx)
    try:
        info = blocks.program_info(Program())
        a = {"u_exposure": 2.0, "u_time": 1.0}
        assert info.plain_values(a) == (("time uniform", 1.0),)
        b = {"u_exposure": 2.0, "u_time": 3.0}
        assert blocks.keys_of(b) is blocks.keys_of(a)
        assert info.plain_values(b) == (("time uniform", 3.0),)
        with_shadow = {"u_exposure": 2.0, "u_time": 4.0, "u_shadow_map": 5}
        assert info.plain_values(with_shadow) == (("time uniform", 4.0), ("shadow uniform", 5))
        assert info.plain_values({"u_exposure": 2.0}) == ()
        assert info.plain_values(b) == (("time uniform", 3.0),)
    finally:
        blocks.release()


def test_road_uniforms_skipped_only_when_unchanged_across_effects_sharing_a_program(gl_ctx):
    """Two renderers share one shader library (so one scene program) with a road effect each, at different
    puddle amounts: the road's skip-unchanged writes must not leave one road's values for the other."""
    a = Scene(gl_ctx, SIZE, settings=_scene_settings(0.9), seed=2, gpu_timing=False,
              effects=[RoadEffect(gl_ctx, _scene_settings(0.9))])
    settings_b = _scene_settings(0.2)
    rb = Renderer(gl_ctx, SIZE, a.world, effects=[RoadEffect(gl_ctx, settings_b)], shaders=a.renderer.shaders,
                  gpu_timing=False)
    try:
        a.step(1 / 30)
        fa = a.frame()
        fb = dataclasses.replace(fa, settings=settings_b)
        a.renderer.render(fa)
        first = a.renderer.hdr_image()
        rb.render(fb)
        other = rb.hdr_image()
        a.renderer.render(fa)
        np.testing.assert_array_equal(a.renderer.hdr_image(), first)
        assert np.abs(other - first).max() > 0.0
    finally:
        rb.release()
        a.release()


def _scene_settings(puddle_amount: float) -> Settings:
    settings = Settings()
    set_value(settings, "time_of_day.hour", 12.0)
    for level in ("wetness", "cracks", "puddles"):
        set_value(settings, f"rain.{level}", 1.0)
    set_value(settings, "road.puddle_amount", puddle_amount)
    return settings


class _Counting:
    def __init__(self):
        self.writes = []

    def get(self, name, default=None):
        return _Uniform(self.writes, name)


class _Uniform:
    def __init__(self, writes, name):
        self.writes, self.name = writes, name

    def write(self, data):
        self.writes.append((self.name, data))

    @property
    def value(self):
        return None

    @value.setter
    def value(self, v):
        self.writes.append((self.name, v))


def test_owned_uniforms_skip_only_equal_values():
    prog = _Counting()
    owned = OwnedUniforms(prog)
    owned.set("u_a", 1.0)
    owned.set("u_a", 1.0)
    owned.set("u_a", 2.0)
    owned.set("u_b", (1.0, 2.0))
    owned.set("u_b", (1.0, 2.0))
    owned.set("u_c", np.array([1.0, 2.0]))
    owned.set("u_c", np.array([1.0, 2.0]))
    owned.set("u_c", np.array([1.0, 3.0]))
    owned.set("u_d", 1)
    owned.set("u_d", 1.0)  # another type: written (an int and a float uniform are different things)
    assert [w[0] for w in prog.writes] == ["u_a", "u_a", "u_b", "u_c", "u_c", "u_d", "u_d"]


class _Program(dict):
    """A program declaring ``names`` (moderngl's Program.get), logging every write."""

    __hash__ = object.__hash__  # a program is its own key in owned_uniforms' weak table
    __eq__ = object.__eq__

    def __init__(self, names):
        self.writes = []
        super().__init__({n: _Uniform(self.writes, n) for n in names})


def test_owned_uniforms_pairs_once_and_assume():
    """update_pairs skips equal values and names the program lacks; assume records another writer's value (the
    next differing value is written); update_once skips the very tuple it last wrote in full."""
    prog = _Program(["u_box_lo", "u_light_count", "u_time_frac"])
    owned = owned_uniforms(prog)
    owned.update_pairs([("u_box_lo", b"\0" * 12), ("u_time_frac", 0.5), ("u_missing", 1.0)])
    owned.update_pairs([("u_box_lo", b"\0" * 12), ("u_time_frac", 0.5), ("u_missing", 1.0)])
    assert prog.writes == [("u_box_lo", b"\0" * 12), ("u_time_frac", 0.5)]
    owned.set("u_light_count", 3.0)
    owned.assume("u_light_count", 9)  # the frame wrote its own count
    owned.set("u_light_count", 3.0)
    assert prog.writes[-2:] == [("u_light_count", 3.0), ("u_light_count", 3.0)]
    owned.set("u_light_count", 3.0)
    assert len(prog.writes) == 4
    constants = (("u_time_frac", 0.75),)
    owned.update_once(constants)
    owned.set("u_time_frac", 0.1)
    owned.update_once(constants)  # the same tuple again: not even compared
    assert prog.writes[-2:] == [("u_time_frac", 0.75), ("u_time_frac", 0.1)]
    owned.update_once(tuple([("u_time_frac", 0.75)]))  # another tuple: compared, written where it differs
    assert prog.writes[-1] == ("u_time_frac", 0.75)


def test_owned_uniforms_update_for_makes_values_only_when_the_key_changes():
    prog = _Counting()
    owned = OwnedUniforms(prog)
    made = []

    def values(v):
        made.append(v)
        return {"u_a": v, "u_b": 2.0}

    owned.update_for("static", (1,), lambda: values(1.0))
    owned.update_for("static", (1,), lambda: values(9.0))  # same key: not even made
    owned.update_for("other", (1,), lambda: values(1.0))  # another group: its own key (u_a, u_b unchanged)
    owned.update_for("static", (2,), lambda: values(3.0))
    assert made == [1.0, 1.0, 3.0]
    assert [w[0] for w in prog.writes] == ["u_a", "u_b", "u_a"]

def test_owned_uniforms_are_one_per_program_object(gl_ctx, shaders):
    prog = shaders.program("core/scene.vert", "core/scene.frag")
    assert owned_uniforms(prog) is owned_uniforms(prog)


def test_frame_uniforms_count_every_change_and_the_block_follows(gl_ctx):
    """FrameUniforms bumps its version on every kind of write, so set_frame_uniforms' quick path (same dict, same
    version) never serves a stale block."""
    from rain_core.gfx.frame import FrameUniforms

    u = FrameUniforms({"a": 1})
    seen = [u.version]
    for write in (lambda: u.__setitem__("b", 2), lambda: u.update(c=3), lambda: u.__ior__({"d": 4}),
                  lambda: u.setdefault("e", 5), lambda: u.pop("e"), lambda: u.__delitem__("d"), u.popitem, u.clear):
        write()
        seen.append(u.version)
    assert seen == sorted(set(seen))  # strictly increasing: each write counted
    scene = _scene(gl_ctx, 12.0)
    try:
        scene.step(1 / 30)
        frame = scene.render()
        renderer = scene.renderer
        rc = renderer.render_context(frame)
        assert type(rc.uniforms) is FrameUniforms
        prog = renderer.scene.scene_prog
        rc.set_frame_uniforms(prog)
        before = renderer.frame_blocks.read_bound()
        rc.uniforms.update({"u_shadow_params": (1.0, 0.25, 0.5)})  # an update in place, as the renderer does
        rc.set_frame_uniforms(prog)
        after = renderer.frame_blocks.read_bound()
        assert after != before
        assert frame_block.unpack(after)["u_shadow_params"] == (1.0, 0.25, 0.5)
        rc.uniforms |= {"u_shadow_params": (2.0, 0.25, 0.5)}
        rc.set_frame_uniforms(prog)
        assert frame_block.unpack(renderer.frame_blocks.read_bound())["u_shadow_params"] == (2.0, 0.25, 0.5)
    finally:
        scene.release()


def test_camera_position_is_the_array_formula_and_follows_the_camera(gl_ctx):
    """camera_position (floats, only z shifted) equals position − (0, 0, shift_z) as arrays, −0.0 included; the
    frame block's u_camera_pos is the same, and a moved camera (new array or new camera) is seen."""
    scene = _scene(gl_ctx, 12.0)
    try:
        scene.step(1 / 30)
        frame = scene.render()
        renderer = scene.renderer
        prog = renderer.scene.scene_prog
        for position in ([-0.0, 1.25, 123.4], [3.5, -0.0, -0.0], [1.0, 2.0, 1e6 + 0.3], [0.1, 0.2, -712.25]):
            camera = dataclasses.replace(frame.camera, position=np.array(position))
            rc = renderer.render_context(dataclasses.replace(frame, camera=camera))
            expected = np.asarray(camera.position, dtype=np.float64) - np.array([0.0, 0.0, rc.shift_z])
            assert rc.camera_position.tobytes() == expected.tobytes()
            assert not rc.camera_position.flags.writeable
            rc.set_frame_uniforms(prog)
            block = frame_block.unpack(renderer.frame_blocks.read_bound())
            assert block["u_camera_pos"] == tuple(float(np.float32(v)) for v in expected)
            camera.position = np.array(position) + 1.0  # replaced in place on the camera: seen
            assert rc.camera_position.tobytes() == (expected + 1.0).tobytes()
    finally:
        scene.release()
