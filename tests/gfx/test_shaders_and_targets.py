import numpy as np
import pytest

from rain_core.gl import PingPong, ShaderCompileError, ShaderLibrary, float_target
from rain_core.paths import ASSETS_DIR, SHADERS_DIR


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


VERT = "#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n"


def test_paths_exist():
    assert (SHADERS_DIR / "core/scene.frag").is_file()
    assert ASSETS_DIR.is_dir()


def test_include_error_names_the_included_file_and_line(gl_ctx, tmp_path):
    _write(tmp_path, "v.vert", VERT)
    _write(tmp_path, "common/helpers.glsl",
           "float ok() { return 1.0; }\n\nfloat broken() {\n  return undefined_x;\n}\n")
    _write(tmp_path, "f.frag", '#version 330 core\n#include "common/helpers.glsl"\nout vec4 c;\n'
                               'void main() { c = vec4(ok()); }\n')
    lib = ShaderLibrary(gl_ctx, root=tmp_path)
    with pytest.raises(ShaderCompileError) as info:
        lib.program("v.vert", "f.frag")
    message = str(info.value)
    assert f"{tmp_path / 'common' / 'helpers.glsl'}:4" in message, message


def test_error_in_main_file_after_an_include_keeps_its_own_line(gl_ctx, tmp_path):
    _write(tmp_path, "v.vert", VERT)
    _write(tmp_path, "inc.glsl", "float a() {\n return 1.0;\n}\n")
    _write(tmp_path, "f.frag", '#version 330 core\n#include "inc.glsl"\nout vec4 c;\nvoid main() {\n'
                               '  c = vec4(a());\n  c = nope;\n}\n')
    lib = ShaderLibrary(gl_ctx, root=tmp_path)
    with pytest.raises(ShaderCompileError) as info:
        lib.program("v.vert", "f.frag")
    assert f"{tmp_path / 'f.frag'}:6" in str(info.value)


def test_missing_include_and_cycle_are_reported(gl_ctx, tmp_path):
    _write(tmp_path, "v.vert", VERT)
    _write(tmp_path, "f.frag", '#version 330 core\n#include "nothere.glsl"\nvoid main() {}\n')
    _write(tmp_path, "a.glsl", '#include "b.glsl"\n')
    _write(tmp_path, "b.glsl", '#include "a.glsl"\n')
    _write(tmp_path, "g.frag", '#version 330 core\n#include "a.glsl"\nvoid main() {}\n')
    lib = ShaderLibrary(gl_ctx, root=tmp_path)
    with pytest.raises(ShaderCompileError, match=r"f\.frag:2.*nothere\.glsl"):
        lib.program("v.vert", "f.frag")
    with pytest.raises(ShaderCompileError, match="include cycle"):
        lib.program("v.vert", "g.frag")


def test_shared_include_is_expanded_once_and_defines_follow_version(gl_ctx, tmp_path):
    _write(tmp_path, "c.glsl", "float c() { return VALUE; }\n")
    _write(tmp_path, "b.glsl", '#include "c.glsl"\n')
    _write(tmp_path, "f.frag", '#version 330 core\n#include "c.glsl"\n#include "b.glsl"\nout vec4 o;\n'
                               'void main() { o = vec4(c()); }\n')
    _write(tmp_path, "v.vert", VERT)
    lib = ShaderLibrary(gl_ctx, root=tmp_path)
    src = lib.preprocess("f.frag", {"VALUE": "0.5"})
    assert src.text.count("float c()") == 1
    assert src.text.splitlines()[1] == "#define VALUE 0.5"
    assert lib.program("v.vert", "f.frag", defines={"VALUE": "0.5"}) is lib.program("v.vert", "f.frag",
                                                                                     defines={"VALUE": "0.5"})


def test_every_project_shader_pair_compiles(shaders):
    for frag in ("core/scene.frag",):
        shaders.program("core/scene.vert", frag)
    for frag in ("core/sky.frag", "core/tonemap.frag", "core/blit.frag"):
        shaders.program("common/fullscreen.vert", frag)


def test_float_target_and_ping_pong_hold_float_values(gl_ctx):
    target = float_target(gl_ctx, (8, 4), 4, "f4")
    target.fbo.clear(1.5, -2.0, 1e5, 0.25)
    data = np.frombuffer(target.fbo.read(components=4, dtype="f4"), np.float32).reshape(4, 8, 4)
    np.testing.assert_allclose(data[0, 0], [1.5, -2.0, 1e5, 0.25])
    pair = PingPong(gl_ctx, (4, 4), components=2)
    first = pair.src
    pair.swap()
    assert pair.dst is first and pair.src is not first
    target.release()
    pair.release()
