#version 330 core
// The drops (and the wiper's bead) as lenses on the glass: one instanced quad per row of the drop buffer the drop
// texture was splatted from (windshield/drop_row.glsl), placed on the curved glass in the world and widened by
// the blur the eye sees it with (its pupil when focused far, else the pixel's footprint).
#include "common/frame.glsl"
#include "windshield/glass_common.glsl"
#include "windshield/drop_row.glsl"
uniform mat4 u_model;          // car local → wrapped world
uniform vec3 u_glass_origin;   // car-local bottom centre of the glass (m)
uniform vec3 u_glass_right;    // car-local +s
uniform vec3 u_glass_up;       // car-local +t
uniform vec3 u_glass_normal;   // car-local outward normal of the glass's plane
uniform float u_glass_sag;     // m: the bulge at the centre
uniform float u_aperture_m;    // radius of the eye's pupil (m)
uniform float u_focus_m;       // distance the eye is focused at (m)
uniform float u_pixel_rad;     // angle of one pixel (rad)
in vec4 in_seg;
in float in_radius;
out vec2 v_local;  // metres: x along p0→p1 from p0, y across
out vec3 v_pos;
flat out vec4 v_shape;  // true radius (m), tail length (m), blur radius (m), kind
flat out vec2 v_axis;   // unit direction p0→p1 in (s, t)
flat out vec3 v_nrm;

vec3 glass_local(vec2 st) {
    vec2 uv = glass_uv(st);
    float bulge = u_glass_sag * (1.0 - pow(2.0 * uv.x - 1.0, 2.0)) * (1.0 - pow(2.0 * uv.y - 1.0, 2.0));
    return u_glass_origin + st.y * u_glass_up + st.x * u_glass_right + bulge * u_glass_normal;
}

void main() {
    vec2 p0, p1;
    float r;
    int kind = drop_row(in_seg, in_radius, p0, p1, r);
    vec2 d = p1 - p0;
    float len = length(d);
    vec2 ax = len > 1e-7 ? d / len : vec2(1.0, 0.0);
    vec2 ay = vec2(-ax.y, ax.x);
    // The blur: from the drop's centre, the same for the whole quad.
    vec3 centre = (u_model * vec4(glass_local(p0), 1.0)).xyz;
    vec3 n_local = cross(glass_local(p0 + vec2(0.0, 0.01)) - glass_local(p0),
                         glass_local(p0 + vec2(0.01, 0.0)) - glass_local(p0));
    vec3 n = normalize(mat3(u_model) * n_local);
    vec3 to = centre - u_camera_pos;
    float dist = length(to);
    float slant = max(abs(dot(to / dist, n)), 0.25);
    float foot = dist * u_pixel_rad / slant;
    float blur = max(u_aperture_m * abs(1.0 - dist / u_focus_m), 0.5 * foot);
    float ext = r + blur + foot;
    int corner = gl_VertexID % 6;
    vec2 c = vec2(corner == 1 || corner == 2 || corner == 4 ? 1.0 : 0.0, corner == 2 || corner >= 4 ? 1.0 : 0.0);
    float x = mix(-ext, len + ext, c.x);
    float y = mix(-ext, ext, c.y);
    vec2 st = p0 + ax * x + ay * y;
    vec4 world = u_model * vec4(glass_local(st), 1.0);
    v_local = vec2(x, y);
    v_pos = world.xyz;
    v_shape = vec4(r, len, blur, float(kind));
    v_axis = ax;
    v_nrm = n;
    gl_Position = u_view_proj * world;
}
