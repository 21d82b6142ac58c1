#version 330 core
// A drop on the glass as a small lens (analytic: a spherical cap of the contact angle, its tail a tapering
// capsule; the wiper's bead a cylinder). Each pixel refracts its view ray through the cap's surface into the
// frame behind (a tiny inverted fish-eye, sharper than through the misted film: a finer mip), less the Fresnel
// reflection that shows the dark cabin, which grows towards the rim where the surface is steep (a dark rim); the
// sky and the lights the lens gathers make a small bright highlight. Seen through the eye's pupil when the eye
// is focused on the road (exact coverage, five taps for the colour); one tap, antialiased, when it is focused on
// the glass. Premultiplied.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/light_grid.glsl"
#include "common/atmosphere.glsl"
#include "windshield/glass_common.glsl"
#include "windshield/optics.glsl"
uniform float u_drop_lod;     // mip level of u_frame through a drop
uniform float u_cap_rn;       // sphere radius / contact radius of a drop's cap (1 / sin θ)
uniform float u_lens;         // × the cap's slope: the optical strength of the lens (1: the contact angle's)
uniform float u_rim;          // strength of the rim's darkening (0: Fresnel alone)
uniform float u_highlight;    // strength of the sky's highlight
uniform vec3 u_sky_light;     // the sky's radiance over the glass (the zenith's), pre-exposed
in vec2 v_local;
in vec3 v_pos;
flat in vec4 v_shape;  // true radius (m), tail length (m), blur radius (m), kind
flat in vec2 v_axis;
flat in vec3 v_nrm;
out vec4 f_color;

void main() {
    use_light_grid();
    float a = v_shape.x, len = v_shape.y, blur = v_shape.z;
    int kind = int(v_shape.w + 0.5);
    vec3 V = normalize(v_pos - u_camera_pos);
    vec3 N, Ts, Tt;
    glass_frame(V, v_nrm, N, Ts, Tt);
    vec3 in_water = water_ray(V, N);
    vec2 ay = vec2(-v_axis.y, v_axis.x);
    float foot = max(length(dFdx(v_local)), length(dFdy(v_local)));
    int taps = blur > 0.3 * a ? 5 : 1;
    float rn2 = u_cap_rn * u_cap_rn;
    // The outline: where the eye is focused on the road, the share of the pupil's blur disc (radius blur) that
    // sees the drop (a disc of radius rad at distance rho: their exact overlap), so a defocused drop is one soft
    // round blob; focused on the glass, the pixel's footprint antialiases it.
    float along0 = clamp(v_local.x, 0.0, len);
    float rad0 = a * (kind == 0 && len > 0.0 ? 1.0 - 0.45 * along0 / len : 1.0);
    float rho0 = length(vec2(v_local.x - along0, v_local.y));
    float cover = taps > 1 ? disc_overlap(rho0, rad0, blur)
                           : clamp(0.5 + (rad0 - rho0) / max(foot, 1e-6), 0.0, 1.0);
    if (cover <= 0.0) discard;
    // The colour: the lens as the pupil's taps see it, each tap's ray through the part of the drop it meets
    // (a tap beyond the outline looks through the rim).
    // Defocus spreads the highlight over the blur disc: wider and dimmer by the same factor (its light kept).
    float spread = taps > 1 ? 1.0 + 8.0 * (blur / a) * (blur / a) : 1.0;
    // ... and the tiny inverted image inside the drop: the five taps see it shifted, so each reads it blurred.
    float lod = u_drop_lod + (taps > 1 ? log2(1.0 + 4.0 * blur / a) : 0.0);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    vec4 glint_dir = vec4(0.0);  // tap 0's ray out of the water, and its transmittance
    vec3 sky_facing = normalize(N + 0.35 * Tt);  // the cap's normal tilted up the glass, towards the sky
    // A blur disc much wider than the drop sees all of it: the taps move from the pupil's disc onto the drop
    // itself, so the colour tends smoothly to the drop's mean instead of switching as taps cross its outline.
    float onto_drop = taps > 1 ? clamp(blur / a - 0.5, 0.0, 1.0) : 0.0;
    for (int k = 0; k < taps; ++k) {
        vec2 q = mix(v_local + DISC_TAPS[k] * blur, vec2(along0, 0.0) + DISC_TAPS[k] * 0.8 * rad0, onto_drop);
        float along = clamp(q.x, 0.0, len);
        float rad = a * (kind == 0 && len > 0.0 ? 1.0 - 0.45 * along / len : 1.0);
        vec2 rel = vec2(q.x - along, q.y);
        float rho = length(rel);
        float wk = 0.05 + 0.95 * clamp(0.5 + (rad - rho) / (0.3 * rad), 0.0, 1.0);
        float d = min(rho / rad, 0.98);
        vec2 dir = rho > 1e-9 ? rel / rho : vec2(0.0);
        // Slope of the surface (outward gradient of the height), dimensionless: a spherical cap of contact
        // angle θ (tan θ at the rim), or the bead's round cross-section (steep at its edges).
        float g = kind == 0 ? d / sqrt(rn2 - d * d) : d / sqrt(1.0 - d * d) * 0.8;
        vec2 grad = -g * u_lens * dir;
        vec2 slope = grad.x * v_axis + grad.y * ay;
        vec3 out_dir;
        float transmit;
        vec3 col = through_water(v_pos, in_water, N, Ts, Tt, slope, lod, out_dir, transmit);
        // Rim: past the Fresnel term, the light near the contact line is bent out of the lens's field (to
        // the car's body and the glass's own reflections): darker towards the outline.
        col *= 1.0 - u_rim * smoothstep(0.55, 1.0, d);
        // The bright sky over the glass in the part of the cap that faces it (its normal tilted up the glass
        // towards the sky): a small highlight. The sun and the lights glint of their own (optics.glsl).
        vec3 Nw = normalize(N - u_refraction * (slope.x * Ts + slope.y * Tt));
        float h = max(dot(Nw, sky_facing), 0.0);
        col += u_sky_light * (u_highlight / spread) * pow(h, 300.0 / spread);
        if (k == 0 && transmit > 0.0) glint_dir = vec4(out_dir, transmit);
        sum += col * wk;
        weight += wk;
    }
    // The lamps' glint along tap 0's ray, like the highlight spread over the blur disc when defocused (its light
    // kept).
    vec3 glint = exposed_glints(v_pos, glint_dir) * 0.2 / spread;
    f_color = vec4((sum / weight + glint) * cover, cover);
}
