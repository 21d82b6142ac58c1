#version 330 core
// The light grid of a view, a texel per tile of u_light_grid_px pixels: bit i set unless light i's range sphere
// lies wholly outside the tile's frustum: its four side planes and the plane through the eye (rows of
// u_view_proj), and a far plane at the farthest depth the scene's depth pre-pass left in the tile (none where a
// pixel kept the cleared depth: sky, or only cars, which the pre-pass leaves out). Whatever the lit pass then
// shows in the tile is in front of the pre-pass's depths, so inside that frustum: a light left out is beyond
// its range there, where light_at gives nothing. The tile is taken a pixel wider on each side, the depth a
// little farther and the range a little longer, for the rounding of the fragments' interpolated positions.
#include "common/frame.glsl"
#include "common/view_distance.glsl"
uniform sampler2D u_depth;  // the view's depth after the pre-pass (window depth, 1: cleared)
uniform vec2 u_near_far;    // the camera's near and far planes (m)
out uint f_lights;

void main() {
    int px = u_light_grid_px;
    ivec2 size = textureSize(u_depth, 0);
    ivec2 first = ivec2(gl_FragCoord.xy) * px - 1;
    float deepest = 0.0;
    for (int y = 0; y < px + 2; ++y)
        for (int x = 0; x < px + 2; ++x)
            deepest = max(deepest, texelFetch(u_depth, clamp(first + ivec2(x, y), ivec2(0), size - 1), 0).r);
    // The distance along the view axis (clip w) of that depth, a little farther; none past the cleared depth.
    float far_w = deepest >= 1.0 ? 3.0e38 : 1.01 * view_distance(deepest, u_near_far) + 0.1;
    vec2 lo = vec2(first) / vec2(size) * 2.0 - 1.0;
    vec2 hi = vec2(first + px + 2) / vec2(size) * 2.0 - 1.0;
    mat4 rows = transpose(u_view_proj);  // rows[k]: the world-space plane of clip coordinate k
    vec4 planes[6] = vec4[6](rows[0] - lo.x * rows[3], hi.x * rows[3] - rows[0], rows[1] - lo.y * rows[3],
                             hi.y * rows[3] - rows[1], rows[3], vec4(-rows[3].xyz, far_w - rows[3].w));
    for (int k = 0; k < 6; ++k) planes[k] /= length(planes[k].xyz);  // signed distances in m
    uint mask = 0u;
    for (int i = 0; i < u_light_count; ++i) {
        vec3 c = u_light_pos[i].xyz;
        float r = abs(u_light_pos[i].w) * 1.001 + 0.05;
        bool reaches = true;
        for (int k = 0; k < 6; ++k)
            reaches = reaches && dot(planes[k].xyz, c) + planes[k].w >= -r;
        if (reaches) mask |= 1u << uint(i);
    }
    f_lights = mask;
}
