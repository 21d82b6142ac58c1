// Drops without state (rain_core/effects/rainfall/drops.py and sim.py are the float64 twin: keep in step).
// Instance i: its diameter and phase from its index, its pass count ("cycle") from time; each cycle draws the
// spawn point, the keep decision and the turbulence step from hash(i, cycle). Positions wrap periodically into
// the camera-following box of the instance's layer, so the boxes hold a stationary sample whatever the camera
// does. The CPU sends only small numbers (time mod 2^14 s as whole seconds + fraction, offsets mod the boxes).
// RainFrame, what changes every frame (it defines LAYERS and RAIN_MAX_VEHICLES):
#include "rainfall/rain_frame.glsl"
#define RAIN_TIME_PERIOD 16384u        // s (constants.TIME_PERIOD_S)
#define RAIN_TABLE_SHIFT 20u           // 32 − constants.TABLE_BITS
#define RAIN_TURB_STEPS 3              // constants.TURBULENCE_STEPS
uniform uint u_seed_key;               // drops.seed_key(seed)
uniform int u_layer_start[LAYERS];    // first instance of each layer
uniform sampler2D u_drop_table;        // RGBA32F (TABLE_SIZE × LAYERS): D mm, passes per period, v m/s, v_true
uniform vec3 u_box_ext[LAYERS];        // m, box sizes: the drops' periods
uniform float u_turb_eps;              // drops.TURB_EPS
uniform vec3 u_thin;                   // (A, B, c): r(D) = A·exp(−B·D), drawn when keep < min(1, r/c)
// Occluders: the top-down roof height maps (m, −1e4 where open), z repeating with the world's period.
uniform sampler2D u_occ_fine;
uniform sampler2D u_occ_coarse;
uniform vec4 u_occ_fine_geom;          // x0 m, cell m, columns, rows
uniform vec4 u_occ_coarse_geom;
uniform float u_period_world;          // m, the world's period along z
uniform float u_ground_y;              // m
// Vehicles: pose (x, y, z wrapped frame, yaw); per piece a local box and two planes (n, d): inside ⇔ n·p ≤ d.
uniform int u_veh_count;
uniform vec4 u_veh_lo[2 * RAIN_MAX_VEHICLES];
uniform vec4 u_veh_hi[2 * RAIN_MAX_VEHICLES];
uniform vec4 u_veh_plane[4 * RAIN_MAX_VEHICLES];

const uint SALT_PHASE = 0x68E31DA4u;
const uint SALT_X = 0xB5297A4Du;
const uint SALT_Z = 0x1B56C4E9u;
const uint SALT_KEEP = 0x3C6EF372u;
const uint SALT_TURB_X = 0xA54FF53Au;
const uint SALT_TURB_Z = 0x510E527Fu;

uint rain_hash(uint x) {  // lowbias32 (drops.hash32)
    x ^= x >> 16u;
    x *= 0x7FEB352Du;
    x ^= x >> 15u;
    x *= 0x846CA68Bu;
    x ^= x >> 16u;
    return x;
}

float rain_u01(uint h) {
    return float(h >> 8u) * (1.0 / 16777216.0);
}

float rain_turb_step(uint hc, uint salt) {
    float n = float(2 * RAIN_TURB_STEPS + 1);
    return min(floor(rain_u01(rain_hash(hc ^ salt)) * n), n - 1.0) - float(RAIN_TURB_STEPS);
}

struct RainDrop {
    int layer;
    float d_mm;
    vec3 pos;      // m, wrapped frame
    vec3 vel;      // m/s
    float r;       // real drops per unit instance density (rates.real_per_instance)
    bool drawn;    // passed the thinning
};

int rain_layer(int id) {
    int k = 0;
    for (int j = 1; j < LAYERS; ++j) k += id >= u_layer_start[j] ? 1 : 0;
    return k;
}

