#version 330 core
// The driver's view through the wet windshield, between the drops (the drops are lenses of their own pass,
// windshield/drop.frag): the water film, the beads sliding drops left behind, the wiper's drying wake and the
// blades. The street behind the glass is the frame drawn so far (without the glass), looked up along the view
// ray refracted by the water (windshield/optics.glsl). A film is misted glass: below the texture's resolution a
// field of micro-droplets and ripples, drawn as a random tilt of the surface that grows with its thickness and
// a coarse mip of the frame (blurrier than through a drop); a thin film (the wiper's wake) shows its streaks as
// a faint haze and ripple that dries away; a drop's trail clears the mist and leaves a line of tiny beads, each
// a small lens, that evaporate one by one. At night the wiper's streaky film smears the lights. Lights glint in
// the film. Output is premultiplied over the HDR frame.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/light_grid.glsl"
#include "common/atmosphere.glsl"
#include "windshield/glass_common.glsl"
#include "windshield/optics.glsl"
uniform sampler2D u_water;    // unit 12: thickness (mm), film (µm), slope of the film along s, t
uniform sampler2D u_beads;    // unit 15: the film texture: film (µm), bead-trail density (0..1)
uniform float u_film_lod;     // mip level of u_frame through the misted film (blurrier than a drop's)
uniform float u_drop_lod;     // mip level of u_frame through a bead
uniform float u_texel_m;      // size of a texel of the water texture (m)
uniform vec4 u_blade[2];      // pivot s, t (m), r inner, r outer (m)
uniform float u_blade_angle[2];
uniform float u_aperture_m;   // radius of the eye's pupil (m): the blur circle on the glass when focused far
uniform float u_focus_m;      // distance the eye is focused at (m; 1e9: the road): the glass blurs by the pupil
                              // scaled by |1 - distance / focus| (thin lens), sharp when focused on the glass
in vec3 v_pos;
in vec3 v_nrm;
in vec2 v_uv;
out vec4 f_color;

const float BEAD_CELL_M = 0.0009;  // one bead at most per cell of this size

float segment_distance(vec2 p, vec2 a, vec2 b) {
    vec2 ab = b - a;
    float x = clamp(dot(p - a, ab) / dot(ab, ab), 0.0, 1.0);
    return length(p - a - ab * x);
}

// A bead of a drop's trail at st, given the trail's density there (0..1): coverage (antialiased over foot, m)
// and the slope of its cap. Each cell holds one bead at a random place, present while the density is above the
// cell's random threshold and shrinking with it: they evaporate one by one.
vec3 bead_at(vec2 st, float density, float foot) {
    vec2 g = st / BEAD_CELL_M;
    ivec2 cell = ivec2(floor(g));
    float keep = ws_rand(cell, 41u);
    if (density <= keep * 0.9 + 0.05) return vec3(0.0);
    vec2 centre = vec2(0.3) + 0.4 * vec2(ws_rand(cell, 43u), ws_rand(cell, 47u));
    float r = BEAD_CELL_M * (0.1 + 0.17 * ws_rand(cell, 53u)) * sqrt(min(density, 1.0));
    vec2 rel = (g - vec2(cell) - centre) * BEAD_CELL_M;
    float rho = length(rel);
    float w = clamp(0.5 + (r - rho) / max(foot, 1e-6), 0.0, 1.0);
    if (w <= 0.0) return vec3(0.0);
    float d = min(rho / r, 0.95);
    vec2 slope = -rel / max(rho, 1e-9) * d / sqrt(1.0 - d * d) * 0.9;
    return vec3(w, slope);
}

