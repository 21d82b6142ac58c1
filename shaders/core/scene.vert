#version 330 core
#include "common/frame.glsl"
uniform mat4 u_model;
uniform vec4 u_clip_plane;  // keep dot(world, plane) >= 0 when GL_CLIP_DISTANCE0 is on (reflection passes)
in vec3 in_position;
in vec3 in_normal;
in vec3 in_albedo;
in vec3 in_params;
out vec3 v_world;
out vec3 v_normal;
out vec3 v_albedo;
out vec3 v_params;
out float gl_ClipDistance[1];
// The depth pre-pass (core/scene_depth.frag) runs this shader too: both must rasterise the same depths.
invariant gl_Position;
void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_world = world.xyz;
    v_normal = mat3(u_model) * in_normal;
    v_albedo = in_albedo;
    v_params = in_params;
    gl_ClipDistance[0] = dot(world, u_clip_plane);
    gl_Position = u_view_proj * world;
}
