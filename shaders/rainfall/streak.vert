#version 330 core
// Rain streaks (rain_core/effects/rainfall/): one instance per drop slot, a screen-aligned quad around the drop's path
// relative to the camera during the exposure. Keep in step with the NumPy twin streaks.streak_geometry.
#include "rainfall/drop.glsl"

#ifndef LAYERS
#define LAYERS 3  // rainfall.LAYER_SCALES (the effect passes the count)
#endif
uniform sampler2D u_state;          // RGBA32F, 3 texels per drop (see RainfallSim.texels)
uniform int u_drops_per_row;
uniform vec3 u_cam_vel;             // m/s, world
uniform float u_exposure_s;         // s
uniform float u_near;               // m
uniform vec3 u_box_lo[LAYERS];      // m, wrapped frame
uniform vec3 u_box_hi[LAYERS];
uniform vec3 u_box_fade[LAYERS];    // m
uniform float u_layer_nu[LAYERS];
uniform float u_shape_area[10];     // side-view area factor at D = 1, 2, 2.5, … 6 mm
uniform float u_shape_width[10];
uniform float u_width_floor_px;
uniform float u_width_max_px;
uniform float u_alpha_max;

out vec2 v_local;   // px from the quad centre: (across, along)
out vec2 v_half;    // px: half extents of the coverage profile + 0.5
flat out vec4 v_color;  // pre-exposed radiance, opacity

float rain_membership(int k, vec3 p) {
    vec3 a = clamp((p - u_box_lo[k]) / u_box_fade[k], 0.0, 1.0);
    vec3 b = clamp((u_box_hi[k] - p) / u_box_fade[k], 0.0, 1.0);
    a.y = p.y >= u_box_lo[k].y ? 1.0 : 0.0;
    return a.x * a.y * a.z * b.x * b.y * b.z;
}

float shape_lookup(float table[10], float d_mm) {
    float x = d_mm <= 2.0 ? d_mm - 1.0 : 1.0 + (d_mm - 2.0) * 2.0;
    x = clamp(x, 0.0, 9.0);
    int i = min(int(floor(x)), 8);
    return mix(table[i], table[i + 1], x - float(i));
}

void cull() {
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    v_local = vec2(0.0);
    v_half = vec2(1.0);
    v_color = vec4(0.0);
}

void main() {
    int id = gl_InstanceID;
    int row = id / u_drops_per_row;
    int col = 3 * (id - row * u_drops_per_row);
    vec4 s0 = texelFetch(u_state, ivec2(col, row), 0);
    vec4 s1 = texelFetch(u_state, ivec2(col + 1, row), 0);
    vec4 s2 = texelFetch(u_state, ivec2(col + 2, row), 0);
    float life = s1.w;
    float age = rain_age(s0.w);
    if (life <= 0.0 || age - u_exposure_s > life) { cull(); return; }
    vec3 p0 = vec3(s0.x, s0.y, rain_wrap_z(s0.z));
    vec3 u = s1.xyz;
    float age_head = min(age, life);
    vec3 head = p0 + u * age_head;
    int layer = int(s2.z + 0.5);
    float m_own = rain_membership(layer, head);
    float density = 0.0;
    for (int k = 0; k < LAYERS; ++k) density += u_layer_nu[k] * rain_membership(k, head);
    density = max(density, u_layer_nu[LAYERS - 1]);
    float weight = s2.y * m_own / density;  // real drops this one stands for, faded at its box's edge
    if (weight <= 0.0) { cull(); return; }
    // The streak: where the drop is now, and where it was relative to the camera when the shutter opened.
    vec3 a_w = head + u_cam_vel * (age - age_head);
    vec3 b_w = p0 + u * (age - u_exposure_s) + u_cam_vel * u_exposure_s;
    vec4 ca = u_view_proj * vec4(a_w, 1.0);
    vec4 cb = u_view_proj * vec4(b_w, 1.0);
    float wmin = u_near * 1.01;
    if (ca.w < wmin && cb.w < wmin) { cull(); return; }
    if (ca.w < wmin) ca = mix(ca, cb, (wmin - ca.w) / (cb.w - ca.w));
    if (cb.w < wmin) cb = mix(cb, ca, (wmin - cb.w) / (ca.w - cb.w));
    // Both ends beyond one side of the view (a margin for the width): nothing to draw, skip the lighting.
    float m = 1.0 + (u_width_max_px + 2.0) / (0.5 * min(u_viewport.x, u_viewport.y));
    if ((ca.x > m * ca.w && cb.x > m * cb.w) || (ca.x < -m * ca.w && cb.x < -m * cb.w) ||
        (ca.y > m * ca.w && cb.y > m * cb.w) || (ca.y < -m * ca.w && cb.y < -m * cb.w)) { cull(); return; }
    vec2 sa = ca.xy / ca.w * 0.5 * u_viewport;
    vec2 sb = cb.xy / cb.w * 0.5 * u_viewport;
    vec2 dir = sb - sa;
    float len = length(dir);
    vec2 t = len > 1e-4 ? dir / len : vec2(0.0, 1.0);
    vec2 n = vec2(-t.y, t.x);
    // Light budget in px² of full coverage: the drop's projected area times its weight.
    float d_m = s2.x * 1e-3;
    float d_px = d_m * u_focal_px / ca.w;
    float area_px = 0.78539816 * d_px * d_px * shape_lookup(u_shape_area, s2.x) * weight * u_brightness;
    float w_px = max(d_px * shape_lookup(u_shape_width, s2.x), u_width_floor_px);
    float alpha = area_px / (w_px * (len + w_px));
    if (alpha > u_alpha_max) {  // compensation: brighter up to u_alpha_max, then wider up to u_width_max_px
        float wide = 0.5 * (-len + sqrt(len * len + 4.0 * area_px / u_alpha_max));
        w_px = min(max(wide, w_px), u_width_max_px);
        alpha = min(area_px / (w_px * (len + w_px)), u_alpha_max);
    }
    // Quad corner (triangle strip): across ±1, along ±1 (−1 at the head).
    int c = gl_VertexID;
    float across = (c & 1) == 0 ? -1.0 : 1.0;
    float along = c < 2 ? -1.0 : 1.0;
    vec2 half_ext = vec2(0.5 * w_px + 0.5, 0.5 * (len + w_px) + 0.5);
    vec2 centre = 0.5 * (sa + sb);
    vec2 pos = centre + t * along * half_ext.y + n * across * half_ext.x;
    vec4 cc = along < 0.0 ? ca : cb;
    gl_Position = vec4(pos / (0.5 * u_viewport) * cc.w, cc.z, cc.w);
    v_local = vec2(across * half_ext.x, along * half_ext.y);
    v_half = half_ext;
    vec3 to_eye = u_camera_pos - head;
    float dist = length(to_eye);
    vec3 radiance = apply_atmosphere_dir(rain_drop_radiance(head, to_eye / max(dist, 1e-4)), dist, -to_eye / max(dist, 1e-4));
    v_color = vec4(radiance * u_exposure, alpha);
}
