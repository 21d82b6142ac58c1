#version 330 core
// Adds the pending source displacement (metres) to both the current and the previous height, so a source
// displaces the water without giving it velocity. Drawn with additive blending (ONE, ONE) straight into the
// state target, scissored to the sources' bounding box; held cells receive nothing.
#include "ripples/stencil.glsl"

uniform sampler2D u_source;  // R32F: displacement to add, metres
out vec2 f_out;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    float a = ripples_held(p) ? 0.0 : texelFetch(u_source, p, 0).r;
    f_out = vec2(a, a);
}
