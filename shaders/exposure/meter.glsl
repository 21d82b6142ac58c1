// The exposure meter's constants: keep in sync with rain_core/exposure.py (tests/gfx/test_exposure.py checks).
const vec2 METER_CENTRE = vec2(0.5, 0.45);
const vec2 METER_SIGMA = vec2(0.3, 0.25);
const float LOG2_FLOOR = -20.0;
const float METER_KEY = 0.6 * 12.5 / (1.2 * 100.0);
const vec2 RANGE_EV = vec2(-3.0, 3.0);
