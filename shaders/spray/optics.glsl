// Scattering by water drops much larger than the wavelength, per unit extinction (1/sr): half diffraction
// (a narrow forward lobe), half geometric: refraction (a forward Henyey–Greenstein lobe) and external reflection
// F(i)/(4π), i = (π − θ)/2. The GLSL twin of rain_core.effects.spray.optics.phase_function; the constants come
// from Python as #defines (SPRAY_G_DIFFRACTION, SPRAY_G_REFRACTION, SPRAY_REFLECTION_SHARE, SPRAY_WATER_IOR).
const float SPRAY_PI = 3.14159265358979;

float spray_hg(float mu, float g) {
    float d = 1.0 + g * g - 2.0 * g * mu;
    return (1.0 - g * g) / (4.0 * SPRAY_PI * d * sqrt(d));
}

float spray_fresnel(float cos_i) {
    float n = SPRAY_WATER_IOR;
    float ci = clamp(cos_i, 0.0, 1.0);
    float ct = sqrt(max(1.0 - (1.0 - ci * ci) / (n * n), 0.0));
    float rs = (ci - n * ct) / (ci + n * ct);
    float rp = (n * ci - ct) / (n * ci + ct);
    return 0.5 * (rs * rs + rp * rp);
}

// External reflection per unit geometric cross-section and steradian.
float spray_reflection(float mu) {
    return spray_fresnel(sqrt(clamp(0.5 * (1.0 - mu), 0.0, 1.0))) / (4.0 * SPRAY_PI);
}

// Refraction: the smooth wide-angle part. The diffracted half of the extinction leaves within ~λ/D (< 1°) of
// the beam, so it only matters looking straight at a light (the atmosphere effect's glow draws that); the
// particles' lighting leaves it out rather than smear it over a whole parcel from the parcel's centre.
float spray_phase_wide(float mu) {
    return 0.5 * (1.0 - SPRAY_REFLECTION_SHARE) * spray_hg(mu, SPRAY_G_REFRACTION);
}

// The whole phase function (normalised); glint scales the reflection lobe (1 = its mean).
float spray_phase(float mu, float glint) {
    return 0.5 * spray_hg(mu, SPRAY_G_DIFFRACTION) + spray_phase_wide(mu) + 0.5 * glint * spray_reflection(mu);
}

// What a point light (sun, lamp) of illuminance E adds to the radiance of drops per unit of their opacity
// (1/sr; × E gives cd/m²): refraction's wide lobe and the Fresnel reflection, the diffracted half left out
// (see spray_phase_wide). The GLSL twin of rain_core.effects.spray.optics.light_lobe.
float spray_light_lobe(float mu) {
    return spray_phase_wide(mu) + 0.5 * spray_reflection(mu);
}
