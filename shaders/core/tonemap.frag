#version 330 core
// Pre-exposed HDR → display: the eye's exposure correction (stops), the ACES filmic fit (Narkowicz 2015), then the
// sRGB transfer curve.
uniform sampler2D u_hdr;
uniform sampler2D u_exposure_ev;  // 1×1: the automatic exposure's correction (rain_core/gfx/exposure.py)
uniform bool u_auto_exposure;
uniform float u_compensation_ev;  // with automatic exposure off: the user's compensation alone
in vec2 v_uv;
out vec4 f_color;
vec3 aces(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}
vec3 srgb_encode(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
void main() {
    vec3 hdr = texture(u_hdr, v_uv).rgb;
    hdr = max(hdr, vec3(0.0));
    if (any(isnan(hdr)) || any(isinf(hdr))) hdr = vec3(0.0);  // never let a bad value reach the screen
    float ev = u_auto_exposure ? texelFetch(u_exposure_ev, ivec2(0), 0).r : u_compensation_ev;
    f_color = vec4(srgb_encode(aces(hdr * exp2(ev))), 1.0);
}
