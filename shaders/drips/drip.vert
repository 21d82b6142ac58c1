#version 330 core
// Drips from roof edges, stateless (GPU twin of rain_core/effects/drips/flow.py): instance = site × slot. Slot 0
// is the drop hanging at the edge, growing until it lets go; slots 1… are the drops released before it, falling
// from rest under quadratic drag, motion-blurred over the shutter, gone once they reach where they land.
#include "common/frame.glsl"
uniform sampler2D u_sites_a;    // per site: x, z (m, tile), edge y, land y
uniform sampler2D u_sites_b;    // per site: phase, roof, terminal speed (m/s), diameter (mm)
uniform sampler2D u_roof_flux;  // per roof: outflow per site (m³/s)
uniform int u_first;            // first site of this draw
uniform int u_slots;            // slots per site
uniform float u_z_offset;       // m: tile z → wrapped frame for this draw's sites
uniform float u_shutter_s;      // s
uniform float u_pixel_rad;      // angular size of a pixel
uniform float u_max_period_s;   // s: slower sites are dry
const float G = 9.81;
const float PI = 3.14159265;
out vec2 v_uv;                  // −1 … 1 across, 0 … 1 along the streak
out float v_alpha;
out float v_round;              // 1: a round (hanging) drop, 0: a streak
out vec3 v_pos;                 // m, wrapped frame

ivec2 texel(int i) { return ivec2(i % 1024, i / 1024); }

// Seconds to fall h metres from rest (flow.fall_time_s).
float fall_time_s(float h, float vt) {
    float y = G * max(h, 0.0) / (vt * vt);
    return vt / G * (y + log(1.0 + sqrt(max(1.0 - exp(-2.0 * y), 0.0))));
}

float fall_m(float t, float vt) {
    float x = G * max(t, 0.0) / vt;
    return vt * vt / G * (x + log(1.0 + exp(-2.0 * x)) - log(2.0));
}

void cull() { gl_Position = vec4(2.0, 2.0, 2.0, 1.0); v_alpha = 0.0; v_uv = vec2(0.0); v_round = 0.0; v_pos = vec3(0.0); }

void main() {
    int site = u_first + gl_InstanceID / u_slots;
    int slot = gl_InstanceID % u_slots;
    vec4 a = texelFetch(u_sites_a, texel(site), 0);
    vec4 b = texelFetch(u_sites_b, texel(site), 0);
    float d_m = b.w * 1e-3;
    float flux = texelFetch(u_roof_flux, ivec2(int(b.y), 0), 0).r;
    float period = flux > 0.0 ? min(PI / 6.0 * d_m * d_m * d_m / flux, u_max_period_s) : u_max_period_s;
    if (period >= u_max_period_s) { cull(); return; }
    // A fast site is a stream: its drawn drops are spread over the whole fall, each standing for several real
    // ones (their coverage adds up), so the stream reaches the ground however few slots there are.
    float drawn_period = max(period, fall_time_s(a.z - a.w, b.z) / float(u_slots - 1));
    float stands_for = drawn_period / period;
    period = drawn_period;
    float cycles = u_time / period - b.x;
    float n = floor(cycles);
    vec3 base = vec3(a.x, a.z, a.y + u_z_offset);
    float top, bottom, width, stream_cover = 0.0;
    if (slot == 0) {  // hanging, growing to the pendant limit as the cycle runs
        float r = 0.5 * d_m * pow(max(cycles - n, 0.02), 1.0 / 3.0);
        top = base.y;
        bottom = base.y - 2.0 * r;
        width = 2.0 * r;
        v_round = 1.0;
    } else {
        float age = (cycles - n + float(slot - 1)) * period;
        float y = base.y - fall_m(age, b.z);
        if (y < a.w) { cull(); return; }
        // Drops closer in time than the shutter overlap in one exposure: a stream, drawn continuous from the drawn
        // drop above this one with the share of its length water covers, d / (v·T). Slower drops are drawn one
        // by one, smeared over the shutter; a drawn drop standing for several adds their coverage.
        bool stream = period / stands_for < u_shutter_s;
        float span = stream ? max(u_shutter_s, period) : u_shutter_s;
        float y_prev = base.y - fall_m(age - span, b.z);
        top = min(y_prev + 0.5 * d_m, base.y);
        bottom = max(y - 0.5 * d_m, a.w);
        width = d_m;
        v_round = 0.0;
        float v = b.z * tanh(G * age / b.z);
        stream_cover = stream ? min(1.0, d_m / max(v * period / stands_for, 1e-6)) : 0.0;
    }
    vec3 centre = vec3(base.x, 0.5 * (top + bottom), base.z);
    float dist = length(centre - u_camera_pos);
    float footprint = dist * u_pixel_rad;                 // m per pixel there
    float drawn = max(width, footprint);                  // never thinner than a pixel …
    float length_m = max(top - bottom, width);
    // … with the coverage of the real drop: its width's share of the pixel, and (a streak) the share of the
    // shutter it spends over each pixel along its path, d / (v·shutter + d).
    v_alpha = (width / drawn) * (stream_cover > 0.0 ? stream_cover
                                                   : min(1.0, width / length_m * (slot == 0 ? 1.0 : stands_for)));
    vec3 to_eye = normalize(u_camera_pos - centre);
    vec3 across = normalize(cross(vec3(0.0, 1.0, 0.0), to_eye) + vec3(1e-6, 0.0, 0.0));
    int corner = gl_VertexID;  // triangle strip: (−,bottom) (+,bottom) (−,top) (+,top)
    float side = float(corner & 1) * 2.0 - 1.0;
    float along = float(corner >> 1);
    vec3 p = vec3(centre.x, mix(bottom, top, along), centre.z) + across * side * 0.5 * drawn;
    v_uv = vec2(side, along);
    v_pos = p;
    gl_Position = u_view_proj * vec4(p, 1.0);
}
