#version 330 core
// Instanced splats into the glass's UV textures: a capsule from p0 to p1 (s, t in m) of radius r (m). kind 0: a
// drop (spherical cap head at p0, tapering tail to p1); 1: a line of water (cylindrical profile: trails, the
// wiper bead); 2: a splash of satellite droplets (speckled disc).
#include "windshield/glass_common.glsl"
in vec4 in_seg;    // s0, t0, s1, t1 (m)
in vec4 in_info;   // radius (m), value (mm height or µm film), kind, spare
out vec2 v_local;  // metres: x along p0→p1 from p0, y across
flat out vec4 v_info;
flat out float v_len;
void main() {
    vec2 p0 = in_seg.xy, p1 = in_seg.zw;
    vec2 d = p1 - p0;
    float len = length(d);
    vec2 ax = len > 1e-7 ? d / len : vec2(1.0, 0.0);
    vec2 ay = vec2(-ax.y, ax.x);
    float r = in_info.x;
    int corner = gl_VertexID % 6;
    // two triangles: (0,0) (1,0) (1,1) / (0,0) (1,1) (0,1)
    vec2 c = vec2(corner == 1 || corner == 2 || corner == 4 ? 1.0 : 0.0, corner == 2 || corner >= 4 ? 1.0 : 0.0);
    float x = mix(-r, len + r, c.x);
    float y = mix(-r, r, c.y);
    vec2 st = p0 + ax * x + ay * y;
    v_local = vec2(x, y);
    v_info = in_info;
    v_len = len;
    gl_Position = vec4(glass_uv(st) * 2.0 - 1.0, 0.0, 1.0);
}
