#version 330 core
// A streak's coverage: a box of the streak's width and length convolved with a 1 px box (so the integral over
// the quad is exactly width × length, the light budget the vertex shader set).
in vec2 v_local;
in vec2 v_half;
flat in vec4 v_color;
out vec4 f_color;
void main() {
    float cx = clamp(v_half.x - abs(v_local.x), 0.0, 1.0);
    float cy = clamp(v_half.y - abs(v_local.y), 0.0, 1.0);
    float a = v_color.a * cx * cy;
    if (a <= 0.0) discard;
    f_color = vec4(v_color.rgb, a);
}
