#version 330 core
// Spray parcels (rain_core/effects/spray): one camera-facing quad per parcel (instanced, 4-vertex strip), flown by
// the closed form from what was stored at spawn, so nothing is uploaded per frame. A droplet parcel is
// stretched along its screen motion over the exposure time (a streak); mist puffs are round and grow.
// Lighting is evaluated per vertex (parcels are small): single scattering of sun and lights with the drops'
// phase function, the reflection lobe kept apart for the fragment's sparkle.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "spray/flight.glsl"
#include "spray/optics.glsl"

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
flat out float v_fade;
flat out vec4 v_misc;        // mist (0/1), random, distance to the eye m, glint weight
flat out vec3 v_axis_a;      // world axis of v_coord.x
flat out vec3 v_axis_b;      // world axis of v_coord.y
flat out vec3 v_view;        // unit, parcel → eye
flat out vec3 v_sun_ss;      // cd/m² per unit (1 − T): sun, single scattering (smooth lobes)
flat out vec3 v_lights_ss;   // the lamps and vehicle lights, same
flat out vec3 v_lights_diffuse;  // the lights' share if the parcel were a dense white body
flat out vec3 v_glint;       // reflection lobe of sun and lights (mean; the fragment concentrates it)
flat out vec3 v_amb_iso;     // sky and ground averaged over all directions
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
    v_shape = vec4(half_len, sigma, sigma_b, tau_c);
    v_fade = fade;
    v_misc = vec4(mist ? 1.0 : 0.0, in_misc.z, dist, 0.0);
    v_axis_a = axis_a;
    v_axis_b = axis_b;
    v_view = view;
    v_pixel_m = dist * u_pixel_angle;

    // Single scattering. mu = cos(scattering angle) between the light's travel and parcel → eye.
    float mu_sun = dot(-u_sun_dir, view);
    v_sun_ss = u_sun_illum * spray_phase_wide(mu_sun);
    vec3 glint = u_sun_illum * 0.5 * spray_reflection(mu_sun);
    vec3 lights = vec3(0.0);
    vec3 lights_diffuse = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 d = u_light_pos[i].xyz - pos;
        float dist2 = dot(d, d);
        float range = abs(u_light_pos[i].w);
        if (dist2 > range * range) continue;
        vec3 L = d * inversesqrt(dist2);
        float window = clamp(1.0 - pow(dist2 / (range * range), 2.0), 0.0, 1.0);
        vec3 E = u_light_color[i].rgb * spot_factor(i, L) * window * window / max(dist2, 0.01);  // lux
        float mu = dot(-L, view);
        lights += E * spray_phase_wide(mu);
        glint += E * 0.5 * spray_reflection(mu);
        lights_diffuse += E * (0.9 / SPRAY_PI) * 0.5 * (1.0 + dot(L, view));
    }
    v_lights_ss = lights;
    v_lights_diffuse = lights_diffuse;
    v_glint = glint * (mist ? 1.0 : in_misc.w);
    v_amb_iso = 0.5 * (sky_ambient(vec3(0.0, 1.0, 0.0)) + sky_ambient(vec3(0.0, -1.0, 0.0)));
}
