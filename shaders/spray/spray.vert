#version 330 core
// Spray parcels (rain_core/effects/spray): one camera-facing quad per parcel (instanced, 4-vertex strip), flown by
// the closed form from what was stored at spawn, so nothing is uploaded per frame. A droplet parcel is
// stretched along its screen motion over the exposure time (its drops' streaks); mist puffs are round and grow.
// The light is evaluated once per parcel (spray/shading.glsl: the environment seen through the drops, the sun's
// and lamps' scattering lobe), through the atmosphere, and handed to the fragment flat.
#include "common/frame.glsl"
#include "common/atmosphere.glsl"
#include "spray/flight.glsl"
#include "spray/shading.glsl"

in vec4 in_p0;    // xyz m (z relative to its period), w period index
in vec4 in_v0;    // xyz m/s launch velocity, w tau s
in vec4 in_u;     // xyz m/s drift velocity, w birth s (effect clock)
in vec4 in_life;  // x lifetime s, y sigma0 m, z spread (droplet: per unit relaxed distance; mist: 2K m²/s), w m²
in vec4 in_misc;  // x kind (0 droplet, 1 mist, +2 fades out at the end), y D mm, z random [0,1),
                  // w droplets: glint weight; mist: largest sigma m

uniform float u_clock;          // s, effect clock
uniform float u_shift_periods;  // renderer shift_z / PERIOD_M
uniform vec3 u_camera_vel;      // m/s, for the streak (what the eye or the shutter smears is relative motion)
uniform float u_exposure_s;     // s
uniform vec3 u_cam_forward;
uniform float u_pixel_angle;    // rad per pixel (vertical)

out vec2 v_coord;            // m from the parcel centre: along the streak, across it
out float v_view_depth;      // m, along the camera's forward axis
flat out vec4 v_shape;       // half streak length m, sigma along the streak / across it m, centre optical depth
flat out vec4 v_misc;        // mist (0/1), random, fade (life and age), sheet share (young splash: 1)
flat out vec3 v_radiance;    // cd/m² per unit opacity, through the atmosphere, × exposure
flat out float v_pixel_m;    // m, the size of a pixel at the parcel

const float EDGE_SIGMAS_DROP = 3.0;
const float EDGE_SIGMAS_MIST = 2.5;

void main() {
    float age = u_clock - in_u.w;
    float life = in_life.x;
    if (age < 0.0 || age >= life) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: nothing rasterised
        return;
    }
    bool mist = mod(in_misc.x, 2.0) > 0.5;
    bool fades = in_misc.x > 1.5 || mist;
    float tau = in_v0.w;
    vec3 pos = spray_position(in_p0.xyz, in_v0.xyz, in_u.xyz, tau, age);
    pos.z += (in_p0.w - u_shift_periods) * SPRAY_PERIOD_M;
    vec3 vel = spray_velocity(in_v0.xyz, in_u.xyz, tau, age);
    // A mist puff spreads sideways without bound but only as high as the wake that holds it (in_misc.w).
    float sigma = mist ? in_life.y + sqrt(in_life.z * age)
                       : in_life.y + in_life.z * spray_relax(age, tau) + 0.02 * age;
    float sigma_b = mist ? min(sigma, in_misc.w) : sigma;

    vec3 to_eye = u_camera_pos - pos;
    float dist = max(length(to_eye), 1e-3);
    vec3 view = to_eye / dist;
    vec3 rel = vel - u_camera_vel;
    vec3 rel_perp = rel - view * dot(rel, view);
    float half_len = mist ? 0.0 : 0.5 * length(rel_perp) * u_exposure_s;
    vec3 side = abs(view.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 axis_a = half_len > 1e-5 ? normalize(rel_perp) : normalize(cross(side, view));
    vec3 axis_b = normalize(cross(view, axis_a));
    float k = mist ? EDGE_SIGMAS_MIST : EDGE_SIGMAS_DROP;
    vec2 ext = vec2(half_len + k * sigma, k * sigma_b);
    vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1)) * 2.0 - 1.0;
    vec3 world = pos + axis_a * corner.x * ext.x + axis_b * corner.y * ext.y;
    gl_Position = u_view_proj * vec4(world, 1.0);
    v_coord = corner * ext;
    v_view_depth = dot(world - u_camera_pos, u_cam_forward);

    // Optical depth at the centre: the extinction area spread over the Gaussian (and along the streak).
    float spread = 2.0 * SPRAY_PI * sigma * sigma_b + 2.0 * half_len * sqrt(2.0 * SPRAY_PI) * sigma_b;
    float tau_c = in_life.w / spread;
    float fade = fades ? clamp((life - age) / (0.25 * life), 0.0, 1.0) : 1.0;
    if (mist) fade *= clamp(age / 0.15, 0.0, 1.0);
    // Side and bow waves and the tread's splash leave the tyre as sheets of water that break into drops after
    // a few centimetres (about SPRAY_SHEET_S per mm of drop size).
    float sheet = (!mist && in_misc.y >= SPRAY_SPLASH_MIN_MM)
        ? 1.0 - clamp(age / (SPRAY_SHEET_S * in_misc.y), 0.0, 1.0) : 0.0;
    v_shape = vec4(half_len, sigma, sigma_b, tau_c);
    v_misc = vec4(mist ? 1.0 : 0.0, in_misc.z, fade, sheet);
    v_pixel_m = dist * u_pixel_angle;
    vec3 radiance = apply_atmosphere_dir(spray_radiance(pos, view), dist, -view);
    v_radiance = radiance * u_exposure;
}
