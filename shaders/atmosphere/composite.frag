#version 330 core
// Glow, step 3, and the light scattered by the rain from the nearest lamps and headlights.
// Blending is (ONE, ONE_MINUS_SRC_ALPHA) onto the HDR colour: hdr·(1 − k·w) + k·blur(c·w) + in-scatter, so a
// uniform region keeps its radiance (the halo only moves light) while bright lights spread into the mist
// (k is capped per pixel at 1/w so that never more than the pixel's own light is moved).
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/atmosphere.glsl"
#include "common/depth.glsl"
uniform sampler2D u_glow;          // blurred c·w at the glow resolution
uniform int u_glow_factor;         // full-resolution pixels per glow texel
uniform float u_glow_strength;     // k: share of the scattered light that forms the visible halo
uniform int u_scatter_count;       // lights (nearest first) traced per pixel
uniform int u_scatter_samples;     // quadrature nodes per light
uniform float u_scatter_per_m;     // σ_s (1/m): scattering coefficient of the rain + haze, × the user's scale
uniform float u_scatter_max_m;     // where rays into the sky stop (m)
uniform float u_scatter_skip;      // exposed radiance a pixel's skipped lights may add up to, together …
uniform float u_scatter_skip_relative;  // … plus this share of the light the pixel keeps (u_glow's alpha; 0: none)
out vec4 f_color;

// The part [ta, tb] of the ray eye + t·dir inside light i's cone (cos_outer > 0: a convex, single-nappe cone);
// false if the ray misses it. Wider cones and point lights leave [ta, tb] as it is.
bool cone_interval(int i, vec3 eye, vec3 dir, inout float ta, inout float tb) {
    float c = u_light_dir[i].w;
    if (c <= 0.0) return true;
    vec3 a = u_light_dir[i].xyz;
    vec3 o = eye - u_light_pos[i].xyz;
    float da = dot(dir, a), oa = dot(o, a), c2 = c * c;
    // Inside the forward nappe ⇔ f(t) = (oa + t·da) − c·|o + t·dir| ≥ 0; f is concave, so that is one interval,
    // bounded by the roots of (oa + t·da)² = c²·|o + t·dir|² that lie on the forward nappe.
    float qa = da * da - c2, qb = 2.0 * (da * oa - c2 * dot(o, dir)), qc = oa * oa - c2 * dot(o, o);
    float r1, r2;
    if (abs(qa) < 1e-6) {
        if (abs(qb) < 1e-9) return false;
        r1 = r2 = -qc / qb;
    } else {
        float disc = qb * qb - 4.0 * qa * qc;
        if (disc < 0.0) return false;
        float q = -0.5 * (qb + sign(qb) * sqrt(disc));  // numerically stable pair of roots
        r1 = q / qa;
        r2 = abs(q) > 1e-12 ? qc / q : r1;
        if (r1 > r2) { float tmp = r1; r1 = r2; r2 = tmp; }
    }
    bool v1 = oa + r1 * da >= 0.0, v2 = oa + r2 * da >= 0.0;
    float t_in, t_out;
    if (v1 && v2 && r2 > r1) {
        t_in = r1;
        t_out = r2;
    } else if (v1 || v2) {
        float r = v1 ? r1 : r2;
        bool after = (oa + (r + 1.0) * da) - c * length(o + (r + 1.0) * dir) > 0.0;
        t_in = after ? r : -1e30;
        t_out = after ? 1e30 : r;
    } else {
        return false;
    }
    ta = max(ta, t_in);
    tb = min(tb, t_out);
    return tb > ta;
}

