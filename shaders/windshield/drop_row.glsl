// One row of the drop buffer (rain_core.effects.windshield.splats.DROP_ROW), read by the drop texture's splats
// (drop_splat.vert) and the drop lenses (drop.vert): in_seg and in_radius. A drop (radius > 0) is its position
// and velocity (s, t, vs, vt), the rows copied from the simulation's as they are; its tail (the capsule from p0
// to p1) is laid here, behind it along its velocity, as long as its radius × speed / 0.25 m/s (at most 1.5
// radii). A wiper bead (radius < 0) is a line (s0, t0, s1, t1) of radius |radius|. Returns the kind (0, 1).
const float DROP_TAIL_SPEED = 0.25;  // m/s: a drop this fast has a tail one radius long
const float DROP_TAIL_MAX = 1.5;     // radii
int drop_row(vec4 seg, float radius, out vec2 p0, out vec2 p1, out float r) {
    p0 = seg.xy;
    if (radius < 0.0) {
        p1 = seg.zw;
        r = -radius;
        return 1;
    }
    vec2 v = seg.zw;
    float speed = length(v);
    p1 = p0 - v / max(speed, 1e-9) * (radius * min(speed / DROP_TAIL_SPEED, DROP_TAIL_MAX));
    r = radius;
    return 0;
}
