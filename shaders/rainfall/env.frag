#version 330 core
// What a drop shows (rain_core/effects/rainfall/optics.py, the NumPy twin drop_environment): for each view direction
// d (equirectangular texel, eye → drop), the drop's luminance (cd/m²) in the environment the camera sees: the sky
// through the rain layer as the sky pass draws it (apply_sky_atmosphere), the lit ground below through the rain
// between it and a drop RAIN_ENV_HEIGHT_M above it —
// Garg & Nayar's photometric model of a drop summed over its disc: refraction through it (its ~165° field of
// view, inverted, most of the disc showing what lies just behind it), specular reflection and one internal
// reflection, each node a source direction at the deviation γ from d with its Fresnel weight (u_optic_*).
// Drawn once per frame; the streak and splash passes read it instead of integrating per vertex.
#include "common/frame.glsl"
#include "common/sky.glsl"
#include "common/atmosphere.glsl"
#define RAIN_OPTIC_NODES 64  // optics.N_NODES
in vec2 v_uv;
out vec4 f_color;
const float PI = 3.14159265;
uniform vec4 u_optic_dir[RAIN_OPTIC_NODES];  // cos γ, sin γ, cos φ, sin φ
uniform float u_optic_w[RAIN_OPTIC_NODES];   // share of the drop's disc × Fresnel factor
const float RAIN_ENV_HEIGHT_M = 1.5;  // m, height of the drops a driver sees (optics.ENV_HEIGHT_M)

// Radiance (cd/m²) arriving at a drop from direction s (unit, drop → source).
vec3 rain_env_radiance(vec3 s) {
    vec3 L = sky_radiance(s, false);
    if (s.y >= 0.0) return apply_sky_atmosphere(L, s);
    return apply_atmosphere_dir(L, RAIN_ENV_HEIGHT_M / max(-s.y, 1e-4), s);
}
void main() {
    float phi = v_uv.x * 2.0 * PI;
    float theta = v_uv.y * PI;
    vec3 d = vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    vec3 helper = abs(d.y) < 0.95 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 a = normalize(cross(d, helper));
    vec3 b = cross(a, d);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < RAIN_OPTIC_NODES; ++i) {
        vec4 o = u_optic_dir[i];
        sum += u_optic_w[i] * rain_env_radiance(normalize(d * o.x + (a * o.z + b * o.w) * o.y));
    }
    f_color = vec4(sum, 1.0);
}
