"""The machinery of the settings tree (``rain_core.settings``): how a leaf is declared (``field``), what is
known of it (``FieldInfo``), how a value is checked and coerced at every entrance, the errors that name the
field path (``SettingsError``, ``ScenarioSyntaxError``), and ``_Section``, the base of every section.
``rain_core.settings`` declares the sections with it and exports these names.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import typing
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rain_core import checks

_BRIEF_ITEMS = 4  # a container in an error message shows at most this many items …
_BRIEF_DEPTH = 3  # … and this many levels (a 5M-item or 1000-deep value is summarised, not formatted)
_BRIEF_TEXT = 100  # a string or bytes value is cut to this many characters before it is quoted


class _Shown:
    """A ready-made text that ``checks.quote`` repeats (and cuts) as the repr of a value."""

    def __init__(self, text: str):
        self.text = text

    def __repr__(self) -> str:
        return self.text


def _brief(value: Any, depth: int = 0) -> str:
    """A short repr of ``value`` in bounded time: containers show a few items and levels, huge ints their size."""
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int):
        if value.bit_length() > 256:  # repr of a 10**5000 would itself raise (int max str digits)
            return f"<integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"
        return repr(value)
    if isinstance(value, str | bytes):
        # checks.quote keeps the head and the tail of the repr and cuts the middle
        return repr(value if len(value) <= 2 * _BRIEF_TEXT else value[:_BRIEF_TEXT] + value[-8:])
    if isinstance(value, list | tuple | dict | set | frozenset):
        opening, closing = {list: "[]", tuple: "()"}.get(type(value), "{}")
        if depth >= _BRIEF_DEPTH:
            return opening + ("…" if value else "") + closing
        head = list(itertools.islice(value.items() if isinstance(value, dict) else value, _BRIEF_ITEMS))
        if isinstance(value, dict):
            parts = [f"{_brief(k, depth + 1)}: {_brief(v, depth + 1)}" for k, v in head]
        else:
            parts = [_brief(v, depth + 1) for v in head]
        if len(value) > _BRIEF_ITEMS:
            parts.append(f"… {len(value)} items")
        return opening + ", ".join(parts) + closing
    try:
        return checks.quote(value)
    except Exception:  # a repr that fails must not hide the real error
        return f"<{type(value).__name__}>"


def _quote(value: Any) -> str:
    """``value`` as an error message shows it: its repr, cut by ``checks.quote`` to a readable length."""
    return checks.quote(_Shown(_brief(value)))


def _path_text(path: Any) -> str:
    """A field path as a message shows it: as is when short, else quoted and cut."""
    return path if isinstance(path, str) and len(path) <= 80 and path.isprintable() else _quote(path)


class SettingsError(ValueError):
    """An invalid setting. Attributes: field_path ("rain.rate_mm_h"), value, allowed (a description of the
    allowed values), source (the file, if any) and line (TOML syntax errors only)."""

    def __init__(self, field_path: str, value: Any, allowed: str, source: str | None = None,
                 line: int | None = None, message: str | None = None):
        self.field_path, self.value, self.allowed, self.source, self.line = field_path, value, allowed, source, line
        where = f"{source}: " if source else ""
        super().__init__(message or f"{where}{_path_text(field_path)} = {_quote(value)} is not allowed: "
                                    f"expected {allowed}")


class ScenarioSyntaxError(SettingsError):
    """A scenario file that is not valid TOML; ``line`` is the line of the error (1-based) when known."""

    def __init__(self, source: str, detail: str, line: int | None):
        at = f" at line {line}" if line else ""
        super().__init__("<file>", None, "valid TOML", source, line, f"{source}: invalid TOML{at}: {detail}")


def field(default: Any, *, range: tuple[float, float] | None = None, unit: str = "",
          choices: tuple[str, ...] | None = None, doc: str = ""):
    """Declare a setting: its default, closed range (lo, hi) for numbers, unit, choices for strings, and a doc."""
    meta = {"range": range, "unit": unit, "choices": choices, "doc": doc}
    return dataclasses.field(default=default, metadata=meta)


def _section(cls):
    return dataclasses.field(default_factory=cls, metadata={"section": True})


@dataclass(frozen=True)
class FieldInfo:
    """What the UI needs to show one setting: path ("rain.rate_mm_h"), kind ("float", "int", "bool", "str"),
    optional (None allowed), default, range (lo, hi) or None, unit, choices or None, doc."""

    path: str
    kind: str
    optional: bool
    default: Any
    range: tuple[float, float] | None
    unit: str
    choices: tuple[str, ...] | None
    doc: str

    def allowed(self) -> str:
        """The allowed values, in words (used in error messages)."""
        unit = f" {self.unit}" if self.unit else ""
        if self.kind == "bool":
            text = "true or false"
        elif self.kind == "str":
            text = "one of " + ", ".join(repr(c) for c in self.choices) if self.choices else "a string"
        else:
            noun = "an integer" if self.kind == "int" else "a number"
            lo, hi = (str(b) if self.kind == "int" else f"{b:g}" for b in self.range or (0, 0))
            text = f"{noun} in [{lo}, {hi}]{unit}" if self.range else f"{noun}{unit}"
        return text + (", or unset (automatic)" if self.optional else "")


_KINDS = {float: "float", int: "int", bool: "bool", str: "str"}


def _unknown(path: str, value: Any, allowed: str, source: str | None = None) -> SettingsError:
    where = f"{source}: " if source else ""
    return SettingsError(path, value, allowed, source,
                         message=f"{where}unknown setting {_path_text(path)} (value {_quote(value)}): {allowed}")


def _field_infos(cls, prefix: str) -> dict[str, FieldInfo]:
    hints = typing.get_type_hints(cls)
    infos = {}
    for f in dataclasses.fields(cls):
        hint = hints[f.name]
        args = typing.get_args(hint)
        optional = type(None) in args
        base = next(a for a in args if a is not type(None)) if optional else hint
        infos[f.name] = FieldInfo(f"{prefix}{f.name}", _KINDS[base], optional, f.default, f.metadata["range"],
                                  f.metadata["unit"], f.metadata["choices"], f.metadata["doc"])
    return infos


def _coerce(info: FieldInfo, value: Any, source: str | None = None) -> Any:
    """The validated value for a field (int → float for float fields), or a SettingsError."""

    original = value

    def fail():
        raise SettingsError(info.path, original, info.allowed(), source)

    if value is None:
        return None if info.optional else fail()
    if info.kind == "bool":
        return value if isinstance(value, bool) else fail()
    if info.kind == "str":
        if not isinstance(value, str) or (info.choices and value not in info.choices):
            fail()
        return value
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        fail()
    if info.kind == "int":
        if not isinstance(value, int | np.integer):
            fail()
        value = int(value)
    else:
        try:
            value = float(value)
        except OverflowError:  # an int too large for a float is out of every range
            fail()
        if not math.isfinite(value):
            fail()
    if info.range and not info.range[0] <= value <= info.range[1]:
        fail()
    return value


class _Section:
    """Base of the settings sections: validates its fields on construction (name in ``SECTION``)."""

    SECTION: ClassVar[str] = ""

    def __post_init__(self):
        self.validate()

    @classmethod
    def field_infos(cls) -> dict[str, FieldInfo]:
        cached = cls.__dict__.get("_infos")
        if cached is None:
            cached = _field_infos(cls, f"{cls.SECTION}.")
            cls._infos = cached
        return cached

    def validate(self, source: str | None = None) -> None:
        """Check every field (SettingsError on the first bad one); ints in float fields become floats."""
        for name, info in self.field_infos().items():
            object.__setattr__(self, name, _coerce(info, getattr(self, name), source))
