// The wet road (DESIGN §3 "Wet road"; rain_core/effects/road/ explains the model, surface.py is the NumPy twin).
// The scene shader calls road_wet_surface before lighting (wet BRDF, water under which the base lies),
// road_water_layer after it (the water surface: Fresnel blend of the reflection, highlights of the lights)
// and road_emission for emissive surfaces. With u_road_wet = 0 (effect off, road dry) all three return at
// their first line: the dry path costs one uniform branch.
// Needs: Surface, sky_radiance/sky_ambient, env_brdf_approx, D_GGX, V_SmithGGXCorrelated, the light arrays
// (common/lighting.glsl), u_view_proj/u_exposure/u_time (common/frame.glsl) and the MAT_* ids.
#include "road/film.glsl"

uniform float u_road_wet;             // 1 while the road effect is active, else 0 (the dry path)
uniform float u_road_mirror;          // 1 while the reflection pass draws (lamp lenses dimmed, no reflection)
uniform float u_road_debug;           // 1: flat colours for the dry / wet / drenched / puddle regions
uniform float u_road_reflect;         // 1: this frame's planar reflection is bound on u_road_reflection
uniform sampler2D u_road_reflection;  // units.ROAD_REFLECTION: the mirrored scene, pre-exposed HDR, mipmapped
uniform vec2 u_road_proj_scale;       // (0.5·P00, 0.5·P11): texture uv per radian near the view axis
uniform sampler2D u_road_ripples;     // units.ROAD_RIPPLES: slopes RG = (dh/dx, dh/dz), height B (m), world-anchored
uniform vec4 u_road_ripple_window;    // origin x, z (m, wrapped; centre of texel 0), extent (m), 1 if bound
uniform sampler2D u_road_rain_rings;   // units.ROAD_RAIN_RINGS: tiled raindrop-ring slopes RG (rc.shared.rain_rings)
uniform vec2 u_road_rain_rings_tile;   // tile size (m), 1 while it rains
uniform vec3 u_road_waves;            // drift velocity of the wind waves x, z (m/s); their slope amplitude
uniform mat4 u_road_cabin;            // wrapped world → ego car local frame (the cabin stays dry)
uniform vec4 u_road_cabin_box;        // local z of the cowl, floor y, half width (m); w = 1 when inside

const float WET_ALBEDO_FACTOR = 0.3;
const float WET_SMOOTHNESS_GAIN = 2.5;
const float WATER_F0 = 0.02;
const float UNDERWATER_F0 = 0.004;
const float FILM_ROUGHNESS = 0.32;
const float WATER_ROUGHNESS = 0.04;
const float LIGHT_MIN_ROUGHNESS = 0.1;
const float LIGHT_SOURCE_RADIANCE = 2.0;
const float MIRROR_LENS_FACTOR = 0.05;
const float WET_MIN = 0.02;
const float SIDEWALK_OUTER_X_M = 10.3;  // roofs shelter the road, kerbs and sidewalks (the map's edge columns)
const vec3 MURK_TINT = vec3(0.62, 0.57, 0.50);
// Per material id (MAT_GENERIC … MAT_RUBBER), as MATERIAL_POROSITY / MATERIAL_FILM in effects/road/surface.py.
const float ROAD_POROSITY[10] = float[10](0.6, 1.0, 0.2, 0.7, 0.0, 0.0, 0.4, 0.0, 0.0, 0.3);
const float ROAD_FILM[10] = float[10](0.5, 1.0, 1.0, 0.8, 0.6, 0.0, 0.3, 0.0, 0.6, 0.5);
const vec3 ROAD_REGION_COLORS[4] = vec3[4](vec3(0.55, 0.45, 0.25), vec3(0.15, 0.55, 0.15),
                                            vec3(0.95, 0.45, 0.05), vec3(0.10, 0.30, 1.00));

// What road_wet_surface found, for road_water_layer.
float g_road_wetness = 0.0;   // wetness of this surface (weather × exposure)
float g_road_cover = 0.0;     // share of the surface under the water layer
float g_road_standing = 0.0;  // coverage by standing water (1: a full water surface)
bool g_road_plane = false;    // on the road plane: the planar reflection is valid here