RainDrop rain_drop(int id) {
    RainDrop d;
    d.layer = rain_layer(id);
    uint key = rain_hash(uint(id) ^ u_seed_key);
    float phase = rain_u01(rain_hash(key ^ SALT_PHASE));
    int bin = int((uint(id) * 2654435769u) >> RAIN_TABLE_SHIFT);
    vec4 tab = texelFetch(u_drop_table, ivec2(bin, d.layer), 0);
    d.d_mm = tab.x;
    uint m = uint(tab.y);
    // Pass count and fraction: exact in integers for the whole seconds, float only for small remainders.
    uint prod = m * uint(u_time_whole);
    float part = float(prod & (RAIN_TIME_PERIOD - 1u)) / float(RAIN_TIME_PERIOD)
                 + float(m) * u_time_frac / float(RAIN_TIME_PERIOD) + phase;
    float fl = floor(part);
    float s = part - fl;
    uint cycle = (prod >> 14u) + uint(fl) + m * u_epoch;
    uint hc = rain_hash(key ^ rain_hash(cycle));
    float x0 = rain_u01(rain_hash(hc ^ SALT_X));
    float z0 = rain_u01(rain_hash(hc ^ SALT_Z));
    float keep = rain_u01(rain_hash(hc ^ SALT_KEEP));
    float jx = rain_turb_step(hc, SALT_TURB_X);
    float jz = rain_turb_step(hc, SALT_TURB_Z);
    vec3 lo = u_box_lo[d.layer];
    vec3 ext = u_box_ext[d.layer];
    vec3 off = u_box_off[d.layer];
    vec3 turb = u_box_turb[d.layer];
    d.pos = lo + vec3(mod(x0 * ext.x + off.x + jx * turb.x, ext.x),
                      mod(ext.y * (1.0 - s) + off.y, ext.y),
                      mod(z0 * ext.z + off.z + jz * turb.z, ext.z));
    d.vel = vec3(u_wind.x * (1.0 + jx * u_turb_eps), -tab.z, u_wind.z * (1.0 + jz * u_turb_eps));
    d.r = u_thin.x * exp(-u_thin.y * d.d_mm);
    d.drawn = keep < min(1.0, d.r / u_thin.z);
    return d;
}

float rain_occ_sample(sampler2D tex, vec4 geom, vec2 xz) {
    float i = floor((xz.x - geom.x) / geom.y);
    float j = floor(mod(xz.y, u_period_world) / geom.y);
    if (i < 0.0 || i >= geom.z) return -1e4;
    return texelFetch(tex, ivec2(int(i), int(min(j, geom.w - 1.0))), 0).r;
}

// Height (m) of the roof over (x, z) (world.occluder_height): the fine map near the road, the coarse beyond.
float rain_occluder_height(vec2 xz) {
    float i = floor((xz.x - u_occ_fine_geom.x) / u_occ_fine_geom.y);
    if (i >= 0.0 && i < u_occ_fine_geom.z) return rain_occ_sample(u_occ_fine, u_occ_fine_geom, xz);
    return rain_occ_sample(u_occ_coarse, u_occ_coarse_geom, xz);
}

bool rain_in_vehicle(vec3 p) {
    for (int v = 0; v < RAIN_MAX_VEHICLES; ++v) {
        if (v >= u_veh_count) break;
        vec4 pose = u_veh_pose[v];
        vec3 rel = p - pose.xyz;
        float c = cos(pose.w), s = sin(pose.w);
        vec3 l = vec3(c * rel.x - s * rel.z, rel.y, s * rel.x + c * rel.z);
        for (int k = 0; k < 2; ++k) {
            int piece = 2 * v + k;
            if (any(lessThan(l, u_veh_lo[piece].xyz)) || any(greaterThan(l, u_veh_hi[piece].xyz))) continue;
            vec4 a = u_veh_plane[2 * piece];
            vec4 b = u_veh_plane[2 * piece + 1];
            if (dot(a.xyz, l) <= a.w && dot(b.xyz, l) <= b.w) return true;
        }
    }
    return false;
}

// Under a roof, inside a vehicle or below the ground: not drawn.
bool rain_occluded(vec3 p) {
    return p.y < u_ground_y || p.y < rain_occluder_height(p.xz) || rain_in_vehicle(p);
}
