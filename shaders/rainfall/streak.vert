#version 330 core
// Rain streaks (rain_core/effects/rainfall/), second pass: one instance per drop, the quad of its streak record
// (rainfall/streak_record.vert wrote them; a culled drop's has r_head.w = 0).
in vec4 r_head;   // px from the view centre at the drop now, then its clip z and w
in vec4 r_tail;   // the same where it was, relative to the camera, when the shutter opened
in vec2 r_half;   // px: half extents of the coverage profile + 0.5 (across, along)
in vec4 r_color;  // pre-exposed radiance, opacity

uniform vec2 u_viewport;  // px

out vec2 v_local;   // px from the quad centre: (across, along)
out vec2 v_half;    // px: half extents of the coverage profile + 0.5
flat out vec4 v_color;  // pre-exposed radiance, opacity

void main() {
    if (r_head.w <= 0.0) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        v_local = vec2(0.0);
        v_half = vec2(1.0);
        v_color = vec4(0.0);
        return;
    }
    vec2 sa = r_head.xy;
    vec2 sb = r_tail.xy;
    vec2 dir = sb - sa;
    float len = length(dir);
    vec2 t = len > 1e-4 ? dir / len : vec2(0.0, 1.0);
    vec2 n = vec2(-t.y, t.x);
    // Quad corner (triangle strip): across ±1, along ±1 (−1 at the head).
    int c = gl_VertexID;
    float across = (c & 1) == 0 ? -1.0 : 1.0;
    float along = c < 2 ? -1.0 : 1.0;
    vec2 centre = 0.5 * (sa + sb);
    vec2 pos = centre + t * along * r_half.y + n * across * r_half.x;
    vec2 cc = along < 0.0 ? r_head.zw : r_tail.zw;
    gl_Position = vec4(pos / (0.5 * u_viewport) * cc.y, cc.x, cc.y);
    v_local = vec2(across * r_half.x, along * r_half.y);
    v_half = r_half;
    v_color = r_color;
}
