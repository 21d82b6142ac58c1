#version 330 core
// Test probe (rain_core/effects/rainfall/effect.py, RainfallEffect.read_drops): one point per instance, written to
// texel (id mod width, id / width) of a float target: the drop's position (wrapped frame) and its flags
// (1: drawn by the thinning, 2: occluded), so tests compare the GPU's drops with the NumPy twin.
#include "rainfall/drops.glsl"
uniform int u_probe_width;
uniform vec2 u_probe_size;  // px of the target
flat out vec4 v_value;
void main() {
    int id = gl_VertexID;
    RainDrop d = rain_drop(id);
    float flags = (d.drawn ? 1.0 : 0.0) + (rain_occluded(d.pos) ? 2.0 : 0.0);
    ivec2 xy = ivec2(id % u_probe_width, id / u_probe_width);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    v_value = vec4(d.pos, flags);
    gl_Position.xy = (vec2(xy) + 0.5) / u_probe_size * 2.0 - 1.0;
}
