#version 330 core
// A drip's light: a water drop refracts a wide cone of what is above and around it (Garg & Nayar 2007), so it
// shows roughly the sky and the street's lights, brighter than the shade under a roof it falls through.
#include "common/frame.glsl"
#include "common/sky.glsl"
in vec2 v_uv;
in float v_alpha;
in float v_round;
in vec3 v_pos;
out vec4 f_color;
void main() {
    float shape = v_round > 0.5 ? step(length(vec2(v_uv.x, v_uv.y * 2.0 - 1.0)), 1.0) : 1.0;
    float alpha = clamp(v_alpha * shape, 0.0, 1.0);
    if (alpha <= 0.0) discard;
    vec3 L = 0.8 * sky_radiance(vec3(0.0, 1.0, 0.0), false) + 0.2 * sky_radiance(vec3(0.0, 0.05, 1.0), false);
    for (int i = 0; i < u_light_count; ++i) {  // the lamps' glints: a drop sends ~1/(4π) of what reaches it
        vec3 d = u_light_pos[i].xyz - v_pos;
        L += u_light_color[i].rgb / max(dot(d, d), 1.0) * 0.08;
    }
    f_color = vec4(L * u_exposure * alpha, alpha);
}
