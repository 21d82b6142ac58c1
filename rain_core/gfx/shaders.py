"""The shader library: GLSL files under ``shaders/`` with ``#include``, compiled and cached per program."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import moderngl

from rain_core.paths import SHADERS_DIR


class ShaderCompileError(RuntimeError):
    """A shader failed to compile or link; the message names the real file and line of each error."""


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

    def release(self) -> None:
        """Release every program compiled through this library (its owner calls this when it is done)."""
        for program in self._programs.values():
            program.release()
        self._programs.clear()
