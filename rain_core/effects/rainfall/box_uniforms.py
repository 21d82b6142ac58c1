"""The rainfall boxes' per-frame uniforms from Python floats (issue 13: the CPU time per frame).

``box_pairs`` and ``splash_box_pairs`` pack them as (name, value) pairs for ``OwnedUniforms.update_pairs``: the
same float64 operations and float32 bytes as the NumPy forms in ``RainfallEffect.drop_uniforms`` /
``splash_uniforms``, which stay for the debug probe and as the tests' oracle. The renderer takes ``box_floats``
(the same floats, for the per-frame block, rain_block.py) and ``box_shape_pairs``."""

from __future__ import annotations

import struct

from rain_core.effects.rainfall.constants import BOX_BOTTOM_Y_M, LAYER_SCALES
from rain_core.effects.rainfall.drops import TURB_EPS

LAYERS = len(LAYER_SCALES)
_VEC3S = struct.Struct(f"={3 * LAYERS}f")  # vec3[LAYERS], tightly packed as glUniform3fv reads it
_FLOATS = struct.Struct(f"={LAYERS}f")


def box_pairs(boxes, wind_integral, shift_z: float) -> tuple:
    """u_box_lo (frame shifted by shift_z), u_box_ext, u_box_off, u_box_turb and u_box_fade_bottom as float32
    bytes: ``sim.box_offsets`` and the shift, element by element in float64 (Python's % is NumPy's mod)."""
    lo_out, ext_out, off_out, turb_out = box_floats(boxes, wind_integral, shift_z)
    pack = _VEC3S.pack
    return (("u_box_lo", pack(*lo_out)), ("u_box_ext", pack(*ext_out)), ("u_box_off", pack(*off_out)),
            ("u_box_turb", pack(*turb_out)), ("u_box_fade_bottom", _FLOATS.pack(*boxes.fade_bottom.tolist())))


def box_shape_pairs(boxes, ext: list) -> tuple:
    """u_box_ext (``box_floats``' ext) and u_box_fade_bottom as float32 bytes: they change with the container."""
    return ("u_box_ext", _VEC3S.pack(*ext)), ("u_box_fade_bottom", _FLOATS.pack(*boxes.fade_bottom.tolist()))


def box_floats(boxes, wind_integral, shift_z: float) -> tuple[list, list, list, list]:
    """``box_pairs``' lo, ext, off and turb as lists of 3·LAYERS Python floats (float64)."""
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
    return lo_out, ext_out, off_out, turb_out


def splash_box_pairs(boxes, layer: int, shift_z: float) -> tuple:
    """u_splash_lo (frame shifted by shift_z), u_splash_ext and u_splash_off of the splash layer's box, as
    tuples of floats (``splash_uniforms``' values)."""
    lx, ly, lz = boxes.lo[layer].tolist()
    hx, hy, hz = boxes.hi[layer].tolist()
    ex, ey, ez = hx - lx, hy - ly, hz - lz
    return (("u_splash_lo", (lx, ly, lz - float(shift_z))), ("u_splash_ext", (ex, ey, ez)),
            ("u_splash_off", ((-lx) % ex, (-ly) % ey, (-lz) % ez)))
