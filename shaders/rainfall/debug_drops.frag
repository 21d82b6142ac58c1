#version 330 core
// Writes the probe value of rainfall/debug_drops.vert.
flat in vec4 v_value;
out vec4 f_value;
void main() {
    f_value = v_value;
}
