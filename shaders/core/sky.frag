#version 330 core
// The sky behind everything: drawn first, depth untouched.
#include "common/frame.glsl"
#include "common/sky.glsl"
#include "common/atmosphere.glsl"
uniform mat4 u_inv_view_proj;
in vec2 v_uv;
out vec4 f_color;
void main() {
    vec4 p = u_inv_view_proj * vec4(v_uv * 2.0 - 1.0, 1.0, 1.0);
    vec3 dir = normalize(p.xyz / p.w - u_camera_pos);
    vec3 radiance = sky_radiance(dir, true);
    radiance = apply_sky_atmosphere(radiance, dir);
    f_color = vec4(radiance * u_exposure, 1.0);
}
