// Surface shading: sun, sky ambient, street lamps and headlights (point / spot lights in candela).
#include "common/brdf.glsl"
#include "common/sky.glsl"
#include "common/bits.glsl"

// The lights (u_light_pos/dir/color[MAX_LIGHTS], u_light_count) are frame-block members (frame.glsl).
#include "common/frame.glsl"
// Direct light (sun, lamps) reaching this draw: 1 outdoors; < 1 inside the cabin, whose roof and pillars shade
// it from the lamps (which cast no shadow maps; the sun's shadow map adds the roof's shadow on top).
uniform float u_direct_scale = 1.0;

// Sun shadow map (renderer.py): depth seen from the sun around the camera, compared in hardware.
uniform sampler2DShadow u_shadow_map;
// u_shadow_matrix (wrapped world → shadow map [0, 1]³) and u_shadow_params (on 1/0, texel size 1/px, depth
// bias) are frame-block members; the sampler cannot be.

// Share of the sun's disc visible from p (3×3 PCF); 1 outside the map or with shadows off.
float sun_visibility(vec3 p, vec3 N) {
    vec3 q = (u_shadow_matrix * vec4(p + N * 0.05, 1.0)).xyz;  // normal offset against acne
    bool unshadowed = u_shadow_params.x < 0.5 || any(lessThan(q, vec3(0.0))) || any(greaterThan(q, vec3(1.0)));
    // Without a shadow there the loop takes no tap: a loop no fragment enters costs llvmpipe one masked pass of
    // its body, where an early return would still run all nine taps masked (it branches on neither).
    float lit = 0.0;
    for (int i = -1; i <= (unshadowed ? -2 : 1); ++i)
        for (int j = -1; j <= 1; ++j)
            lit += texture(u_shadow_map, vec3(q.xy + vec2(i, j) * u_shadow_params.y, q.z - u_shadow_params.z));
    return unshadowed ? 1.0 : lit / 9.0;
}

struct Surface {
    vec3 position;   // m, world (wrapped frame)
    vec3 normal;
    vec3 albedo;     // linear
    float roughness;
    float metallic;
    float f0;        // dielectric reflectance at normal incidence (0.04 default, 0.02 water)
    float ambient_occlusion;
};

float spot_factor(int i, vec3 L) {
    float cos_outer = u_light_dir[i].w;
    if (cos_outer <= -1.0) return 1.0;
    float cd = dot(-L, u_light_dir[i].xyz);
    float f = smoothstep(cos_outer, u_light_color[i].w, cd);
    if (u_light_pos[i].w < 0.0) {
        // Low beam: intensity falls steeply below ~1.5° under the horizon (ECE R112-like pattern), so the road
        // right in front of the car is not lit as hard as the hotspot 20–40 m ahead.
        float below_deg = degrees(asin(clamp(L.y, -1.0, 1.0)));  // L points to the light: +y = light above
        f *= exp(-max(below_deg - 1.5, 0.0) / 3.0);
    }
    return f;
}

// The lights a loop visits (bit i: light i): all of them, unless a fragment shader took its tile's from the light
// grid (common/light_grid.glsl). Loops take them lowest first, as a loop over i would, so the sums are the same.
uint g_light_mask = 0xFFFFFFFFu;
uint light_mask() {
    return u_light_count >= 32 ? g_light_mask : g_light_mask & ((1u << uint(u_light_count)) - 1u);
}

// Light i at p: false beyond its range; else L, the unit direction from p to it, and E, the illuminance (lux,
// RGB) it gives there, on a surface facing it — spot cone and low-beam pattern included, smoothly windowed to 0
// at the range. Every lit thing (surfaces, road water, drops, spray, glass glints) reads the lights through this.
bool light_at(int i, vec3 p, out vec3 L, out vec3 E) {
    vec3 d = u_light_pos[i].xyz - p;
    float dist2 = dot(d, d);
    float range = abs(u_light_pos[i].w);  // negative: a low-beam headlight (spot_factor shapes it)
    if (dist2 > range * range) return false;
    L = d * inversesqrt(max(dist2, 1e-8));
    float window = clamp(1.0 - pow(dist2 / (range * range), 2.0), 0.0, 1.0);
    E = u_light_color[i].rgb * spot_factor(i, L) * window * window / max(dist2, 0.01);
    return true;
}

// Luminance (cd/m²) leaving the surface towards V from the lights (no emission).
vec3 shade_surface(Surface s, vec3 V) {
    vec3 N = s.normal;
    vec3 f0 = mix(vec3(s.f0), s.albedo, s.metallic);
    vec3 diffuse_color = s.albedo * (1.0 - s.metallic);
    vec3 color = brdf_direct(N, V, u_sun_dir, diffuse_color, f0, s.roughness) * u_sun_illum
                 * sun_visibility(s.position, N);
    for (uint m = light_mask(); m != 0u;) {
        int i = pop_bit(m);
        vec3 L, E;
        if (light_at(i, s.position, L, E)) color += brdf_direct(N, V, L, diffuse_color, f0, s.roughness) * E;
    }
    color *= u_direct_scale;
    float NoV = max(dot(N, V), 1e-4);
    vec3 spec_env = env_brdf_approx(f0, s.roughness, NoV);
    vec3 R = reflect(-V, N);
    R.y = abs(R.y) * (1.0 - s.roughness) + R.y * s.roughness;  // rough lobes see more of the sky average
    vec3 env = mix(sky_radiance(normalize(R), false), sky_ambient(N), s.roughness);
    color += (diffuse_color * sky_ambient(N) * (1.0 - spec_env) + env * spec_env) * s.ambient_occlusion;
    return color;
}
