#version 330 core
// Rain streaks (rain_core/effects/rainfall/), first pass: one vertex per drop, no rasterising. It finds the drop
// (rainfall/drops.glsl: no stored state), culls it, lights it and writes its streak record by transform feedback:
// the screen-aligned quad around the drop's path relative to the camera during the exposure. rainfall/streak.vert
// then draws each record's quad. Done here, a drop's work runs once rather than at each of its quad's 4 corners.
// Keep in step with the NumPy twin streaks.streak_geometry.
#include "rainfall/drop.glsl"
#include "rainfall/drops.glsl"

uniform float u_exposure_s;         // s
uniform float u_near;               // m
uniform vec3 u_box_fade[LAYERS];    // m
uniform float u_box_fade_bottom[LAYERS];  // m (0: a hard floor below the ground)
uniform float u_layer_rho[LAYERS];  // instances per m³
uniform float u_shape_area[10];     // side-view area factor at D = 1, 2, 2.5, … 6 mm
uniform float u_shape_width[10];
uniform float u_width_floor_px;
uniform float u_width_max_px;
uniform float u_alpha_max;
uniform float u_alpha_spread;       // constants.SPREAD_ALPHA
uniform float u_stretch_max;        // constants.STRETCH_MAX

// The streak record (streak_pass.RECORD_FORMAT); a culled drop writes r_head.w = 0.
out vec4 r_head;   // px from the view centre at the drop now, then its clip z and w
out vec4 r_tail;   // the same where it was, relative to the camera, when the shutter opened
out vec2 r_half;   // px: half extents of the coverage profile + 0.5 (across, along)
out vec4 r_color;  // pre-exposed radiance, opacity

float rain_membership(int k, vec3 p) {
    vec3 a = clamp((p - u_box_lo[k]) / u_box_fade[k], 0.0, 1.0);
    vec3 b = clamp((u_box_lo[k] + u_box_ext[k] - p) / u_box_fade[k], 0.0, 1.0);
    float fb = u_box_fade_bottom[k];
    a.y = fb > 0.0 ? clamp((p.y - u_box_lo[k].y) / fb, 0.0, 1.0) : (p.y >= u_box_lo[k].y ? 1.0 : 0.0);
    return a.x * a.y * a.z * b.x * b.y * b.z;
}

float shape_lookup(float table[10], float d_mm) {
    float x = d_mm <= 2.0 ? d_mm - 1.0 : 1.0 + (d_mm - 2.0) * 2.0;
    x = clamp(x, 0.0, 9.0);
    int i = min(int(floor(x)), 8);
    return mix(table[i], table[i + 1], x - float(i));
}

void cull() {
    r_head = vec4(0.0);
    r_tail = vec4(0.0);
    r_half = vec2(0.0);
    r_color = vec4(0.0);
}

void main() {
    RainDrop drop = rain_drop(gl_VertexID);
    if (!drop.drawn) { cull(); return; }
    vec3 head = drop.pos;
    float m_own = rain_membership(drop.layer, head);
    float density = 0.0;
    for (int k = 0; k < LAYERS; ++k) density += u_layer_rho[k] * rain_membership(k, head);
    density = max(density, u_layer_rho[LAYERS - 1]);
    float weight = max(drop.r, u_thin.z) * m_own / density;  // real drops this one stands for
    if (weight <= 0.0) { cull(); return; }
    vec3 u = drop.vel;
    // The streak: where the drop is now, and where it was relative to the camera when the shutter opened.
    vec3 a_w = head;
    vec3 b_w = head + (u_cam_vel - u) * u_exposure_s;
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
    if (rain_occluded(head)) { cull(); return; }  // after the view test: it reads textures
    vec2 sa = ca.xy / ca.w * 0.5 * u_viewport;
    vec2 sb = cb.xy / cb.w * 0.5 * u_viewport;
    float len = length(sb - sa);
    // Light budget in px² of full coverage: the drop's projected area times its weight. Coverage (optics.
    // streak_coverage): a pixel on the path is covered A·(τ/T)/(pixel area) on average over the exposure, so
    // α = A / (w·(ℓ + h)), h the drop's own chord along the motion (area / true width), w ≥ the 1 px floor.
    float d_m = drop.d_mm * 1e-3;
    float d_px = d_m * u_focal_px / ca.w;
    float area_f = shape_lookup(u_shape_area, drop.d_mm);
    float width_f = shape_lookup(u_shape_width, drop.d_mm);
    float area_px = 0.78539816 * d_px * d_px * area_f * weight * u_brightness;
    float h_px = 0.78539816 * d_px * area_f / width_f;
    float len_h = len + h_px;
    float w_px = max(d_px * width_f, u_width_floor_px);
    float alpha = area_px / (w_px * len_h);
    if (alpha > u_alpha_spread) {
        // Compensation: spread like the drops it stands for — first longer along the motion (up to
        // u_stretch_max × the footprint: a line of rain, not a fleck), then wider up to u_width_max_px, then
        // brighter up to u_alpha_max (twin: rain_core.effects.rainfall.streaks).
        float need = area_px / u_alpha_spread;
        len_h = clamp(need / w_px, len_h, u_stretch_max * len_h);
        w_px = min(max(need / len_h, w_px), u_width_max_px);
        alpha = min(area_px / (w_px * len_h), u_alpha_max);
    }
    r_head = vec4(sa, ca.zw);
    r_tail = vec4(sb, cb.zw);
    r_half = vec2(0.5 * w_px + 0.5, 0.5 * len_h + 0.5);
    vec3 to_eye = u_camera_pos - head;
    float dist = length(to_eye);
    vec3 radiance = apply_atmosphere_dir(rain_drop_radiance(head, to_eye / max(dist, 1e-4)), dist, -to_eye / max(dist, 1e-4));
    r_color = vec4(radiance * u_exposure, alpha);
}
