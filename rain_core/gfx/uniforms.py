"""The one way to set uniforms: by name, skipping names a program does not declare.

GLSL compilers drop uniforms a variant does not use, so every effect writes "where the program has it". Values
may be numbers, tuples, raw bytes (written as-is) or NumPy arrays (written as contiguous float32).
"""

from __future__ import annotations

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


def mat4_bytes(m) -> bytes:
    """A row-major NumPy 4×4 (or 3×3) matrix → the column-major float32 bytes GLSL expects."""
    return np.ascontiguousarray(np.asarray(m, dtype=np.float32).T).tobytes()
