#version 330 core
// The driver's view through the wet windshield. The street behind the glass is the frame drawn so far (without
// the glass); each pixel of the glass looks it up along the view ray refracted by the water on the glass:
// into the water through the flat glass, out through the water surface (normal from the water texture). A drop
// is a small ball lens, so that is a tiny inverted fish-eye of what lies behind it; where the exit angle is past
// the critical angle (drop rims at the grazing view of a raked glass) the ray is reflected back into the dark
// cabin. Drops show the street slightly blurred and brighter or darker as they gather light from a wide field;
// a film blurs and ripples the view and, at night, smears the lights along the wiper's streaks. Lights (lamps,
// headlights, the sun) glint in the drops. The wiper blades are drawn on the glass. Output is premultiplied
// over the HDR frame.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/atmosphere.glsl"
#include "windshield/glass_common.glsl"
uniform sampler2D u_water;    // unit 12: thickness (mm), film (µm), slope along s, t
uniform sampler2D u_frame;    // unit 13: the frame without the glass (pre-exposed HDR), mipmapped
uniform sampler2D u_depth;    // unit 14: its depth
uniform vec2 u_near_far;      // camera near, far (m)
uniform float u_cabin_depth;  // m: what the frame shows nearer than this is the cabin, not the street
uniform vec3 u_axis_s;        // world direction of +s (the car's right)
uniform vec3 u_axis_t;        // world direction of +t (up the glass)
uniform float u_refraction;   // × the physical bending
uniform float u_drop_lod;     // mip level of u_frame for the slight blur through water
uniform vec4 u_blade[2];      // pivot s, t (m), r inner, r outer (m)
uniform float u_blade_angle[2];
uniform float u_aperture_m;   // radius of the eye's pupil (m): the blur circle on the glass when focused far
uniform float u_focus_m;      // distance the eye is focused at (m; 1e9: the road): the glass blurs by the pupil
                              // scaled by |1 - distance / focus| (thin lens), sharp when focused on the glass
uniform vec3 u_cabin;         // luminance seen by total internal reflection (the dark cabin), pre-exposed
in vec3 v_pos;
in vec3 v_nrm;
in vec2 v_uv;
out vec4 f_color;

const float N_WATER = 1.333;

