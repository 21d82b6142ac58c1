#version 330 core
// A splash seen from the side: on water a crown (a thin sheet ring that rises and collapses, with a brighter
// rim) throwing droplets; on a dry surface a prompt splash (droplets only, flatter). Droplets follow ballistic
// arcs; ones smaller than a pixel are drawn a pixel wide with the same light (so far splashes do not vanish).
in vec2 v_m;
flat in vec4 v_shape;
flat in vec4 v_kind;
flat in vec4 v_color;
uniform float u_splash_alpha_max;
out vec4 f_color;

const float G = 9.81;

float hash(float n) {
    return fract(sin(n) * 43758.5453);
}

float disc(vec2 q, vec2 c, float r, float px) {
    float re = max(r, 0.6 * px);
    return (r * r) / (re * re) * clamp((re - length(q - c)) / px + 0.5, 0.0, 1.0);
}

void main() {
    float age = v_shape.x;
    float phase = clamp(age / v_shape.y, 0.0, 1.0);
    float crown = v_shape.z;
    float d = v_shape.w;
    float px = v_kind.z;
    float seed = v_kind.y * 97.0;
    bool prompt = v_kind.x > 1.5;
    float cov = 0.0;
    float rc = d * (0.8 + 2.2 * sqrt(phase));
    if (!prompt) {
        float hc = crown * sin(3.14159265 * min(phase / 0.75, 1.0));
        float s = abs(v_m.x);
        float top = hc * (0.65 + 0.35 * min(s / rc, 1.0) * min(s / rc, 1.0));
        float inside = clamp((top - v_m.y) / px + 0.5, 0.0, 1.0) * clamp(v_m.y / px + 0.5, 0.0, 1.0);
        float rim = clamp(1.0 - abs(v_m.y - top) / max(0.15 * crown, px), 0.0, 1.0);
        float edge = clamp((rc - s) / px + 0.5, 0.0, 1.0);
        cov = edge * max(0.3 * inside, 0.8 * rim) * step(px * 0.25, hc);
    }
    int n = prompt ? 8 : 6;
    float h_max = prompt ? 0.6 * crown : 1.5 * crown;
    for (int k = 0; k < 8; ++k) {
        if (k >= n) break;
        float r1 = hash(seed + float(k) * 1.731);
        float r2 = hash(seed * 1.37 + float(k) * 2.917);
        float r3 = hash(seed * 2.11 + float(k) * 0.613);
        float ang = 6.2831853 * (float(k) + r1) / float(n);
        float v_up = sqrt(2.0 * G * h_max) * (0.6 + 0.4 * r2);
        float v_out = (prompt ? 1.5 : 0.6) * v_up * (0.5 + r3);
        vec2 c = vec2(cos(ang) * (rc + v_out * age), v_up * age - 0.5 * G * age * age);
        if (c.y < 0.0) continue;
        cov = max(cov, disc(v_m, c, 0.12 * d * (0.7 + 0.6 * r2), px));
    }
    float a = min(v_color.a * cov, u_splash_alpha_max);
    if (a <= 0.0) discard;
    f_color = vec4(v_color.rgb, a);
}
