#version 330 core
// The water texture the glass shader reads: total thickness (mm), film (µm, rescaled to the CPU truth) and the
// slope of the film's surface along s and t (dimensionless), by central differences in metres. The drops are
// not in the slope: they are lenses of their own (windshield/drop.frag), analytic and round at any resolution.
#include "windshield/glass_common.glsl"
uniform sampler2D u_drops;    // unit 12: drop and bead heights (mm)
uniform sampler2D u_film;     // unit 13: film (µm), mipmapped
uniform sampler2D u_coarse;   // unit 14: the CPU film now (µm cell means)
uniform float u_coarse_lod;
uniform vec2 u_texel;
in vec2 v_uv;
out vec4 f_water;

// The film rescaled to the CPU's cell mean (see windshield_film.frag): f·ratio + even.
vec2 rescale(vec2 uv) {
    float m = textureLod(u_film, uv, u_coarse_lod).r;
    float c = texture(u_coarse, uv).r;
    if (m <= 1e-6) return vec2(0.0, c);
    float ratio = min(c / m, 4.0);
    return vec2(ratio, max(c - ratio * m, 0.0));
}

float water_mm(vec2 uv, vec2 k) {
    return 1e-3 * (k.x * textureLod(u_film, uv, 0.0).r + k.y);
}

void main() {
    vec2 k = rescale(v_uv);  // coarse-scale: shared by the neighbours
    float film = k.x * textureLod(u_film, v_uv, 0.0).r + k.y;
    float h = textureLod(u_drops, v_uv, 0.0).r + 1e-3 * film;
    vec2 du = vec2(u_texel.x, 0.0), dv = vec2(0.0, u_texel.y);
    float t = v_uv.y * u_glass.z;
    float ds = 2.0 * u_texel.x * glass_width(t) * 1000.0;  // mm between the samples
    float dt = 2.0 * u_texel.y * u_glass.z * 1000.0;
    float gs = (water_mm(v_uv + du, k) - water_mm(v_uv - du, k)) / ds;
    float gt = (water_mm(v_uv + dv, k) - water_mm(v_uv - dv, k)) / dt;
    f_water = vec4(h, film, gs, gt);
}
