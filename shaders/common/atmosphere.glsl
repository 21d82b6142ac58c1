// Aerial perspective: transmittance exp(−β·d) with in-scattered airlight (rain_core/effects/atmosphere/model.py
// has the NumPy twins — transmittance, phase_hg, phase_rain, airlight — and the model with its sources).
// Clear air: a clear-day β and the horizon sky's colour (the renderer's clear_air_uniforms). The atmosphere
// effect (its frame_uniforms) raises β with the rain rate and the haze, makes the airlight rain-grey, and adds
// the sun's forward-peaked share. Its extra terms are 0 when it is off, and then every function below equals
// plain apply_atmosphere.
// β, the airlights and the phase lobes are members of the frame block:
#include "common/frame.glsl"

// Height of the scattering layer (m): the sky is seen through this much rain/haze straight up.
const float ATMOSPHERE_LAYER_M = 1000.0;

vec3 apply_atmosphere(vec3 radiance, float distance_m) {
    float t = exp(-u_extinction_per_m * distance_m);
    return radiance * t + u_airlight * (1.0 - t);
}

// Henyey–Greenstein phase function (1/sr); mu = cos of the scattering angle (1 = straight on).
float atmosphere_phase(float mu, float g) {
    float d = 1.0 + g * g - 2.0 * g * mu;
    return (1.0 - g * g) / (12.566370614 * d * sqrt(d));
}

// The medium's phase function (1/sr): a forward lobe plus a weak backward one (two-term Henyey–Greenstein).
float atmosphere_phase_medium(float mu) {
    return mix(atmosphere_phase(mu, u_phase_g), atmosphere_phase(mu, u_phase_back_g), u_phase_back_weight);
}

// Airlight seen along view_dir (unit, from the eye outwards): isotropic part + sunlight scattered towards the eye.
vec3 atmosphere_airlight(vec3 view_dir) {
    return u_airlight + u_airlight_sun * atmosphere_phase_medium(dot(view_dir, u_airlight_sun_dir));
}

// A surface distance_m away along view_dir (unit, eye → surface).
vec3 apply_atmosphere_dir(vec3 radiance, float distance_m, vec3 view_dir) {
    float t = exp(-u_extinction_per_m * distance_m);
    return radiance * t + atmosphere_airlight(view_dir) * (1.0 - t);
}

// Path (m) through the scattering layer towards the sky along view_dir; "infinite" at and below the horizon.
float atmosphere_sky_path_m(vec3 view_dir) {
    return ATMOSPHERE_LAYER_M / max(view_dir.y, 1e-3);
}

// The sky behind the rain: the analytic sky already holds the clear air, so only the medium's β acts here.
vec3 apply_sky_atmosphere(vec3 radiance, vec3 view_dir) {
    float t = exp(-u_medium_extinction_per_m * atmosphere_sky_path_m(view_dir));
    return radiance * t + atmosphere_airlight(view_dir) * (1.0 - t);
}
