#version 330 core
// What a drop shows (rain_core/effects/rainfall/): for each view direction d (equirectangular texel), the mean sky
// radiance (cd/m²) over the ~165° field of view behind the drop around d (Garg & Nayar 2004) — 64 directions
// spread evenly over the spherical cap (Fibonacci spiral). Drawn once per frame; the streak and splash passes
// read it instead of integrating per vertex.
#include "common/frame.glsl"
#include "common/sky.glsl"
in vec2 v_uv;
out vec4 f_color;
const float PI = 3.14159265;
const int N = 64;
const float COS_HALF = 0.13052619;  // cos(82.5°)
void main() {
    float phi = v_uv.x * 2.0 * PI;
    float theta = v_uv.y * PI;
    vec3 d = vec3(sin(theta) * cos(phi), cos(theta), sin(theta) * sin(phi));
    vec3 helper = abs(d.y) < 0.95 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 a = normalize(cross(d, helper));
    vec3 b = cross(a, d);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < N; ++i) {
        float c = 1.0 - (float(i) + 0.5) / float(N) * (1.0 - COS_HALF);  // uniform in solid angle
        float s = sqrt(max(1.0 - c * c, 0.0));
        float az = float(i) * 2.39996323;  // golden angle
        sum += sky_radiance(normalize(d * c + (a * cos(az) + b * sin(az)) * s), false);
    }
    f_color = vec4(sum / float(N), 1.0);
}
