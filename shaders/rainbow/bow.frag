#version 330 core
// The rainbow: sunlight the rain drops scatter into the angle θ from the antisolar point (rain_core/effects/
// rainbow/optics.py computes P(θ), 1/sr, linear RGB), in single scattering over the rain the eye ray crosses:
// L = E_sun · P(θ) · (1 − exp(−β·ℓ)), ℓ the ray's length inside the rain (shower.py) before the first surface or
// the cloud base. Added to the HDR colour (blending ONE, ONE).
#include "common/frame.glsl"
#include "common/depth.glsl"
uniform sampler2D u_bow_lut;   // P(θ): width = samples over [u_theta_range.x, u_theta_range.y] rad, 1 row
uniform vec2 u_theta_range;    // rad
uniform float u_rain_beta;     // 1/m, the rain's extinction
uniform vec2 u_rain_span_m;    // near, far (m) along every ray where there is rain
uniform float u_cloud_base_m;  // m above the eye: rays into the sky leave the rain there
uniform float u_strength;      // ×
out vec4 f_color;

void main() {
    vec3 dir;
    bool sky;
    float dist = atmosphere_pixel_ray(ivec2(gl_FragCoord.xy), vec2(textureSize(u_depth, 0)), u_camera_pos, 1e9,
                                      dir, sky);
    float theta = acos(clamp(dot(dir, -u_sun_dir), -1.0, 1.0));
    float u = (theta - u_theta_range.x) / (u_theta_range.y - u_theta_range.x);
    if (u <= 0.0 || u >= 1.0) discard;
    float end = dir.y > 1e-4 ? min(dist, u_cloud_base_m / dir.y) : dist;
    float inside = max(min(end, u_rain_span_m.y) - u_rain_span_m.x, 0.0);
    float scattered = 1.0 - exp(-u_rain_beta * inside);
    vec3 p = texture(u_bow_lut, vec2(u, 0.5)).rgb;
    f_color = vec4(p * u_sun_illum * scattered * u_strength * u_exposure, 0.0);
}
