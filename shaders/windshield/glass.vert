#version 330 core
// The windshield mesh (car-local positions, outward normals, glass UV) placed by the ego car's model matrix.
#include "common/frame.glsl"
uniform mat4 u_model;  // car local → wrapped world
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_pos;
out vec3 v_nrm;
out vec2 v_uv;
void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_pos = world.xyz;
    v_nrm = mat3(u_model) * in_normal;
    v_uv = in_uv;
    gl_Position = u_view_proj * world;
}
