// Aerial perspective: transmittance exp(−β·d) with in-scattered airlight of the horizon sky's colour.
// The atmosphere effect raises β with the rain rate and adds haze; without it, a clear-day β remains.
uniform float u_extinction_per_m;  // 1/m
uniform vec3 u_airlight;           // cd/m²

vec3 apply_atmosphere(vec3 radiance, float distance_m) {
    float t = exp(-u_extinction_per_m * distance_m);
    return radiance * t + u_airlight * (1.0 - t);
}
