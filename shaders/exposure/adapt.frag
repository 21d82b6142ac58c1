#version 330 core
// The eye's adaptation, one texel: the correction (stops, relative to the hour's meter) moves towards what the
// meter asks with time constant u_tau_s, exactly for any step (rain_core/exposure.py: adapt).
#include "exposure/meter.glsl"
uniform sampler2D u_meter;     // RG: mip level u_top holds (mean weight × log2 L, mean weight)
uniform sampler2D u_previous;  // R: last frame's correction (EV)
uniform int u_top;
uniform float u_dt_s;
uniform float u_tau_s;
uniform float u_compensation_ev;
uniform bool u_reset;          // no history (the first frame): take the target at once
out float f_ev;

void main() {
    vec2 m = texelFetch(u_meter, ivec2(0), u_top).rg;
    float mean_log2 = m.x / max(m.y, 1e-30);
    float target = clamp(log2(METER_KEY) - mean_log2 + u_compensation_ev, RANGE_EV.x, RANGE_EV.y);
    float previous = texelFetch(u_previous, ivec2(0), 0).r;
    if (u_reset || isnan(previous) || isinf(previous)) {
        f_ev = target;
        return;
    }
    float k = 1.0 - exp(-max(u_dt_s, 0.0) / max(u_tau_s, 1e-6));
    f_ev = previous + (target - previous) * k;
}
