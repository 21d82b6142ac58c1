#version 330 core
// Spray parcels, blended premultiplied over the HDR frame. A parcel is a Gaussian cloud of drops of optical
// depth tau (its extinction area over its footprint); its opacity is 1 − e^(−tau) and its radiance per unit
// opacity is the scattered light of spray/shading.glsl (flat, from the vertex), so spray is translucent and as
// bright as what it scatters, never a white body.
//   Mist: a smooth medium, opacity 1 − e^(−tau) exactly (the extinction the emitter's line of sight computes).
//   Droplets: where a parcel spans a few pixels its drops show. A share SPRAY_STREAK_SHARE of its optical depth
//   is drawn as streaks about a pixel wide, each a drop (a clump of them) smeared along the parcel's screen
//   motion over the exposure; the rest, the drops too fine to see, stays a thin smooth veil. Streaks are laid
//   in cells (rows a couple of pixels apart, cells one streak long), each holding at most one streak at a
//   hashed place, so a fragment looks at three cells: the expected opacity follows the parcel's Gaussian.
//   Young splash parcels (sheet share v_misc.w) are still sheets of water: smooth, the streaks come as they
//   break up.
// The scene's depth (read as a texture: the pass writes through a colour-only framebuffer) hides parcels behind
// geometry and fades them softly where they meet it.

uniform sampler2D u_depth;
uniform vec2 u_viewport;
uniform float u_near;
uniform float u_far;

in vec2 v_coord;
in float v_view_depth;
flat in vec4 v_shape;
flat in vec4 v_misc;
flat in vec3 v_radiance;
flat in float v_pixel_m;
out vec4 f_color;

float linear_depth(float d) {
    float z = d * 2.0 - 1.0;
    return 2.0 * u_near * u_far / (u_far + u_near - z * (u_far - u_near));
}

float hash12(vec2 p) {
    vec3 p3 = fract(vec3(p.xyx) * 0.1031);
    p3 += dot(p3, p3.yzx + 33.33);
    return fract((p3.x + p3.y) * p3.z);
}

// Opacity of the streaks of droplet parcel at c (m, along/across the streak): half streak length hl, Gaussian
// sizes sa/sb, instantaneous centre optical depth tau_i of the streaked share, pixel size px (m), seed.
float streaks(vec2 c, float hl, float sa, float sb, float tau_i, float px, float seed) {
    float w = 0.7 * px;                // half-width of a streak, and the ramp at its ends
    float row = 2.0 * w;               // rows of streaks
    float cell = 2.0 * hl + 3.0 * w;   // one streak and a gap
    float fill = (2.0 * hl + w) * w / (cell * row);  // share of a row a streak in every cell would cover
    float j = floor(c.y / row);
    float k0 = floor(c.x / cell);
    float clear = 1.0;
    for (int dk = -1; dk <= 1; ++dk) {
        vec2 id = vec2(k0 + float(dk), j) + seed;
        float h_along = hash12(id);
        float h_across = hash12(id + 17.31);
        float h_keep = hash12(id + 41.07);
        float h_size = hash12(id + 73.9);
        vec2 centre = vec2((k0 + float(dk) + h_along) * cell, (j + 0.25 + 0.5 * h_across) * row);
        vec2 g = centre / vec2(sa, sb);
        float q = tau_i * exp(-0.5 * dot(g, g)) / fill;  // expected opacity × chance the cell needs
        float chance = min(q / SPRAY_STREAK_ALPHA, 1.0);
        if (h_keep >= chance) continue;
        float a = min(q / chance, 1.0) * (0.5 + h_size);
        float along = clamp((hl + w - abs(c.x - centre.x)) / w, 0.0, 1.0);
        float across = clamp(1.0 - abs(c.y - centre.y) / w, 0.0, 1.0);
        clear *= 1.0 - min(a, 1.0) * along * across;
    }
    return 1.0 - clear;
}

void main() {
    float half_len = v_shape.x;
    float sigma_a = v_shape.y;
    float sigma_b = v_shape.z;
    bool mist = v_misc.x > 0.5;
    float along = max(abs(v_coord.x) - half_len, 0.0);
    vec2 r = vec2(along, v_coord.y) / vec2(sigma_a, sigma_b);
    float edge = mist ? 2.5 : 3.0;
    float cut = exp(-0.5 * edge * edge);
    float density = max(exp(-0.5 * dot(r, r)) - cut, 0.0) / (1.0 - cut);
    float tau = v_shape.w * density;

    // Depth: behind the scene → hidden; close in front of it → faded over about a sigma.
    float scene = linear_depth(texture(u_depth, gl_FragCoord.xy / u_viewport).r);
    float soft = clamp((scene - v_view_depth) / max(sigma_b * (mist ? 0.7 : 1.0), 0.02), 0.0, 1.0);
    float near = mist ? clamp((v_view_depth - 0.3) / 1.7, 0.0, 1.0) : clamp((v_view_depth - 0.05) / 0.25, 0.0, 1.0);
    float vis = v_misc.z * soft * near;
    if (vis * tau < 1.0 / 4096.0) discard;

    float alpha;
    if (mist) {
        alpha = 1.0 - exp(-tau);
    } else {
        // Streaks show where the parcel spans a few pixels across and once a splash sheet has broken up.
        float detail = clamp(sigma_b / (2.0 * v_pixel_m) - 0.5, 0.0, 1.0) * (1.0 - v_misc.w);
        float share = SPRAY_STREAK_SHARE * detail;
        float streak = 0.0;
        if (share > 0.0) {
            // The streaked share's optical depth at the centre of an unsmeared parcel (its drops' positions).
            float tau_i = share * v_shape.w * (1.0 + 0.79788 * half_len / sigma_a);
            streak = streaks(v_coord, half_len, sigma_a, sigma_b, tau_i, v_pixel_m, v_misc.y * 517.0);
        }
        alpha = 1.0 - exp(-(1.0 - share) * tau) * (1.0 - streak);
    }
    alpha *= vis;
    if (alpha < 1.0 / 1024.0) discard;
    f_color = vec4(v_radiance * alpha, alpha);
}
