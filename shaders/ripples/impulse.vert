#version 330 core
// One raised-cosine bump (WaveSolverGPU), covering the cells within its radius plus one cell on each side so
// every cell centre inside the rim gets a fragment. Cell (ix, iz) is the pixel whose centre is at
// (ix + 0.5, iz + 0.5) in the n×n state target. Two variants:
//  - the bumps of the instance buffer (wakes, spray: add_impulses_unchecked), one quad per instance;
//  - RIPPLES_RAIN: the frame's raindrops, made here from a hash (ripples/raindrops.glsl), one point per drop
//    (vertex i is drop i; a drop over a dry cell is culled). Points: one vertex per drop instead of four, which
//    matters where a CPU emulates the GPU (llvmpipe shades vertices on the calling thread).
#include "ripples/stencil.glsl"
#ifdef RIPPLES_RAIN
#include "ripples/raindrops.glsl"
#else
in vec4 in_bump;     // x, z of the centre and the radius, in cells (cell centres at integers); peak, metres
#endif
flat out vec4 v_bump;

void main() {
#ifdef RIPPLES_RAIN
    vec4 bump;
    bool wet = ripples_raindrop(uint(gl_VertexID), bump);
    v_bump = bump;
    gl_PointSize = 2.0 * (bump.z + 1.0);
    gl_Position = wet ? vec4((bump.xy + 0.5) / float(u_n) * 2.0 - 1.0, 0.0, 1.0)
                      : vec4(2.0, 2.0, 0.0, 1.0);  // off the target: nothing drawn
#else
    vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1)) * 2.0 - 1.0;  // strip order
    vec2 cells = in_bump.xy + 0.5 + corner * (in_bump.z + 1.0);
    v_bump = in_bump;
    gl_Position = vec4(cells / float(u_n) * 2.0 - 1.0, 0.0, 1.0);
#endif
}
