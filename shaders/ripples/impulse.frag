#version 330 core
// Adds one bump of the frame's batch to both the current and the previous height, so a source displaces the
// water without giving it velocity: 0.5·(1 + cos(π·d/r))·peak for cells within the radius r of the centre
// (d measured between cell centres, as in the NumPy footprint). Drawn instanced with additive blending
// (ONE, ONE) straight into the state target; held cells and the fixed edges receive nothing.
#include "ripples/stencil.glsl"

flat in vec4 v_bump;  // x, z, radius in cells; peak in metres
out vec2 f_out;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float rel = length(vec2(p) - v_bump.xy) / v_bump.z;
    if (rel >= 1.0 || ripples_held(p)) {
        discard;
    }
    float a = 0.5 * (1.0 + cos(3.14159265358979 * rel)) * v_bump.w;
    f_out = vec2(a, a);
}
