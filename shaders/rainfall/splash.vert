#version 330 core
// Impact splashes (rain_core/effects/rainfall/): one instance per ring slot, a billboard standing on the impact
// point and turned to the camera about the vertical; the fragment shader draws the crown and its droplets.
#include "rainfall/drop.glsl"

in vec4 in_a;  // x, y, z mod period (m), impact time mod time period (s)
in vec4 in_b;  // D (mm), lifetime (s), type + seed, weight (impacts per drawn splash)
uniform float u_crown_per_d;  // crown height / D
out vec2 v_m;             // m in the billboard: (across, height above the ground)
flat out vec4 v_shape;    // (age s, lifetime s, crown height m, D m)
flat out vec4 v_kind;     // (type, seed, m per px, unused)
flat out vec4 v_color;    // pre-exposed radiance, light multiplier

void main() {
    float age = rain_age(in_a.w);
    float life = in_b.y;
    if (life <= 0.0 || age > life) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        v_m = vec2(0.0);
        v_shape = vec4(0.0);
        v_kind = vec4(0.0);
        v_color = vec4(0.0);
        return;
    }
    vec3 p = vec3(in_a.x, in_a.y, rain_wrap_z(in_a.z));
    float type = floor(in_b.z);
    float d_m = in_b.x * 1e-3;
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
    v_kind = vec4(type, fract(in_b.z), m_per_px, 0.0);
    vec3 radiance = apply_atmosphere_dir(rain_drop_radiance(p + vec3(0.0, crown, 0.0), to_eye / max(dist, 1e-4)), dist,
                                          -to_eye / max(dist, 1e-4));
    v_color = vec4(radiance * u_exposure, in_b.w * u_brightness);
}
