"""The rainfall programs' uniforms as the effect writes them every frame (issue 13: the CPU time per frame).

``program_uniforms(program)`` is one program's cache of the value last written to each name, shared by every
effect drawing with that program, so only values that changed reach GL. ``box_pairs`` and ``splash_box_pairs``
pack the per-frame box uniforms from Python floats: the same float64 operations and float32 bytes as the NumPy
forms in ``RainfallEffect.drop_uniforms`` / ``splash_uniforms``, which stay for the debug probe and as the
tests' oracle."""

from __future__ import annotations

import struct
import weakref

from rain_core.effects.rainfall.constants import BOX_BOTTOM_Y_M, LAYER_SCALES
from rain_core.effects.rainfall.drops import TURB_EPS

_MISSING = object()
LAYERS = len(LAYER_SCALES)
_VEC3S = struct.Struct(f"={3 * LAYERS}f")  # vec3[LAYERS], tightly packed as glUniform3fv reads it
_FLOATS = struct.Struct(f"={LAYERS}f")


class ProgramUniforms:
    """Writes uniforms of one program, skipping a write whose value (bytes, a number or a tuple) equals the one
    written last through this object. Everything that writes these names in this program must go through it,
    or tell it (``assume``) what it wrote."""

    __slots__ = ("_program", "_uniforms", "_last", "applied")

    def __init__(self, program):
        self._program = weakref.ref(program)  # the cache must not keep a released program alive
        self._uniforms: dict[str, object] = {}  # name → moderngl Uniform, None where the compiler dropped it
        self._last: dict[str, object] = {}
        self.applied = None  # the constant pairs last put in full (a shortcut only: put compares anyway)

    def put(self, name: str, value) -> None:
        last = self._last.get(name, _MISSING)
        if type(last) is type(value) and last == value:
            return
        self._last[name] = value
        uniform = self._uniforms.get(name, _MISSING)
        if uniform is _MISSING:
            uniform = self._uniforms[name] = self._program().get(name, None)
        if uniform is None:
            return
        if type(value) is bytes:
            uniform.write(value)
        else:
            uniform.value = value

    def put_pairs(self, pairs) -> None:
        put = self.put
        for name, value in pairs:
            put(name, value)

    def put_once(self, pairs: tuple) -> None:
        """``put_pairs`` unless this very tuple was the last put in full (constants: one identity test a frame)."""
        if self.applied is not pairs:
            self.put_pairs(pairs)
            self.applied = pairs

    def assume(self, name: str, value) -> None:
        """Someone else (``rc.set_frame_uniforms``: the frame's lights) wrote ``value`` to ``name``."""
        self._last[name] = value


_PROGRAMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def program_uniforms(program) -> ProgramUniforms:
    """The one ``ProgramUniforms`` of ``program`` (held weakly: a released program leaves with its entry)."""
    cache = _PROGRAMS.get(program)
    if cache is None:
        cache = _PROGRAMS[program] = ProgramUniforms(program)
    return cache


def box_pairs(boxes, wind_integral, shift_z: float) -> tuple:
    """u_box_lo (frame shifted by shift_z), u_box_ext, u_box_off, u_box_turb and u_box_fade_bottom as float32
    bytes: ``sim.box_offsets`` and the shift, element by element in float64 (Python's % is NumPy's mod)."""
    w0, _, w2 = wind_integral.tolist()
    t0, t2 = TURB_EPS * w0, TURB_EPS * w2
    shift_z = float(shift_z)
    lo_out, ext_out, off_out, turb_out = [], [], [], []
    for (lx, ly, lz), (hx, hy, hz) in zip(boxes.lo.tolist(), boxes.hi.tolist(), strict=True):
        ex, ey, ez = hx - lx, hy - ly, hz - lz
        lo_out += (lx, ly, lz - shift_z)
        ext_out += (ex, ey, ez)
        off_out += ((w0 - lx) % ex, (BOX_BOTTOM_Y_M - ly) % ey, (w2 - lz) % ez)
        turb_out += (t0 % ex, 0.0, t2 % ez)
    pack = _VEC3S.pack
    return (("u_box_lo", pack(*lo_out)), ("u_box_ext", pack(*ext_out)), ("u_box_off", pack(*off_out)),
            ("u_box_turb", pack(*turb_out)), ("u_box_fade_bottom", _FLOATS.pack(*boxes.fade_bottom.tolist())))


def splash_box_pairs(boxes, layer: int, shift_z: float) -> tuple:
    """u_splash_lo (frame shifted by shift_z), u_splash_ext and u_splash_off of the splash layer's box, as
    tuples of floats (``splash_uniforms``' values)."""
    lx, ly, lz = boxes.lo[layer].tolist()
    hx, hy, hz = boxes.hi[layer].tolist()
    ex, ey, ez = hx - lx, hy - ly, hz - lz
    return (("u_splash_lo", (lx, ly, lz - float(shift_z))), ("u_splash_ext", (ex, ey, ez)),
            ("u_splash_off", ((-lx) % ex, (-ly) % ey, (-lz) % ez)))
