"""OpenGL plumbing: contexts, shader loading with ``#include``, float render targets, ping-pong pairs, timers.

The main path targets OpenGL 3.3 core so the app runs on every desktop; nothing here needs more.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import moderngl

from rain_core.paths import SHADERS_DIR

MIN_GL_VERSION = 330


class GLUnavailableError(RuntimeError):
    """No OpenGL ≥ 3.3 context could be created (or the one given is too old)."""


class ShaderCompileError(RuntimeError):
    """A shader failed to compile or link; the message names the real file and line of each error."""


def _check_version(ctx: moderngl.Context) -> moderngl.Context:
    if ctx.version_code < MIN_GL_VERSION:
        found = ctx.info.get("GL_VERSION", ctx.version_code)
        renderer = ctx.info.get("GL_RENDERER", "unknown renderer")
        ctx.release()
        raise GLUnavailableError(
            f"OpenGL 3.3 core is required, this driver offers {found} ({renderer}). "
            "Update the graphics driver, or on a machine without a GPU install Mesa (llvmpipe)."
        )
    return ctx


def create_headless_context() -> moderngl.Context:
    """A standalone context with no window: EGL first (works without a display), then the platform default."""
    errors = []
    for kwargs in ({"backend": "egl"}, {}):
        try:
            return _check_version(moderngl.create_standalone_context(require=MIN_GL_VERSION, **kwargs))
        except GLUnavailableError:
            raise
        except Exception as exc:  # each backend fails in its own way (missing libEGL, no display, ...)
            errors.append(f"{kwargs.get('backend', 'default')}: {exc}")
    raise GLUnavailableError(
        "could not create a headless OpenGL 3.3 context (" + "; ".join(errors) + "). "
        "On Linux install Mesa's EGL (e.g. apt install libegl1 libgl1-mesa-dri)."
    )


def context_from_window() -> moderngl.Context:
    """The context of the window whose GL context is current (e.g. moderngl-window's ``wnd.ctx``)."""
    try:
        ctx = moderngl.create_context(require=MIN_GL_VERSION)
    except Exception as exc:
        raise GLUnavailableError(f"the window has no usable OpenGL 3.3 context: {exc}") from exc
    return _check_version(ctx)


# --- shaders ---------------------------------------------------------------------------------------------

_INCLUDE_RE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*$')
# Driver error formats: Mesa "0:12(5): error", NVIDIA "0(12) : error", AMD/Intel "ERROR: 0:12: ...".
_ERROR_LINE_RES = (
    re.compile(r"(?P<pre>\b)0:(?P<line>\d+)\((?P<col>\d+)\)"),
    re.compile(r"(?P<pre>\b)0\((?P<line>\d+)\)"),
    re.compile(r"(?P<pre>ERROR: )0:(?P<line>\d+):"),
)


@dataclass
class ShaderSource:
    """A preprocessed shader: the expanded text and, per expanded line, the (file, line) it came from."""

    text: str
    origins: list[tuple[Path, int]] = field(default_factory=list)

    def origin(self, expanded_line: int) -> tuple[Path, int]:
        if 1 <= expanded_line <= len(self.origins):
            return self.origins[expanded_line - 1]
        return (self.origins[-1][0], expanded_line) if self.origins else (Path("?"), expanded_line)


class ShaderLibrary:
    """Loads GLSL from ``shaders/`` with ``#include "file"`` (relative to the including file, then the root).

    Each file is included at most once per program (so shared chunks need no guards). Programs are cached by
    their file names and defines. The expanded source keeps a line map instead of ``#line`` directives (whose
    meaning differs between GLSL versions and drivers), so compile errors name the real file and line.
    """

    def __init__(self, ctx: moderngl.Context, root: Path | str = SHADERS_DIR):
        self.ctx = ctx
        self.root = Path(root)
        self._programs: dict[tuple, moderngl.Program] = {}

    def _resolve(self, name: str, including: Path | None) -> Path:
        candidates = ([including.parent / name] if including else []) + [self.root / name]
        for path in candidates:
            if path.is_file():
                return path.resolve()
        where = f" (included from {including})" if including else ""
        raise ShaderCompileError(f"shader file not found: {name!r}{where}; looked in " +
                                 ", ".join(str(c.parent) for c in candidates))

    def preprocess(self, name: str, defines: dict[str, object] | None = None) -> ShaderSource:
        """Expand includes and insert ``#define``s right after ``#version``."""
        out = ShaderSource("")
        lines: list[str] = []
        seen: set[Path] = set()

        def expand(path: Path, stack: tuple[Path, ...]):
            if path in stack:
                chain = " -> ".join(p.name for p in (*stack, path))
                raise ShaderCompileError(f"{path}: include cycle: {chain}")
            if path in seen:
                return
            seen.add(path)
            for number, line in enumerate(path.read_text().splitlines(), start=1):
                match = _INCLUDE_RE.match(line)
                if match:
                    try:
                        target = self._resolve(match.group(1), path)
                    except ShaderCompileError as exc:
                        raise ShaderCompileError(f"{path}:{number}: {exc}") from None
                    expand(target, (*stack, path))
                    continue
                lines.append(line)
                out.origins.append((path, number))
                if line.lstrip().startswith("#version") and defines and len(lines) == 1:
                    for key, value in defines.items():
                        lines.append(f"#define {key} {value}")
                        out.origins.append((path, number))

        expand(self._resolve(name, None), ())
        out.text = "\n".join(lines) + "\n"
        return out

    def _translate_errors(self, message: str, sources: dict[str, ShaderSource]) -> str:
        # moderngl prefixes each stage's log with its name ("fragment_shader\n====="); map lines per stage.
        stage = None
        translated = []
        for raw in message.splitlines():
            key = raw.strip()
            if key in sources:
                stage = key
            src = sources.get(stage) if stage else None
            if src is not None:
                for pattern in _ERROR_LINE_RES:
                    match = pattern.search(raw)
                    if match:
                        path, line = src.origin(int(match.group("line")))
                        raw = raw[: match.start()] + match.group("pre") + f"{path}:{line}" + raw[match.end():]
                        break
            translated.append(raw)
        return "\n".join(translated)

    def program(self, vertex: str, fragment: str | None = None, geometry: str | None = None,
                defines: dict[str, object] | None = None, varyings: tuple[str, ...] = ()) -> moderngl.Program:
        """Compile (or fetch from the cache) a program from shader file names relative to ``shaders/``."""
        key = (vertex, fragment, geometry, tuple(sorted((defines or {}).items())), varyings)
        if key in self._programs:
            return self._programs[key]
        stages = {"vertex_shader": vertex, "fragment_shader": fragment, "geometry_shader": geometry}
        sources = {stage: self.preprocess(name, defines) for stage, name in stages.items() if name}
        try:
            prog = self.ctx.program(**{stage: src.text for stage, src in sources.items()},
                                    varyings=list(varyings))
        except moderngl.Error as exc:
            names = ", ".join(n for n in stages.values() if n)
            raise ShaderCompileError(f"compiling {names}:\n" + self._translate_errors(str(exc), sources)) from None
        self._programs[key] = prog
        return prog


# --- render targets --------------------------------------------------------------------------------------

@dataclass
class RenderTarget:
    """A framebuffer with one colour texture and an optional depth texture."""

    fbo: moderngl.Framebuffer
    color: moderngl.Texture
    depth: moderngl.Texture | None

    @property
    def size(self) -> tuple[int, int]:
        return self.color.size

    def release(self):
        # Releasing the bound framebuffer leaves a dead name bound: later framebuffers then fail with
        # GL_INVALID_OPERATION. Bind the default one first.
        self.fbo.ctx.detect_framebuffer(0).use()
        for obj in (self.fbo, self.color, self.depth):
            if obj is not None:
                obj.release()


def float_target(ctx: moderngl.Context, size: tuple[int, int], components: int = 4, dtype: str = "f2",
                 depth: bool = False, filter_linear: bool = True) -> RenderTarget:
    """A float colour target (``f2`` half or ``f4`` full precision), clamped at the edges."""
    color = ctx.texture(size, components, dtype=dtype)
    flt = moderngl.LINEAR if filter_linear else moderngl.NEAREST
    color.filter = (flt, flt)
    color.repeat_x = color.repeat_y = False
    depth_tex = ctx.depth_texture(size) if depth else None
    fbo = ctx.framebuffer(color_attachments=[color], depth_attachment=depth_tex)
    return RenderTarget(fbo, color, depth_tex)


class PingPong:
    """Two float targets of one size that swap roles: read ``src``, write ``dst``, then ``swap()``."""

    def __init__(self, ctx: moderngl.Context, size: tuple[int, int], components: int = 2, dtype: str = "f4",
                 filter_linear: bool = False):
        self.targets = [float_target(ctx, size, components, dtype, filter_linear=filter_linear) for _ in range(2)]
        self._index = 0

    @property
    def src(self) -> RenderTarget:
        return self.targets[self._index]

    @property
    def dst(self) -> RenderTarget:
        return self.targets[1 - self._index]

    def swap(self):
        self._index = 1 - self._index

    def release(self):
        for target in self.targets:
            target.release()


class ColorView:
    """A framebuffer onto another target's colour texture without its depth, so a pass can sample that depth
    while it draws. Rebuilt when the texture *object* changes (after a resize): GL names are reused by drivers,
    so comparing ``.glo`` could keep drawing into a deleted texture."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._texture = None
        self._fbo: moderngl.Framebuffer | None = None

    def fbo(self, texture: moderngl.Texture) -> moderngl.Framebuffer:
        if texture is not self._texture or self._fbo is None:
            self.release()
            self._texture = texture
            self._fbo = self.ctx.framebuffer(color_attachments=[texture])
        return self._fbo

    def release(self) -> None:
        if self._fbo is not None:
            self.ctx.detect_framebuffer(0).use()
            self._fbo.release()
        self._fbo = self._texture = None


def fullscreen_triangle(ctx: moderngl.Context, program: moderngl.Program) -> moderngl.VertexArray:
    """A VAO that draws one triangle covering the viewport (vertex shader uses gl_VertexID)."""
    return ctx.vertex_array(program, [])


# --- timing ----------------------------------------------------------------------------------------------

class PassTimer:
    """Measures one pass: CPU time of the Python side, and GPU time from a timer query where the driver has one
    (else the wall time up to ``ctx.finish()``, which includes the CPU side). ``gpu_source`` says which."""

    def __init__(self, ctx: moderngl.Context, gpu: bool = True):
        self.ctx = ctx
        self.gpu = gpu
        self._query = None
        self.gpu_source = "none"
        if gpu:
            try:
                self._query = ctx.query(time=True)
                self.gpu_source = "timer query"
            except Exception:  # drivers without ARB_timer_query
                self._query = None
                self.gpu_source = "wall time after finish"

    def measure(self, fn) -> tuple[float, float | None]:
        """Run fn(); return (cpu_ms, gpu_ms or None)."""
        if not self.gpu:
            t0 = time.perf_counter()
            fn()
            return (time.perf_counter() - t0) * 1e3, None
        if self._query is not None:
            t0 = time.perf_counter()
            with self._query:
                fn()
            cpu = (time.perf_counter() - t0) * 1e3
            elapsed_ns = self._query.elapsed
            # Some drivers answer a query they could not time (e.g. across a shader compile) with 2³²−1 ns.
            return cpu, (None if elapsed_ns >= 0xFFFFFFFF else elapsed_ns * 1e-6)
        t0 = time.perf_counter()
        fn()
        cpu = (time.perf_counter() - t0) * 1e3
        self.ctx.finish()
        return cpu, (time.perf_counter() - t0) * 1e3
