#version 330 core
// Transform-feedback probe of the spray's GLSL model (tests and the bench compare it with the NumPy twin).
#include "spray/flight.glsl"
#include "spray/optics.glsl"
in vec4 in_p0;   // xyz m
in vec4 in_v0;   // xyz m/s, w tau s
in vec4 in_u;    // xyz m/s, w age s
in float in_mu;  // cos of the scattering angle
out vec3 out_pos;
out vec3 out_vel;
out float out_phase;
void main() {
    out_pos = spray_position(in_p0.xyz, in_v0.xyz, in_u.xyz, in_v0.w, in_u.w);
    out_vel = spray_velocity(in_v0.xyz, in_u.xyz, in_v0.w, in_u.w);
    out_phase = spray_phase(in_mu, 1.0);
}
