// The light a spray parcel sends to the eye, per unit of its opacity (cd/m², before the atmosphere): water drops
// scatter, they do not glow. Per unit extinction half the light is diffracted straight on and half is refracted
// through the drop, both showing the environment behind the drop over a wide field (a drop is a fish-eye of
// ~165°, Garg & Nayar) — so a drop looks like the mean of what lies behind it, dark road and bright sky mixed,
// never whiter than the sky; the Fresnel reflection (the share SPRAY_REFLECTION_SHARE of the geometric half)
// mirrors the hemisphere behind the eye. Point lights (sun, lamps, headlights) add their forward-peaked lobe
// (spray_light_lobe): backlit spray glows, spray in front of the sun's back stays grey.
// rain_core.effects.spray.optics.radiance_bound is the NumPy bound tests/effects/spray/test_look.py holds it to.
#include "common/frame.glsl"
#include "common/sky.glsl"
#include "common/lighting.glsl"
#include "spray/optics.glsl"

// Environment seen through and on the drops (view: unit, parcel → eye).
vec3 spray_environment(vec3 view) {
    float r = 0.5 * SPRAY_REFLECTION_SHARE;
    return (1.0 - r) * sky_ambient(-view) + r * sky_ambient(view);
}

// Sun and lights scattered towards the eye by drops at pos (lux × 1/sr).
vec3 spray_point_lights(vec3 pos, vec3 view) {
    vec3 light = u_sun_illum * spray_light_lobe(dot(-u_sun_dir, view));
    for (int i = 0; i < u_light_count; ++i) {
        vec3 L, E;
        if (light_at(i, pos, L, E)) light += E * spray_light_lobe(dot(-L, view));
    }
    return light;
}

vec3 spray_radiance(vec3 pos, vec3 view) {
    return spray_environment(view) + spray_point_lights(pos, view);
}
