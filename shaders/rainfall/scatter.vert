#version 330 core
// Writes single texels of the drop state texture (rain_core/effects/rainfall/): one point per texel.
in int in_texel;
in vec4 in_value;
uniform ivec2 u_size;  // texels
flat out vec4 v_value;
void main() {
    ivec2 xy = ivec2(in_texel % u_size.x, in_texel / u_size.x);
    gl_Position = vec4((vec2(xy) + 0.5) / vec2(u_size) * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    v_value = in_value;
}
