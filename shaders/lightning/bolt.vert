#version 330 core
// A lightning channel segment as a screen-aligned strip a few pixels wide (instanced: one segment per instance,
// four vertices). The channel is centimetres wide and kilometres away, far below a pixel: its light is spread
// over the strip so that the strip's integral across it equals the sub-pixel line's (bolt.frag).
#include "common/frame.glsl"
in vec3 a_p0;        // m, wrapped frame
in vec3 a_p1;
in float a_weight;   // share of the stroke's current in this branch (main channel 1)
uniform vec2 u_viewport;       // px
uniform float u_half_width_px; // half the strip's width
out float v_across;  // −1 … 1 across the strip, in units of the half width
out float v_weight;
out float v_dist;    // m, eye to the segment's point
void main() {
    float t = float(gl_VertexID & 1);
    float side = float(gl_VertexID >> 1) * 2.0 - 1.0;
    vec4 c0 = u_view_proj * vec4(a_p0, 1.0);
    vec4 c1 = u_view_proj * vec4(a_p1, 1.0);
    if (c0.w <= 0.0 || c1.w <= 0.0) {  // behind the eye: drop the segment (bolts are far; nothing is lost)
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        v_across = 0.0; v_weight = 0.0; v_dist = 1.0;
        return;
    }
    vec2 s0 = c0.xy / c0.w * u_viewport * 0.5;
    vec2 s1 = c1.xy / c1.w * u_viewport * 0.5;
    vec2 along = s1 - s0;
    vec2 dir = length(along) > 1e-4 ? normalize(along) : vec2(0.0, 1.0);
    vec2 normal = vec2(-dir.y, dir.x);
    vec4 clip = mix(c0, c1, t);
    clip.xy += normal * side * u_half_width_px * 2.0 / u_viewport * clip.w;
    // Beyond the far plane (bolts are kilometres off): pinned just inside it, behind every surface, so the
    // depth test still hides the bolt behind buildings.
    clip.z = min(clip.z, clip.w * 0.999999);
    gl_Position = clip;
    v_across = side;
    v_weight = a_weight;
    v_dist = length(mix(a_p0, a_p1, t) - u_camera_pos);
}
