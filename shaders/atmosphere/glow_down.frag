#version 330 core
// Glow, step 1: the light each pixel loses to scattering on its way to the eye, box-averaged down to the glow
// resolution. A pixel at distance d keeps exp(−β·d) of its light; a share (1 − exp(−β·d)) is scattered, and its
// forward part reaches the eye from nearby directions: that is the halo (blurred next, added back last).
// Alpha: the least light a pixel of the block keeps after the composite moves its halo share away, its dimmest
// channel (hdr·(1 − k·w), composite.frag's). The composite skips lights whose in-scatter is a small share of it.
#include "common/frame.glsl"
#include "common/atmosphere.glsl"
#include "common/depth.glsl"
uniform sampler2D u_color;   // pre-exposed HDR scene
uniform int u_factor;        // full-resolution pixels per glow texel (per axis)
uniform float u_glow_strength;  // k, as in composite.frag (0: no halo drawn; the alpha still made)
out vec4 f_color;

void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * u_factor;
    ivec2 size = textureSize(u_color, 0);
    vec3 sum = vec3(0.0);
    float n = 0.0;
    float kept = 65504.0;  // the largest half float
    for (int j = 0; j < u_factor; ++j) {
        for (int i = 0; i < u_factor; ++i) {
            ivec2 p = base + ivec2(i, j);
            if (p.x >= size.x || p.y >= size.y) continue;
            vec3 dir;
            bool sky;
            float d = atmosphere_pixel_ray(p, vec2(size), u_camera_pos, 0.0, dir, sky);
            if (sky) d = atmosphere_sky_path_m(dir);
            vec3 c = max(texelFetch(u_color, p, 0).rgb, vec3(0.0));
            if (any(isnan(c)) || any(isinf(c))) c = vec3(0.0);  // one bad pixel must not become a blurred disc
            float w = 1.0 - exp(-u_medium_extinction_per_m * d);
            sum += c * w;
            n += 1.0;
            float k = min(u_glow_strength, 1.0 / max(w, 1e-6));  // composite.frag's k_eff
            kept = min(kept, min(c.r, min(c.g, c.b)) * max(1.0 - k * w, 0.0));
        }
    }
    f_color = vec4(sum / max(n, 1.0), n > 0.0 ? kept : 0.0);
}