// Single scattering along the eye ray [0, t_max] from light i (cd/m², not yet exposed):
//   ∫ σ_s·p(μ)·I·spot·window·exp(−β(t + r)) / r² dt,  r = distance from the ray point to the light.
// The ray is first clipped to the light's range and cone. Then the equiangular substitution t = t0 + h·tan θ
// (Kulla & Fajardo 2012) turns dt/r² into dθ/h, integrating the 1/r² peak exactly (for β = 0 and a point light
// this is the classic closed form (atan(b) − atan(a))/h); the smooth rest (phase, spot falloff, attenuation) is
// taken at the midpoints in θ.
vec3 light_inscatter(int i, vec3 eye, vec3 dir, float t_max, inout float budget) {
    vec3 lp = u_light_pos[i].xyz;
    float range = abs(u_light_pos[i].w);  // negative marks a low-beam headlight (spot_factor)
    vec3 rel = lp - eye;
    float t0 = dot(rel, dir);
    float h_ray = length(rel - t0 * dir);  // the ray's true distance from the lamp
    float h = max(h_ray, 0.15);  // a lamp head is ~0.3 m across: no singular core
    if (h >= range) return vec3(0.0);
    float half_chord = sqrt(range * range - h * h);
    float ta = max(0.0, t0 - half_chord);
    float tb = min(t_max, t0 + half_chord);
    if (tb <= ta || !cone_interval(i, eye, dir, ta, tb)) return vec3(0.0);
    // An upper bound of the quadrature below, from its factors' bounds on [ta, tb]: spot and window ≤ 1, the
    // attenuation ≤ exp(−β(ta + h_ray)) (t ≥ ta, r ≥ h_ray), the phase at most its largest at the ends (each
    // lobe is monotonic in μ = −sin θ, and sin(atan x) = x / √(1 + x²); any μ where h was raised to 0.15 m).
    // A light whose bound fits in what is left of the pixel's budget is skipped and its bound spent.
    float xa = (ta - t0) / h, xb = (tb - t0) / h;
    float tha = atan(xa);
    float thb = atan(xb);
    bool true_h = h_ray >= 0.15;
    float mu_lo = true_h ? -xb * inversesqrt(1.0 + xb * xb) : -1.0;
    float mu_hi = true_h ? -xa * inversesqrt(1.0 + xa * xa) : 1.0;
    float phase_hi = mix(max(atmosphere_phase(mu_lo, u_phase_g), atmosphere_phase(mu_hi, u_phase_g)),
                         max(atmosphere_phase(mu_lo, u_phase_back_g), atmosphere_phase(mu_hi, u_phase_back_g)),
                         u_phase_back_weight);
    vec3 color = u_light_color[i].rgb;
    float bound = 1.01 * max(color.r, max(color.g, color.b)) * u_scatter_per_m * u_exposure * phase_hi
                  * exp(-u_extinction_per_m * (ta + h_ray)) * (thb - tha) / h;
    if (bound <= budget) {
        budget -= bound;
        return vec3(0.0);
    }
    float dth = (thb - tha) / float(u_scatter_samples);
    float sum = 0.0;
    for (int k = 0; k < u_scatter_samples; ++k) {
        float th = tha + (float(k) + 0.5) * dth;
        float t = t0 + h * tan(th);
        vec3 d = lp - (eye + t * dir);
        float r2 = dot(d, d);
        float r = sqrt(r2);
        vec3 L = d / r;
        float window = clamp(1.0 - pow(r2 / (range * range), 2.0), 0.0, 1.0);
        sum += atmosphere_phase_medium(dot(L, dir)) * spot_factor(i, L) * window * window
               * exp(-u_extinction_per_m * (t + r));
    }
    return color * (u_scatter_per_m * sum * dth / h);
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec2 size = vec2(textureSize(u_depth, 0));
    vec3 dir;
    bool sky;
    float dist = atmosphere_pixel_ray(pixel, size, u_camera_pos, u_scatter_max_m, dir, sky);
    float w = 1.0 - exp(-u_medium_extinction_per_m * (sky ? atmosphere_sky_path_m(dir) : dist));
    vec2 uv = gl_FragCoord.xy / (float(u_glow_factor) * vec2(textureSize(u_glow, 0)));
    // k·w is the share of this pixel's light moved into the halo; it cannot be more than all of it. Past
    // k·w = 1 (glow > 2 in dense rain) hdr·(1 − k·w) would go negative: k_eff = min(k, 1/w) keeps the halo
    // conservative (a uniform region still keeps its radiance) and the result ≥ 0 (glow.py's twin does the same).
    float k = min(u_glow_strength, 1.0 / max(w, 1e-6));
    vec3 glow = k > 0.0 ? k * texture(u_glow, uv).rgb : vec3(0.0);
    vec3 scatter = vec3(0.0);
    // What the skipped lights may add: a fixed amount, below an 8-bit step on the darkest pixel, and a share of
    // the pixel's own light (the least its glow block keeps), below one on any pixel of the tone map's curve.
    float budget = u_scatter_skip;
    if (u_scatter_skip_relative > 0.0)
        budget += u_scatter_skip_relative * texelFetch(u_glow, pixel / u_glow_factor, 0).a;
    for (int i = 0; i < min(u_scatter_count, u_light_count); ++i) {
        scatter += light_inscatter(i, u_camera_pos, dir, dist, budget);
    }
    f_color = vec4(glow + scatter * u_exposure, k * w);
}
