#version 330 core
// Depth from the sun for the shadow map (positions only).
uniform mat4 u_model;
uniform mat4 u_light_view_proj;
in vec3 in_position;
void main() {
    gl_Position = u_light_view_proj * (u_model * vec4(in_position, 1.0));
}
