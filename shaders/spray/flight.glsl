// Closed-form flight of a spray parcel: linear drag towards the drift velocity u (m/s) with time constant tau (s).
// The GLSL twin of rain_core.effects.spray.flight.flight_position / flight_velocity
// (tests/effects/spray/test_optics.py checks they agree).
// x(t) = x0 + u·t + (v0 − u)·τ·(1 − e^(−t/τ))

// τ·(1 − e^(−t/τ)), with the series near t = 0 where the subtraction would lose digits.
float spray_relax(float t, float tau) {
    float x = t / tau;
    return x < 1e-3 ? t * (1.0 - 0.5 * x) : tau * (1.0 - exp(-x));
}

vec3 spray_position(vec3 p0, vec3 v0, vec3 u, float tau, float t) {
    return p0 + u * t + (v0 - u) * spray_relax(t, tau);
}

vec3 spray_velocity(vec3 v0, vec3 u, float tau, float t) {
    return u + (v0 - u) * exp(-t / tau);
}
