#version 330 core
#include "common/frame.glsl"
uniform mat4 u_model;
in vec3 in_position;
in vec3 in_normal;
in vec3 in_albedo;
in vec3 in_params;
out vec3 v_world;
out vec3 v_normal;
out vec3 v_albedo;
out vec3 v_params;
void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_world = world.xyz;
    v_normal = mat3(u_model) * in_normal;
    v_albedo = in_albedo;
    v_params = in_params;
    gl_Position = u_view_proj * world;
}
