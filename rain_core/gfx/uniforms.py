"""The one way to set uniforms: by name, skipping names a program does not declare.

GLSL compilers drop uniforms a variant does not use, so every effect writes "where the program has it". Values
may be numbers, tuples, raw bytes (written as-is) or NumPy arrays (written as contiguous float32).
"""

from __future__ import annotations

import struct
import weakref

import numpy as np


def set_uniform(program, name: str, value) -> None:
    """Write one uniform if ``program`` declares it."""
    # program.get is one dict lookup; ``name in program`` would walk every uniform (moderngl has no __contains__).
    uniform = program.get(name, None)
    if uniform is None:
        return
    if isinstance(value, bytes):
        uniform.write(value)
    elif isinstance(value, np.ndarray):
        uniform.write(np.ascontiguousarray(value, dtype=np.float32).tobytes())
    else:
        uniform.value = value


def set_uniforms(program, values: dict | None = None, /, **named) -> None:
    """Write every uniform of ``values`` (and the keyword arguments) that ``program`` declares."""
    for source in (values or {}, named):
        for name, value in source.items():
            set_uniform(program, name, value)


_MAT4 = struct.Struct("=16f")


def rows_bytes(rows: list) -> bytes:
    """``mat4_bytes`` of a 4×4 given as four rows of Python floats (``ndarray.tolist()``)."""
    r0, r1, r2, r3 = rows
    try:
        return _MAT4.pack(r0[0], r1[0], r2[0], r3[0], r0[1], r1[1], r2[1], r3[1],
                          r0[2], r1[2], r2[2], r3[2], r0[3], r1[3], r2[3], r3[3])
    except OverflowError:  # struct refuses what overflows float32 (NumPy makes it inf)
        return np.array(rows, dtype=np.float64).T.astype(np.float32).tobytes()


_FLOAT_DTYPES = (np.dtype(np.float64), np.dtype(np.float32))


def mat4_bytes(m) -> bytes:
    """A row-major NumPy 4×4 (or 3×3) matrix → the column-major float32 bytes GLSL expects."""
    if type(m) is np.ndarray and m.shape == (4, 4) and m.dtype in _FLOAT_DTYPES:
        # A float 4×4 (a dozen a frame) as Python floats packed by struct: the same C cast to float32 as NumPy's
        # astype, one C call each instead of four NumPy calls, which cost ~2× more between the frame's GL work
        # (cold caches).
        return rows_bytes(m.tolist())
    # astype keeps the transposed (Fortran) layout and tobytes writes it in logical order: the same bytes as a
    # contiguous copy of the float32 transpose, in half the time.
    return np.asarray(m).T.astype(np.float32).tobytes()


_MISSING = object()


class OwnedUniforms:
    """Writes uniforms of one program that a single owner alone sets (e.g. the road's ``u_road_*`` in the scene
    program), skipping a write whose value equals the one this object wrote last: most of them do not change
    from frame to frame. Anything else writing the same names in the same program would make it skip wrongly."""

    __slots__ = ("_program", "_uniforms", "_last", "_keys", "_frozen", "_once")

    def __init__(self, program):
        self._program = weakref.ref(program)  # the cache below must not keep a program alive
        self._uniforms: dict[str, object] = {}  # name → moderngl Uniform, None where the compiler dropped it
        self._last: dict[str, object] = {}
        self._once = None  # the pairs last written in full by update_once
        self._keys: dict[str, object] = {}  # group → the key its values were last written for (update_for)
        self._frozen: dict[str, np.ndarray | None] = {}  # name → the read-only array its last value came from

    @property
    def program(self):
        return self._program()

    def set(self, name: str, value) -> None:
        """Write ``name`` unless its value equals the last one written; an ndarray is compared as its float32
        bytes, and the same read-only array object as last time is known equal without converting it."""
        frozen = None
        if isinstance(value, np.ndarray):
            if not value.flags.writeable:
                if self._frozen.get(name) is value:
                    return
                frozen = value
            value = np.ascontiguousarray(value, dtype=np.float32).tobytes()
        self._frozen[name] = frozen
        last = self._last.get(name, _MISSING)
        if type(last) is type(value) and last == value:
            return
        self._last[name] = value
        uniform = self._uniforms.get(name, _MISSING)
        if uniform is _MISSING:  # a program's uniforms never change: look each name up once
            uniform = self._uniforms[name] = self._program().get(name, None)
        if uniform is None:
            return
        if type(value) is bytes:
            uniform.write(value)
        else:
            uniform.value = value

    def update(self, values: dict) -> None:
        for name, value in values.items():
            self.set(name, value)

    def update_pairs(self, pairs) -> None:
        """``set`` each (name, value) of an iterable of pairs."""
        set_ = self.set
        for name, value in pairs:
            set_(name, value)

    def update_once(self, pairs: tuple) -> None:
        """``update_pairs`` unless this very tuple was the last given here: constants cost one identity test a
        frame. Nothing else may write those names in between."""
        if self._once is not pairs:
            self.update_pairs(pairs)
            self._once = pairs

    def assume(self, name: str, value) -> None:
        """Someone else wrote ``value`` to ``name`` (e.g. ``set_frame_uniforms``' lights): compare with it next."""
        self._last[name] = value
        self._frozen[name] = None

    def update_for(self, group: str, key, make_values) -> None:
        """``update(make_values())`` unless this program last got ``group``'s values for an equal ``key``: uniforms
        that change only with what ``key`` holds (the resolution, the camera's lens) are then not even made or
        compared between its changes. ``key`` must hold everything the values are made of."""
        if self._keys.get(group, _MISSING) != key:
            self.update(make_values())
            self._keys[group] = key


# Program → its OwnedUniforms, held weakly: a dropped program leaves with its entry (a strong cache once kept
# programs of dropped shader libraries alive until an eviction, and they then died "unreleased" in whatever
# scene happened to evict them).
_OWNED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def owned_uniforms(program) -> OwnedUniforms:
    """The one ``OwnedUniforms`` of ``program``, shared by every owner instance (two road effects drawing through
    one shader library's scene program must see each other's writes)."""
    owned = _OWNED.get(program)
    if owned is None:
        owned = _OWNED[program] = OwnedUniforms(program)
    return owned
