#version 330 core
// Radiance of a sub-pixel line source: a channel of luminous intensity i (cd per metre of channel) seen at
// distance d by a pixel of angular size θ has luminance i / (d·θ) (its light over the pixel's solid angle θ²
// from a length d·θ of channel), dimmed by the medium's transmittance exp(−β·d). The strip spreads it across
// its width with a normalised Gaussian (the sum across the strip is one pixel's worth).
#include "common/frame.glsl"
uniform float u_line_cd_per_m;    // the stroke's intensity over the channel's length (cd/m), shutter-averaged
uniform float u_pixel_rad;        // angular size of a pixel
uniform float u_half_width_px;
uniform vec3 u_bolt_color;        // linear RGB, mean 1
in float v_across;
in float v_weight;
in float v_dist;
out vec4 f_color;
void main() {
    float x = v_across * u_half_width_px;  // px from the channel's centre line
    float sigma = u_half_width_px / 2.5;
    float spread = exp(-0.5 * x * x / (sigma * sigma)) / (sigma * 2.5066283);
    float L = u_line_cd_per_m * v_weight / (v_dist * u_pixel_rad) * exp(-u_extinction_per_m * v_dist);
    f_color = vec4(u_bolt_color * L * spread * u_exposure, 0.0);
}
