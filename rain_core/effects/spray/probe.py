"""The GLSL twin of the flight and phase functions, evaluated on the GPU by transform feedback (tests and bench
compare it with the NumPy reference)."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core.effects.spray.optics import shader_defines


def probe_program(shaders):
    """The transform-feedback probe of the GLSL twin (shaders/spray/probe.vert): inputs in_p0 (xyz m),
    in_v0 (xyz m/s, w τ s), in_u (xyz m/s, w age s), in_mu; outputs out_pos, out_vel, out_phase."""
    return shaders.program("spray/probe.vert", varyings=("out_pos", "out_vel", "out_phase"),
                           defines=shader_defines())


def glsl_probe(ctx: moderngl.Context, shaders, p0, v0, tau, u, age, mu):
    """Evaluate the GLSL twin for n parcels: (positions (n, 3) m, velocities (n, 3) m/s, phase (n,) 1/sr) at
    ages ``age`` (s) and scattering cosines ``mu``, computed in float32 on the GPU."""
    prog = probe_program(shaders)
    n = len(age)
    data = np.zeros((n, 13), np.float32)
    data[:, 0:3], data[:, 4:7], data[:, 7] = p0, v0, tau
    data[:, 8:11], data[:, 11], data[:, 12] = u, age, mu
    vbo = ctx.buffer(data.tobytes())
    out = ctx.buffer(reserve=n * 7 * 4)
    fbo = ctx.simple_framebuffer((1, 1))  # a draw needs a complete framebuffer even with rasteriser discard
    fbo.use()
    vao = ctx.vertex_array(prog, [(vbo, "4f 4f 4f 1f", "in_p0", "in_v0", "in_u", "in_mu")])
    vao.transform(out, mode=moderngl.POINTS, vertices=n)
    res = np.frombuffer(out.read(), np.float32).reshape(n, 7).astype(np.float64)
    ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
    for obj in (vao, vbo, out, fbo):
        obj.release()
    return res[:, :3], res[:, 3:6], res[:, 6]
