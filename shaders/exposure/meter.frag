#version 330 core
// One texel of the exposure meter: the centre-weighted log2 luminance of its patch of the pre-exposed frame,
// as (weight × mean log2 L of 2×2 bilinear taps, weight); the texture's mip chain then averages both, so its top
// level's ratio is the frame's weighted mean (rain_core/exposure.py: metered_log2_luminance, the reference).
#include "exposure/meter.glsl"
uniform sampler2D u_hdr;
uniform vec2 u_meter_size;  // texels (w, h)
out vec2 f_meter;

float log_luminance(vec2 uv) {
    vec3 c = textureLod(u_hdr, uv, 0.0).rgb;
    if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);  // a bad pixel counts as black, never as NaN
    float lum = dot(max(c, vec3(0.0)), vec3(0.2126, 0.7152, 0.0722));
    return max(log2(max(lum, exp2(LOG2_FLOOR))), LOG2_FLOOR);
}

void main() {
    vec2 cell = floor(gl_FragCoord.xy);
    float sum = 0.0;
    for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a)
            sum += log_luminance((cell + (vec2(a, b) + 0.5) * 0.5) / u_meter_size);
    vec2 d = ((cell + 0.5) / u_meter_size - METER_CENTRE) / METER_SIGMA;
    float weight = exp(-0.5 * dot(d, d));
    f_meter = vec2(weight * 0.25 * sum, weight);
}
