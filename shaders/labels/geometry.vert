#version 330 core
// Label images, geometry pass (rain_core/labels/): the opaque scene's meshes as the scene pass draws them, with a
// class id per vertex (or one per draw) instead of a material.
#include "common/frame.glsl"
uniform mat4 u_model;   // mesh → wrapped world
uniform float u_class;  // ≥ 0: the class of every vertex of this draw; < 0: each vertex's in_class
in vec3 in_position;
in float in_class;
out vec3 v_world;
flat out float v_class;
void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_world = world.xyz;
    v_class = u_class >= 0.0 ? u_class : in_class;
    gl_Position = u_view_proj * world;
}
