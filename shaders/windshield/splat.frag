#version 330 core
#include "windshield/glass_common.glsl"
in vec2 v_local;
flat in vec4 v_info;
flat in float v_len;
out vec2 f_value;  // the target's value; a film target also takes a trail's bead density (green)
uniform float u_cap_rn;   // sphere radius / contact radius of a drop's cap (1 / sin θ)
void main() {
    float r = v_info.x;
    int kind = int(v_info.z + 0.5);
    float along = clamp(v_local.x, 0.0, v_len);
    float d = length(vec2(v_local.x - along, v_local.y)) / r;
    if (d >= 1.0) discard;
    float value;
    float beads = 0.0;
    if (kind == 0) {
        // Spherical cap normalised to height 1 at the centre; the tail thins towards p1.
        float rn2 = u_cap_rn * u_cap_rn;
        float cap = (sqrt(rn2 - d * d) - sqrt(rn2 - 1.0)) / (u_cap_rn - sqrt(rn2 - 1.0));
        float taper = v_len > 0.0 ? 1.0 - 0.6 * along / v_len : 1.0;
        value = v_info.y * cap * taper;
    } else if (kind == 1) {
        value = v_info.y * sqrt(1.0 - d * d);
        beads = d < 0.8 ? 1.0 : 0.0;  // a drop's trail: the beads it leaves (the film target keeps them)
    } else {
        vec2 p = v_local / (0.25 * r);
        float speck = step(0.72, ws_rand(ivec2(floor(p)), uint(v_info.w)));
        value = v_info.y * speck * 3.5 * (1.0 - d);
    }
    f_value = vec2(value, beads);
}