vec2 screen_of(vec3 origin, vec3 dir) {
    vec4 clip = u_view_proj * vec4(origin + dir * 50.0, 1.0);
    if (clip.w <= 1e-4) return vec2(-1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}

float view_depth(vec2 uv) {
    float z = textureLod(u_depth, uv, 0.0).r * 2.0 - 1.0;
    float n = u_near_far.x, f = u_near_far.y;
    return 2.0 * n * f / (f + n - z * (f - n));
}

// What a ray leaving the glass at v_pos along dir sees: the frame where it shows the street, else (off screen,
// or where the frame shows the cabin in front of the glass) the sky and the lit ground through the rain.
vec3 behind_glass(vec3 dir, float lod) {
    vec3 sky = apply_sky_atmosphere(sky_radiance(dir, false), dir) * u_exposure;
    vec2 uv = screen_of(v_pos, dir);
    vec2 edge = min(uv, 1.0 - uv);
    float on_screen = smoothstep(0.0, 0.02, min(edge.x, edge.y));
    if (on_screen <= 0.0) return sky;
    float street = on_screen * smoothstep(0.8, 1.0, view_depth(uv) / u_cabin_depth);
    return mix(sky, textureLod(u_frame, uv, lod).rgb, street);
}

float segment_distance(vec2 p, vec2 a, vec2 b) {
    vec2 ab = b - a;
    float x = clamp(dot(p - a, ab) / dot(ab, ab), 0.0, 1.0);
    return length(p - a - ab * x);
}

// Glints: lights seen through the drop along the refracted ray (a narrow lobe around each light's direction).
vec3 glints(vec3 dir) {
    vec3 sum = u_sun_illum * 0.3 * pow(max(dot(dir, u_sun_dir), 0.0), 3000.0) * 3001.0 / 6.2832;
    for (int i = 0; i < u_light_count; ++i) {
        vec3 d = u_light_pos[i].xyz - v_pos;
        float dist2 = dot(d, d);
        float range = u_light_pos[i].w;
        if (dist2 > range * range) continue;
        vec3 L = d * inversesqrt(dist2);
        float c = dot(dir, L);
        if (c < 0.99) continue;
        vec3 lux = u_light_color[i].rgb * spot_factor(i, L) / max(dist2, 0.25);
        sum += lux * pow(c, 600.0) * 601.0 / 6.2832;
    }
    return sum;
}

void main() {
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
    vec3 N = normalize(v_nrm);
    if (dot(N, V) < 0.0) N = -N;  // outward = away from the eye
    vec3 Ts = normalize(u_axis_s - N * dot(N, u_axis_s));
    vec3 Tt = normalize(cross(N, Ts));
    if (dot(Tt, u_axis_t) < 0.0) Tt = -Tt;
    float film = texture(u_water, v_uv).y;
    vec2 here = gl_FragCoord.xy / vec2(textureSize(u_frame, 0));

    // Drops and film: refraction through the water surface, averaged over the eye's pupil (u_aperture_m) or
    // the pixel's footprint on the glass, whichever is larger. The eye is focused on the road, so each point of
    // the glass is seen through a disc the size of the pupil: drops of a millimetre or two are soft blobs of
    // their inverted images and dark rims, not sharp dots. A film is not flat either: below the texture's
    // resolution it is a field of micro-droplets and ripples, drawn as a random tilt of the surface that
    // grows with its thickness, and a blur.
    vec3 in_water = refract(V, -N, 1.0 / N_WATER);
    float foot = max(length(dFdx(st)), length(dFdy(st)));
    float radius = max(u_aperture_m * abs(1.0 - length(v_pos - u_camera_pos) / u_focus_m), 0.5 * foot);
    float cover = 0.0;
    float drop_cover = 0.0;
    vec3 wet_col = vec3(0.0);
    vec4 glint_dir = vec4(0.0);
    const vec2 taps[5] = vec2[5](vec2(0.0), vec2(0.7, 0.25), vec2(-0.25, 0.7), vec2(-0.7, -0.25),
                                 vec2(0.25, -0.7));
    for (int k = 0; k < 5; ++k) {
        vec2 st_k = st + taps[k] * radius;
        vec4 w = texture(u_water, glass_uv(st_k));
        float c_drop = smoothstep(0.004, 0.03, w.x - 1e-3 * w.y);
        float c_film = 1.0 - exp(-w.y / 5.0);
        float c = max(c_drop, c_film);
        if (c <= 0.002) continue;
        // Smooth (value-noise) tilt over 2 mm cells: constant per cell it shows as squares once the eye focuses
        // on the glass (the glass camera), where no pupil blur averages the cells.
        vec2 g = st_k / 0.002;
        ivec2 cell = ivec2(floor(g));
        vec2 f = g - vec2(cell);
        f = f * f * (3.0 - 2.0 * f);
        vec2 j00 = vec2(ws_rand(cell, 3u), ws_rand(cell, 7u));
        vec2 j10 = vec2(ws_rand(cell + ivec2(1, 0), 3u), ws_rand(cell + ivec2(1, 0), 7u));
        vec2 j01 = vec2(ws_rand(cell + ivec2(0, 1), 3u), ws_rand(cell + ivec2(0, 1), 7u));
        vec2 j11 = vec2(ws_rand(cell + ivec2(1, 1), 3u), ws_rand(cell + ivec2(1, 1), 7u));
        vec2 jitter = mix(mix(j00, j10, f.x), mix(j01, j11, f.x), f.y) - 0.5;
        vec2 slope = w.zw + jitter * 0.5 * (1.0 - exp(-w.y / 10.0));
        vec3 Nw = normalize(N - u_refraction * (slope.x * Ts + slope.y * Tt));
        vec3 out_dir = refract(in_water, -Nw, N_WATER);
        vec3 col;
        if (dot(out_dir, out_dir) < 0.5) {
            col = u_cabin;  // total internal reflection: the ray turns back into the dark cabin
        } else {
            float cosx = abs(dot(out_dir, Nw));
            float transmit = 1.0 - (0.02 + 0.98 * pow(1.0 - cosx, 5.0));
            col = behind_glass(out_dir, u_drop_lod + 2.0 * c_film * (1.0 - c_drop)) * transmit;
            if (k == 0) glint_dir = vec4(out_dir, transmit);  // glints from the centre tap only: 32 lights
        }
        drop_cover += c_drop;
        wet_col += col * c;
        cover += c;
    }
    wet_col /= max(cover, 1e-6);
    cover *= 0.2;
    vec3 glint = glint_dir.w > 0.0 ? glints(glint_dir.xyz) * u_exposure * glint_dir.w * 0.2 * drop_cover : vec3(0.0);
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
