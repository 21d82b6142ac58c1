// Rainfall (rain_core/effects/rainfall/): what a falling drop looks like.
// A drop is a tiny fish-eye lens: it refracts a ~165° field of view behind it and reflects the rest of the sky
// (Garg & Nayar 2004, 2007; rainfall/env.frag sums the three orders with their Fresnel weights, optics.py), so it
// is usually brighter than what it covers. On top of that it scatters the sun, street lamps
// and headlights towards the eye; for a drop of radius r lit with illuminance E the scattered intensity is
// E·πr²·p(θ)/4π, i.e. luminance E·p(θ)/4π over its disc. p: two-term Henyey–Greenstein, the same as the
// atmosphere effect's (forward lobe g = 0.7, back lobe g = −0.5 weighted so p(180°)/4π = 1/18.8 sr).
// The effect passes only the lights that reach its boxes (effect.py _lights), as members of its per-frame block
// (rain_frame.glsl: written with the rest, once a frame). FRAME_OWN_LIGHTS keeps the frame's list out of the frame
// block.
#define FRAME_OWN_LIGHTS
#include "common/frame.glsl"
#include "rainfall/rain_frame.glsl"
#include "common/lighting.glsl"
#include "common/atmosphere.glsl"

const float RAIN_INV_4PI = 0.0795774715;
const float RAIN_PHASE_G = 0.7;
const float RAIN_PHASE_BACK_G = -0.5;
const float RAIN_PHASE_BACK_WEIGHT = 0.0957;

uniform vec2 u_viewport;      // px
uniform float u_focal_px;     // px per unit of tan(angle) vertically
uniform float u_brightness;   // streak_brightness setting

float rain_hg(float g, float c) {
    float d = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (d * sqrt(d));
}

// Phase function normalised to 4π (∫ p dΩ = 4π); cos_theta between the light's travel and the view direction.
float rain_phase(float cos_theta) {
    return (1.0 - RAIN_PHASE_BACK_WEIGHT) * rain_hg(RAIN_PHASE_G, cos_theta)
           + RAIN_PHASE_BACK_WEIGHT * rain_hg(RAIN_PHASE_BACK_G, cos_theta);
}

uniform sampler2D u_rain_env;  // rainfall/env.frag: a drop's luminance (cd/m²), by view direction

// Luminance (cd/m²) of a drop seen along d (eye → drop) from the sky and the ground (rainfall/env.frag).
vec3 rain_environment(vec3 d) {
    float u = fract(atan(d.z, d.x) * 0.15915494);  // φ / 2π in [0, 1)
    float v = acos(clamp(d.y, -1.0, 1.0)) * 0.31830989;  // θ / π
    return textureLod(u_rain_env, vec2(u, v), 0.0).rgb;
}

// Luminance (cd/m²) of a drop at p (wrapped frame) seen along to_eye (unit, from the drop to the camera). The
// rainfall effect passes only the lights that can reach its container (RainFrame's).
vec3 rain_drop_radiance(vec3 p, vec3 to_eye) {
    vec3 L = rain_environment(-to_eye);
    L += u_sun_illum * rain_phase(dot(-u_sun_dir, to_eye)) * RAIN_INV_4PI;
    for (int i = 0; i < u_light_count; ++i) {
        vec3 Ld, E;
        if (light_at(i, p, Ld, E)) L += E * rain_phase(dot(-Ld, to_eye)) * RAIN_INV_4PI;
    }
    return L;
}
