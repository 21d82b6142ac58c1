#version 330 core
// The drop texture's splats (splat.frag's kinds 0 and 1) from the drop buffer's rows (drop_row.glsl): a drop or
// bead narrower than u_min_radius is splatted that wide and lower, the same height × width (the water it holds),
// so it does not flicker between texels. Its value is its height (mm): u_height_per_radius × radius for a drop's
// cap, the radius for a bead's cylinder.
#include "windshield/glass_common.glsl"
#include "windshield/drop_row.glsl"
uniform float u_min_radius;         // m: 0.75 texel of the drop texture
uniform float u_height_per_radius;  // a drop's cap height / contact radius
in vec4 in_seg;
in float in_radius;
out vec2 v_local;  // metres: x along p0→p1 from p0, y across
flat out vec4 v_info;
flat out float v_len;
void main() {
    vec2 p0, p1;
    float a;
    int kind = drop_row(in_seg, in_radius, p0, p1, a);
    vec2 d = p1 - p0;
    float len = length(d);
    vec2 ax = len > 1e-7 ? d / len : vec2(1.0, 0.0);
    vec2 ay = vec2(-ax.y, ax.x);
    float r = max(a, u_min_radius);
    float k = kind == 0 ? u_height_per_radius : 1.0;
    int corner = gl_VertexID % 6;
    // two triangles: (0,0) (1,0) (1,1) / (0,0) (1,1) (0,1)
    vec2 c = vec2(corner == 1 || corner == 2 || corner == 4 ? 1.0 : 0.0, corner == 2 || corner >= 4 ? 1.0 : 0.0);
    float x = mix(-r, len + r, c.x);
    float y = mix(-r, r, c.y);
    vec2 st = p0 + ax * x + ay * y;
    v_local = vec2(x, y);
    v_info = vec4(r, 1e3 * k * a * (a / r), float(kind), 0.0);
    v_len = len;
    gl_Position = vec4(glass_uv(st) * 2.0 - 1.0, 0.0, 1.0);
}
