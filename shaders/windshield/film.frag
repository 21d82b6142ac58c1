#version 330 core
// The film texture's relaxation step (one frame): rescale last frame's film to the CPU truth it was drawn for,
// then spread (diffusion), dry (subtract: thin parts dry first, so residue dries in streaks), bead up, and clear
// what the wiper blades swept this frame down to their streaky residue. Thickness in µm. The second channel is
// the density (0..1) of the tiny beads sliding drops leave behind (stamped by their trail splats): it
// evaporates at a steady rate, so the beads of a trail vanish one by one, and the blades wipe it.
#include "windshield/glass_common.glsl"
uniform sampler2D u_film;     // unit 12: last frame's film (µm), mipmapped
uniform sampler2D u_coarse;   // unit 13: the CPU film last frame (µm cell means), FILM_CELLS²
uniform float u_coarse_lod;   // the mip level of u_film whose texels are the CPU cells
uniform vec2 u_texel;         // 1 / resolution
uniform float u_diffusion;    // D·dt/h² (≤ 0.2)
uniform float u_dry_um;       // thickness evaporated this frame (µm)
uniform float u_bead_mix;     // 1 − exp(−rate·dt)
uniform vec4 u_blade[2];      // pivot s, t (m), r inner, r outer (m)
uniform vec4 u_sweep[2];      // swept angle lo, hi (rad), 1 if swept this frame, residue (µm)
uniform int u_seed;
uniform float u_bead_dry;   // bead-trail density evaporated this frame
in vec2 v_uv;
out vec2 f_film;

// The film rescaled to the CPU's cell mean: f·ratio + even, with ratio = min(c/m, 4) and even the rest of the
// mean (a capped ratio keeps the mean exact without blowing a lone speck up where the texture had almost
// nothing). Both vary only on the coarse scale, so neighbouring texels share them.
vec2 rescale(vec2 uv) {
    float m = textureLod(u_film, uv, u_coarse_lod).r;
    float c = texture(u_coarse, uv).r;
    if (m <= 1e-6) return vec2(0.0, c);
    float ratio = min(c / m, 4.0);
    return vec2(ratio, max(c - ratio * m, 0.0));
}

void main() {
    vec2 k = rescale(v_uv);
    vec2 here = textureLod(u_film, v_uv, 0.0).rg;
    float raw = here.r;
    float trail = max(min(here.g, 1.0) - u_bead_dry, 0.0);
    float lap = textureLod(u_film, v_uv + vec2(u_texel.x, 0.0), 0.0).r
              + textureLod(u_film, v_uv - vec2(u_texel.x, 0.0), 0.0).r
              + textureLod(u_film, v_uv + vec2(0.0, u_texel.y), 0.0).r
              + textureLod(u_film, v_uv - vec2(0.0, u_texel.y), 0.0).r - 4.0 * raw;
    float f = max(k.x * (raw + u_diffusion * lap) + k.y - u_dry_um, 0.0);
    vec2 st = glass_st(v_uv);
    f = mix(f, f * bead_pattern(st), u_bead_mix);
    for (int b = 0; b < 2; ++b) {
        if (u_sweep[b].z < 0.5) continue;
        vec2 rel = st - u_blade[b].xy;
        float r = length(rel);
        float phi = atan(rel.y, rel.x);
        if (r >= u_blade[b].z && r <= u_blade[b].w && phi >= u_sweep[b].x && phi <= u_sweep[b].y) {
            f = min(f, u_sweep[b].w * wiper_streaks(r, uint(u_seed) + uint(b) * 101u));
            trail = 0.0;
        }
    }
    f_film = vec2(f, trail);
}
