#version 330 core
flat in vec4 v_value;
out vec4 f_value;
void main() {
    f_value = v_value;
}