void main() {
    use_light_grid();
    vec2 st = glass_st(v_uv);
    // Wiper blades and arms, opaque, on the outside of the glass.
    float blade = 0.0;
    for (int b = 0; b < 2; ++b) {
        vec2 dir = vec2(cos(u_blade_angle[b]), sin(u_blade_angle[b]));
        vec2 pivot = u_blade[b].xy;
        float rubber = segment_distance(st, pivot + dir * u_blade[b].z, pivot + dir * u_blade[b].w) - 0.011;
        float arm = segment_distance(st, pivot, pivot + dir * 0.55 * (u_blade[b].z + u_blade[b].w)) - 0.013;
        float dist = min(rubber, arm);
        float aa = max(fwidth(dist), 1e-5);
        blade = max(blade, clamp(0.5 - dist / aa, 0.0, 1.0));
    }

    vec3 V = normalize(v_pos - u_camera_pos);
    vec3 N, Ts, Tt;
    glass_frame(V, v_nrm, N, Ts, Tt);
    vec3 in_water = water_ray(V, N);
    float film = texture(u_water, v_uv).y;
    vec2 here = gl_FragCoord.xy / vec2(textureSize(u_frame, 0));

    // Film and beads, averaged over the eye's pupil (u_aperture_m) or the pixel's footprint on the glass,
    // whichever is larger: focused on the road, each point of the glass is seen through a disc the size of the
    // pupil. Beads far smaller than that disc are seen as what they are on average: a faint dimpled haze.
    float foot = max(length(dFdx(st)), length(dFdy(st)));
    float radius = max(u_aperture_m * abs(1.0 - length(v_pos - u_camera_pos) / u_focus_m), 0.5 * foot);
    // The film is sampled over at least a texel of its texture: a soft mist, never the texture's squares.
    float film_radius = max(radius, 0.7 * u_texel_m);
    float bead_sharp = clamp((2.0 * BEAD_CELL_M - radius) / BEAD_CELL_M, 0.0, 1.0);
    float cover = 0.0;
    vec3 wet_col = vec3(0.0);
    vec4 glint_dir = vec4(0.0);
    // The taps' film first, then the refracted lookups of the wet taps only, lowest first as a loop over all
    // would take them: where no fragment of a group has a wet tap (a wiped, dry glass) the lookups cost nothing
    // on llvmpipe, which leaves a loop once no fragment iterates but runs an `if` masked. (The film's texture
    // reads stay in uniform control flow, as their implicit derivatives need.)
    vec4 film_k[5];   // per tap: mist (µm), and its cover as a film, a thin film and a bead haze
    vec2 slope_k[5];  // per tap: the film's slope along s, t
    uint wet = 0u;
    for (int k = 0; k < 5; ++k) {
        vec2 uv_k = glass_uv(st + DISC_TAPS[k] * film_radius);
        vec4 w = texture(u_water, uv_k);
        float trail = clamp(texture(u_beads, uv_k).g, 0.0, 1.0);
        // A drop's trail collected the mist: the film is clearer along it.
        float mist = w.y * (1.0 - 0.7 * trail);
        float c_film = 1.0 - exp(-mist / 4.0);
        float c_thin = (1.0 - exp(-mist / 0.25)) * 0.35;  // a thin film (a drying wake): a faint streaky haze
        float c_bead = (1.0 - bead_sharp) * 0.12 * trail;  // beads far smaller than the blur: a dimpled haze
        film_k[k] = vec4(mist, c_film, c_thin, c_bead);
        slope_k[k] = w.zw;
        if (min(max(max(c_film, c_thin), c_bead), 1.0) > 0.002) wet |= 1u << uint(k);
    }
    vec3 veil = sky_ambient(-N) * u_exposure * 0.9;
    for (uint m = wet; m != 0u;) {
        int k = pop_bit(m);
        vec2 st_k = st + DISC_TAPS[k] * film_radius;
        float mist = film_k[k].x, c_film = film_k[k].y, c_thin = film_k[k].z, c_bead = film_k[k].w;
        float c = min(max(max(c_film, c_thin), c_bead), 1.0);
        // Smooth (value-noise) tilt over 2 mm cells: the micro-droplets and ripples of the film, small slopes.
        vec2 g = st_k / 0.002;
        ivec2 cell = ivec2(floor(g));
        vec2 f = g - vec2(cell);
        f = f * f * (3.0 - 2.0 * f);
        vec2 j00 = vec2(ws_rand(cell, 3u), ws_rand(cell, 7u));
        vec2 j10 = vec2(ws_rand(cell + ivec2(1, 0), 3u), ws_rand(cell + ivec2(1, 0), 7u));
        vec2 j01 = vec2(ws_rand(cell + ivec2(0, 1), 3u), ws_rand(cell + ivec2(0, 1), 7u));
        vec2 j11 = vec2(ws_rand(cell + ivec2(1, 1), 3u), ws_rand(cell + ivec2(1, 1), 7u));
        vec2 jitter = mix(mix(j00, j10, f.x), mix(j01, j11, f.x), f.y) - 0.5;
        vec2 slope = slope_k[k] + jitter * (0.12 * (1.0 - exp(-mist / 10.0)) + 0.1 * c_thin + 0.2 * c_bead);
        vec3 out_dir;
        float transmit;
        vec3 col = through_water(v_pos, in_water, N, Ts, Tt, slope, u_film_lod, out_dir, transmit);
        // Mist scatters a little of the sky's light towards the eye: the film is a brighter veil.
        col = mix(col, veil, 0.1 * c_film);
        if (k == 0 && transmit > 0.0) glint_dir = vec4(out_dir, transmit);  // glints from the centre tap only
        wet_col += col * c;
        cover += c;
    }
    wet_col /= max(cover, 1e-6);
    cover *= 0.2;
    vec3 glint = exposed_glints(v_pos, glint_dir) * 0.05 * cover;
    // The beads of drops' trails, each a tiny lens, where the eye resolves them (the glass close-up).
    if (bead_sharp > 0.0) {
        vec2 uv = glass_uv(st);
        vec3 bead = bead_at(st, clamp(texture(u_beads, uv).g, 0.0, 1.0), foot);
        float wb = bead.x * bead_sharp;
        if (wb > 0.0) {
            vec3 out_dir;
            float transmit;
            vec3 col = through_water(v_pos, in_water, N, Ts, Tt, bead.yz, u_drop_lod, out_dir, transmit);
            wet_col = mix(wet_col, col, wb / max(max(cover, wb), 1e-6));
            cover = max(cover, wb);
        }
    }
    // Along the wiper's arcs a streaky film smears bright lights (only what is brighter than white).
    float smear = clamp(film / 0.3, 0.0, 1.0) * 0.35;
    vec3 glare = vec3(0.0);
    if (smear > 0.0) {
        vec2 rel = st - u_blade[0].xy;
        vec2 tang_st = normalize(vec2(-rel.y, rel.x));
        vec2 along = screen_of(v_pos + 0.05 * (tang_st.x * u_axis_s + tang_st.y * u_axis_t), V) - here;
        along /= max(length(along), 1e-6);
        for (int k = -2; k <= 2; ++k)
            glare += max(textureLod(u_frame, here + along * float(k) * 0.016, 2.0).rgb - vec3(1.0), 0.0);
        glare *= smear / 5.0;
    }
    vec3 color = wet_col * cover + glint + glare;
    float alpha = cover;

    vec3 blade_col = vec3(0.012) * sky_ambient(-V) * u_exposure + vec3(0.002) * u_exposure;
    f_color = vec4(mix(color, blade_col, blade), mix(alpha, 1.0, blade));
}
