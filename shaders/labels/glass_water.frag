#version 330 core
// Label images: water on the windshield as seen, 0..1, as the output alpha (used with windshield/glass.vert).
// The coverage glass.frag gives the water layer: drops (thickness, mm) and film (µm) over the eye's pupil or
// the pixel's footprint, whichever is larger, averaged over the same five taps; the wiper blades are not water.
#include "windshield/glass_common.glsl"
uniform sampler2D u_water;   // the windshield's water texture: thickness (mm), film (µm), slopes
uniform float u_aperture_m;  // radius of the eye's pupil (m)
in vec3 v_pos;
in vec3 v_nrm;
in vec2 v_uv;
out vec4 f_color;

void main() {
    vec2 st = glass_st(v_uv);
    float foot = max(length(dFdx(st)), length(dFdy(st)));
    float radius = max(u_aperture_m, 0.5 * foot);
    const vec2 taps[5] = vec2[5](vec2(0.0), vec2(0.7, 0.25), vec2(-0.25, 0.7), vec2(-0.7, -0.25),
                                 vec2(0.25, -0.7));
    float cover = 0.0;
    for (int k = 0; k < 5; ++k) {
        vec4 w = texture(u_water, glass_uv(st + taps[k] * radius));
        float c_drop = smoothstep(0.004, 0.03, w.x - 1e-3 * w.y);
        float c_film = 1.0 - exp(-w.y / 5.0);
        cover += max(c_drop, c_film);
    }
    f_color = vec4(0.0, 0.0, 0.0, clamp(cover * 0.2, 0.0, 1.0));
}
