// Per-frame camera uniforms shared by every pass that draws in the world.
uniform mat4 u_view_proj;
uniform vec3 u_camera_pos;   // m, wrapped frame
uniform float u_exposure;    // cd/m² → tone-mapper input
uniform float u_time;        // s
uniform float u_night;       // 0 day … 1 night
