#version 330 core
// Impact splashes (rain_core/effects/rainfall/): one instance per splash slot, a billboard standing on the impact
// point and turned to the camera about the vertical; the fragment shader draws the crown and its droplets.
#include "rainfall/drop.glsl"

#include "rainfall/drops.glsl"

// Splash slot j has one impact per period, at a phase from its index; the impact's place (world-anchored in the
// splash layer's box), its drop and whether it is drawn come from hash(j, period count). Twin: RainfallSim.splashes.
uniform uint u_splash_key;
uniform float u_splash_period; // s
uniform float u_splash_accept; // share of the impacts drawn (the rate)
uniform float u_splash_weight; // real impacts per drawn splash
uniform float u_splash_lam;    // 1/mm, Marshall–Palmer slope
uniform vec3 u_splash_ext;     // m
uniform float u_splash_v[16];  // m/s, fall speed at D = 1.5 … 6 mm
uniform float u_wetness;
uniform float u_puddles;
uniform sampler2D u_road_height;  // world.road_heightmap (LINEAR, x clamped, z repeating)
uniform vec2 u_road_extent;       // m
uniform vec3 u_road_geom;         // road half width, outer edge of the sidewalk, kerb height (m)
uniform float u_crown_per_d;      // crown height / D
out vec2 v_m;             // m in the billboard: (across, height above the ground)
flat out vec4 v_shape;    // (age s, lifetime s, crown height m, D m)
flat out vec4 v_kind;     // (type, seed, m per px, unused)
flat out vec4 v_color;    // pre-exposed radiance, light multiplier

const uint SALT_D[4] = uint[4](0x1F83D9ABu, 0x5BE0CD19u, 0xCBBB9D5Du, 0x629A292Au);
const uint SALT_V[4] = uint[4](0x9159015Au, 0x152FECD8u, 0x67332667u, 0x8EB44A87u);
const uint SALT_KIND = 0xDB0C2E0Du;

float splash_v(float d_mm) {
    float x = clamp((d_mm - 1.5) / 0.3, 0.0, 15.0);
    int i = min(int(floor(x)), 14);
    return mix(u_splash_v[i], u_splash_v[i + 1], x - float(i));
}

void hide() {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    v_m = vec2(0.0);
    v_shape = vec4(0.0);
    v_kind = vec4(0.0);
    v_color = vec4(0.0);
}

void main() {
    uint key = rain_hash(uint(gl_InstanceID) ^ u_splash_key);
    float x = u_splash_tau + rain_u01(rain_hash(key ^ SALT_PHASE));
    float fl = floor(x);
    float age = (x - fl) * u_splash_period;
    uint hc = rain_hash(key ^ rain_hash(u_splash_count + uint(fl)));
    if (rain_u01(rain_hash(hc ^ SALT_KEEP)) >= u_splash_accept) { hide(); return; }
    // The splashing drop, ∝ N(D)·v(D): truncated-exponential draws kept with probability v/v_max.
    float span = 1.0 - exp(-u_splash_lam * 4.5);  // D from 1.5 to 6 mm
    float d_mm = 1.5;
    for (int k = 0; k < 4; ++k) {
        float u = rain_u01(rain_hash(hc ^ SALT_D[k]));
        d_mm = 1.5 - log(1.0 - u * span) / u_splash_lam;
        if (rain_u01(rain_hash(hc ^ SALT_V[k])) * u_splash_v[15] < splash_v(d_mm)) break;
    }
    float life = 0.1 + 0.2 * clamp((d_mm - 1.5) / 3.0, 0.0, 1.0);
    if (age >= life) { hide(); return; }
    float px = u_splash_lo.x + mod(rain_u01(rain_hash(hc ^ SALT_X)) * u_splash_ext.x + u_splash_off.x, u_splash_ext.x);
    float pz = u_splash_lo.z + mod(rain_u01(rain_hash(hc ^ SALT_Z)) * u_splash_ext.z + u_splash_off.z, u_splash_ext.z);
    float ax = abs(px);
    bool kerb = ax >= u_road_geom.x && ax <= u_road_geom.y;
    vec3 p = vec3(px, kerb ? u_road_geom.z : u_ground_y, pz);
    if (rain_occluder_height(p.xz) >= p.y || rain_in_vehicle(p + vec3(0.0, 0.01, 0.0))) { hide(); return; }
    float type = 2.0;  // prompt
    if (u_wetness >= 0.3) type = 1.0;  // film crown
    if (ax < u_road_geom.x) {
        vec2 uv = vec2((px + 0.5 * u_road_extent.x) / u_road_extent.x, pz / u_road_extent.y);
        if (textureLod(u_road_height, uv, 0.0).r < u_puddles) type = 0.0;  // puddle crown
    }
    float seed = rain_u01(rain_hash(hc ^ SALT_KIND));
    float d_m = d_mm * 1e-3;
    float crown = u_crown_per_d * d_m * (type < 0.5 ? 1.0 : (type < 1.5 ? 0.6 : 0.5));
    vec3 to_eye = u_camera_pos - p;
    float dist = length(to_eye);
    vec3 right = cross(vec3(0.0, 1.0, 0.0), to_eye);
    right = dot(right, right) > 1e-8 ? normalize(right) : vec3(1.0, 0.0, 0.0);
    vec4 centre_clip = u_view_proj * vec4(p, 1.0);
    float m_per_px = max(centre_clip.w, 0.05) / u_focal_px;
    float pad = 1.5 * m_per_px;
    float half_w = max(1.8 * crown, 4.0 * d_m) + pad;
    float lo = -0.3 * crown - pad;
    float hi = 1.8 * crown + pad;
    int c = gl_VertexID;
    vec2 m = vec2((c & 1) == 0 ? -half_w : half_w, c < 2 ? lo : hi);
    gl_Position = u_view_proj * vec4(p + right * m.x + vec3(0.0, m.y, 0.0), 1.0);
    v_m = m;
    v_shape = vec4(age, life, crown, d_m);
    v_kind = vec4(type, seed, m_per_px, 0.0);
    vec3 radiance = apply_atmosphere_dir(rain_drop_radiance(p + vec3(0.0, crown, 0.0), to_eye / max(dist, 1e-4)), dist,
                                          -to_eye / max(dist, 1e-4));
    v_color = vec4(radiance * u_exposure, u_splash_weight * u_brightness);
}