// --- wind waves: two scrolling layers of value noise (analytic gradient), periodic along z like the world ---
float road_hash(vec2 i, float period_cells) {
    i.y = mod(i.y, period_cells);
    vec3 p3 = fract(vec3(i.xyx) * 0.1031);
    p3 += dot(p3, p3.yzx + 33.33);
    return fract((p3.x + p3.y) * p3.z);
}

vec2 road_noise_gradient(vec2 p, float period_cells) {
    vec2 i = floor(p);
    vec2 f = p - i;
    vec2 u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    vec2 du = 30.0 * f * f * (f * (f - 2.0) + 1.0);
    float a = road_hash(i, period_cells);
    float b = road_hash(i + vec2(1.0, 0.0), period_cells);
    float c = road_hash(i + vec2(0.0, 1.0), period_cells);
    float d = road_hash(i + vec2(1.0, 1.0), period_cells);
    return du * (vec2(b - a, c - a) + (a - b - c + d) * u.yx);
}

// Slope (dh/dx, dh/dz) of the wind ripples on standing water.
vec2 road_wave_slope(vec2 xz) {
    if (u_road_waves.z <= 0.0) return vec2(0.0);
    vec2 drift = u_road_waves.xy * u_time;
    vec2 drift2 = mat2(0.82, 0.57, -0.57, 0.82) * drift * 1.7;  // the second layer crosses the first
    vec2 g1 = road_noise_gradient((xz - drift) / 0.4, ROAD_PERIOD_M / 0.4);
    vec2 g2 = road_noise_gradient((xz - drift2) / 0.15, ROAD_PERIOD_M / 0.15);
    return u_road_waves.z * (0.65 * g1 + 0.35 * g2);
}

// Slope (RG) and height (B, m) from the ripple simulation (ripples.py), faded out at the window's edge.
vec3 road_ripple_sample(vec2 xz) {
    if (u_road_ripple_window.w < 0.5) return vec3(0.0);
    vec2 t = (xz - u_road_ripple_window.xy) / u_road_ripple_window.z;
    float edge = min(min(t.x, t.y), min(1.0 - t.x, 1.0 - t.y));
    if (edge <= 0.0) return vec3(0.0);
    vec2 n = vec2(textureSize(u_road_ripples, 0));
    vec2 uv = (t * (n - 1.0) + 0.5) / n;
    return texture(u_road_ripples, uv).rgb * smoothstep(0.0, 0.05, edge);
}

vec2 road_ripple_slope(vec2 xz) {
    return road_ripple_sample(xz).xy;
}

// Raindrop rings on all standing water: the tiled map (the simulated window's own drops are too small to see).
vec2 road_rain_ring_slope(vec2 xz) {
    if (u_road_rain_rings_tile.y < 0.5) return vec2(0.0);
    return texture(u_road_rain_rings, xz / u_road_rain_rings_tile.x).rg;
}

