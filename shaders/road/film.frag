#version 330 core
// Evaluates road_water_depths_mm at arbitrary points: the GPU side of the film-depth parity test, and a way for
// CPU code to ask the shader's model. One texel of u_points (x, z in m, wrapped frame) per output texel.
#include "road/film.glsl"
uniform sampler2D u_points;
out vec4 f_depth;  // standing water (mm), wet film (mm), film depth (mm), 0
void main() {
    vec2 xz = texelFetch(u_points, ivec2(gl_FragCoord.xy), 0).rg;
    vec2 d = road_water_depths_mm(xz);
    f_depth = vec4(d, max(d.x, d.y), 0.0);
}
