// Analytic sky (cd/m²): a zenith–horizon gradient, a glow around the sun, the sun disk, a dark ground below.
// The sun and sky (u_sun_dir, u_sun_illum, u_sky_zenith, u_sky_horizon, u_ground_albedo) are frame-block members.
#include "common/frame.glsl"

vec3 sky_radiance(vec3 dir, bool with_sun) {
    float up = dir.y;
    vec3 sky;
    if (up >= 0.0) {
        float t = pow(clamp(1.0 - up, 0.0, 1.0), 3.0);  // a normalised dir.y may round above 1: pow(<0) is NaN
        sky = mix(u_sky_zenith, u_sky_horizon, t);
    } else {
        // Below the horizon: the lit ground (Lambert, sun + sky), fading in from the horizon colour.
        vec3 ground = u_ground_albedo / 3.14159265 * (u_sun_illum * max(u_sun_dir.y, 0.0)
                                                      + 3.14159265 * 0.5 * (u_sky_zenith + u_sky_horizon));
        sky = mix(u_sky_horizon, ground, clamp(-up * 8.0, 0.0, 1.0));
    }
    float mu = dot(dir, u_sun_dir);
    // Forward-scattering aureole around the sun; ~1% of the sun's light spread over a few degrees.
    sky += u_sun_illum * 0.02 * pow(max(mu, 0.0), 64.0) * float(up > -0.02);
    if (with_sun && mu > 0.99996) sky += u_sun_illum / 6.8e-5 * 0.02;  // disk (dimmed: no bloom to spread it)
    return sky;
}

// Mean sky radiance seen by a surface with normal N (cheap hemispherical irradiance / π).
vec3 sky_ambient(vec3 N) {
    vec3 sky_mean = 0.5 * (u_sky_zenith + u_sky_horizon);
    vec3 ground = u_ground_albedo / 3.14159265 * (u_sun_illum * max(u_sun_dir.y, 0.0) + 3.14159265 * sky_mean);
    return mix(ground, mix(u_sky_horizon, sky_mean, 0.6), 0.5 + 0.5 * N.y);
}