// --- before lighting ---------------------------------------------------------------------------------------
// Wet BRDF on every surface the rain reaches; on the road also the water in cracks and puddles.
void road_wet_surface(inout Surface s, int material) {
    g_road_wetness = 0.0;
    g_road_cover = 0.0;
    g_road_standing = 0.0;
    g_road_plane = false;
    if (u_road_wet <= 0.0) return;
    int m = clamp(material, 0, 9);
    // Rain falls: tops get wet, walls less, undersides not; nothing under a roof or inside the car.
    float exposure = clamp(0.4 + 0.6 * s.normal.y, 0.0, 1.0);
    if (s.position.y < 1.0 && abs(s.position.x) < SIDEWALK_OUTER_X_M) {
        exposure *= 1.0 - road_maps(s.position.xz).g;
    }
    if (u_road_cabin_box.w > 0.5) {
        vec3 local = (u_road_cabin * vec4(s.position, 1.0)).xyz;
        if (m != MAT_CAR_PAINT && local.z > u_road_cabin_box.x && local.y > u_road_cabin_box.y
            && abs(local.x) < u_road_cabin_box.z) {  // the painted hood and mirrors are outside
            exposure = 0.0;
        }
    }
    float w = u_road_levels.x * exposure;
    g_road_wetness = w;
    float standing = 0.0;
    float a = 0.0;
    if ((m == MAT_ASPHALT || m == MAT_PAINT) && abs(s.position.x) <= ROAD_HALF_WIDTH_M && s.position.y < 0.05
        && s.normal.y > 0.9) {
        g_road_plane = true;
        standing = road_water_depths_mm(s.position.xz).x;
        // The ripples move the surface: where a tyre's trough is deeper than the water, the asphalt is bared.
        float surface = standing > 0.0 ? standing + 1000.0 * road_ripple_sample(s.position.xz).z : 0.0;
        a = clamp(surface / MACROTEXTURE_MM, 0.0, 1.0);
        g_road_standing = a;
    }
    float soaked = max(w, a);  // under standing water the asphalt is soaked whatever the film does
    s.albedo *= mix(1.0, WET_ALBEDO_FACTOR, soaked * ROAD_POROSITY[m]);
    // Light crosses the murky water twice: darker and browner with depth, never a saturated colour.
    s.albedo *= pow(MURK_TINT, vec3(standing / PUDDLE_MAX_MM));
    float smoothness = min(1.0, (1.0 - s.roughness) * mix(1.0, WET_SMOOTHNESS_GAIN, soaked));
    s.roughness = max(1.0 - smoothness, 0.02);
    float cover = max(w * ROAD_FILM[m], a);
    s.f0 = mix(s.f0, UNDERWATER_F0, cover);
    g_road_cover = cover;
}

// --- after lighting ----------------------------------------------------------------------------------------
float road_water_spec(vec3 N, vec3 V, vec3 L, float alpha) {
    float NoL = dot(N, L);
    if (NoL <= 0.0) return 0.0;
    vec3 H = normalize(V + L);
    float NoV = max(dot(N, V), 1e-4);
    float VoH = max(dot(V, H), 0.0);
    // VoH rounds above 1 when L ≈ V (a headlight right beside the eye, at night): pow of a negative is NaN.
    float F = WATER_F0 + (1.0 - WATER_F0) * pow(clamp(1.0 - VoH, 0.0, 1.0), 5.0);
    return D_GGX(max(dot(N, H), 0.0), alpha) * V_SmithGGXCorrelated(NoV, NoL, alpha) * F * NoL;
}

// Highlights of the sun, lamps and headlights on the water layer (cd/m²). At grazing angles the GGX lobe of
// the rough film is long along the view: the streaks of lights on a wet street. A thin layer (walls, damp
// surfaces: coverage below 1/4) takes the sun only: its lamp highlights would be faint, the loop is not.
vec3 road_light_highlights(vec3 P, vec3 N, vec3 V, float roughness, float cover) {
    float alpha = max(roughness * roughness, 0.002);
    vec3 color = road_water_spec(N, V, u_sun_dir, alpha) * u_sun_illum;
    for (uint m = cover < 0.25 ? 0u : light_mask(); m != 0u;) {
        int i = pop_bit(m);
        vec3 L, E;
        if (light_at(i, P, L, E)) color += road_water_spec(N, V, L, alpha) * E;
    }
    return color;
}

vec3 road_sky_reflection(vec3 R, vec3 N, float roughness) {
    R.y = abs(R.y) * (1.0 - roughness) + R.y * roughness;
    return mix(sky_radiance(normalize(R), false), sky_ambient(N), roughness);
}

// Radiance (cd/m²) the water layer reflects along R: the planar reflection where it is valid, else the sky.
// The texture holds the mirrored scene as this camera sees it, so the mirrored ray (R.x, −R.y, R.z) projects
// to where it shows R's radiance. A rough layer blurs it over its lobe: vertically ±α (in angle), across only
// ±α·cosθ — vertical streaks at grazing angles, as on wet streets.
vec3 road_reflected_radiance(vec3 N, vec3 R, float roughness, float NoV) {
    vec3 sky = road_sky_reflection(R, N, roughness);
    if (!g_road_plane || u_road_reflect < 0.5) return sky;
    vec4 clip = u_view_proj * vec4(R.x, -R.y, R.z, 0.0);
    if (clip.w <= 1e-4) return sky;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    float alpha = roughness * roughness;
    vec2 size = vec2(textureSize(u_road_reflection, 0));
    float half_v = alpha * u_road_proj_scale.y;
    float half_u = alpha * NoV * u_road_proj_scale.x;
    int taps = half_v * size.y > 1.5 ? 8 : 1;
    float spacing_px = 2.0 * half_v * size.y / 7.0;
    float lod = log2(max(max(half_u * size.x, spacing_px), 1.0));
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int i = 0; i < taps; ++i) {
        float t = taps == 1 ? 0.0 : float(i) / float(taps - 1) * 2.0 - 1.0;
        float wt = exp(-2.0 * t * t);
        sum += textureLod(u_road_reflection, uv + vec2(0.0, t * half_v), lod).rgb * wt;
        wsum += wt;
    }
    vec3 mirrored = sum / (wsum * u_exposure);
    // Flat water maps a pixel to itself; waves push the ray off the texture: fade to the sky past its edge
    // (the edge texels stand in for the first 2 %).
    vec2 outside = max(-uv, uv - 1.0);
    float inside = 1.0 - clamp((max(outside.x, outside.y) - 0.02) / 0.04, 0.0, 1.0);
    return mix(sky, mirrored, inside);
}

// The water layer over the shaded base: L = (1 − c·F)·L_base + c·(F·L_reflected + highlights).
vec3 road_water_layer(Surface s, vec3 V, vec3 radiance) {
    if (u_road_wet <= 0.0) return radiance;
    if (u_road_debug > 0.5) {
        int region = g_road_standing >= 1.0 ? 3 : (g_road_standing > 0.0 ? 2 : (g_road_wetness >= WET_MIN ? 1 : 0));
        return ROAD_REGION_COLORS[region] * 0.5 / u_exposure;
    }
    float c = g_road_cover;
    if (c <= 0.0) return radiance;
    float a = g_road_standing;
    vec3 N = s.normal;
    if (a > 0.0) {
        // In a kerb stream the water's pattern and the raindrop rings drift downstream (−z) with the flow.
        vec2 xz = s.position.xz;
        float stream = road_gutter_depth_mm(xz) > 0.0 ? 1.0 : 0.0;
        vec2 carried = xz + vec2(0.0, road_gutter_speed_m_s(xz) * u_time) * stream;
        vec2 flow = stream * 0.25 * road_noise_gradient(carried / vec2(0.6, 0.25), ROAD_PERIOD_M / 0.25);
        vec2 slope = (road_wave_slope(xz) + road_ripple_slope(xz) + road_rain_ring_slope(carried) + flow) * a;
        N = normalize(vec3(N.x - slope.x, N.y, N.z - slope.y));  // UDN blend onto the surface normal
    }
    float roughness = mix(FILM_ROUGHNESS, WATER_ROUGHNESS, a);
    float NoV = max(dot(N, V), 1e-4);
    float F = env_brdf_approx(vec3(WATER_F0), roughness, NoV).x;
    vec3 R = reflect(-V, N);
    vec3 reflected = road_reflected_radiance(N, R, roughness, NoV);
    vec3 highlights = road_light_highlights(s.position, N, V, max(roughness, LIGHT_MIN_ROUGHNESS), c);
    return radiance * (1.0 - c * F) + c * (F * reflected + highlights);
}

// Emissive surfaces: in the reflection pass the lamp and headlight lenses are dimmed, because their light
// reaches the water as the highlights above (a lens drawn too would count it twice).
vec3 road_emission(vec3 emissive_albedo, vec3 radiance) {
    if (u_road_mirror < 0.5) return radiance;
    float luminance = dot(emissive_albedo, vec3(0.2126, 0.7152, 0.0722));
    return luminance > LIGHT_SOURCE_RADIANCE ? radiance * MIRROR_LENS_FACTOR : radiance;
}
