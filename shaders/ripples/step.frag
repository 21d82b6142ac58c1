#version 330 core
// Wave-equation passes over the (current, previous) height texture, one variant per define
// (the maths and its derivation are in rain_core/ripples.py):
//   (none)          one leapfrog step with centred damping: z+ = z + a(z - z-) + k(sum4 - 4z)
//   RIPPLES_RETIME  change the sub-step dt, keeping the synchronous velocity (scaled by the energy guard)
//   RIPPLES_REDUCE  per-block sums (u^2, z*Az, (Az)^2) for the discrete energy and the retime guard
//   RIPPLES_SHIFT   scroll the window by whole cells (cells that enter are at rest), or apply a new mask
//   RIPPLES_MASK_SHIFT  scroll the water mask itself (cells that enter count as water until told otherwise)
#include "ripples/stencil.glsl"

#if defined(RIPPLES_RETIME) || defined(RIPPLES_REDUCE)
uniform float u_dt_old;   // s, sub-step of the stored state; 0 when the state is synchronous and at rest
uniform float u_s2;       // m^2/s^2, wave speed squared
uniform float u_inv_h2;   // 1/m^2

// A z = -(discrete Laplacian) z, in 1/m, and the synchronous velocity u = v - (dt/2) s^2 A z, in m/s.
void ripples_sync(ivec2 p, out float z, out float az, out float u) {
    vec2 s = ripples_state(p);
    z = s.x;
    az = (4.0 * s.x - ripples_neighbours(p)) * u_inv_h2;
    u = u_dt_old > 0.0 ? (s.x - s.y) / u_dt_old - 0.5 * u_dt_old * u_s2 * az : 0.0;
}
#endif

#if defined(RIPPLES_MASK_SHIFT)
uniform ivec2 u_shift;    // cells: new(p) = old(p + shift)
out float f_out;          // R8 target: exactly 0 or 1, as uploaded
void main() {
    ivec2 q = ivec2(gl_FragCoord.xy) + u_shift;
    bool inside = all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(u_n)));
    f_out = inside ? texelFetch(u_mask, q, 0).r : 1.0;
}

#elif defined(RIPPLES_REDUCE)
out vec4 f_out;
void main() {
    ivec2 base = ivec2(gl_FragCoord.xy) * RIPPLES_BLOCK;
    vec3 acc = vec3(0.0);
    for (int j = 0; j < RIPPLES_BLOCK; ++j) {
        for (int i = 0; i < RIPPLES_BLOCK; ++i) {
            ivec2 p = base + ivec2(i, j);
            if (p.x >= u_n || p.y >= u_n || ripples_held(p)) continue;
            float z, az, u;
            ripples_sync(p, z, az, u);
            acc += vec3(u * u, z * az, az * az);
        }
    }
    f_out = vec4(acc, 0.0);
}

#elif defined(RIPPLES_RETIME)
uniform float u_dt_new;   // s
uniform float u_lambda;   // energy guard: scale of the synchronous velocity
uniform float u_mu;       // energy guard: scale of the height (1 unless the velocity alone cannot pay)
out vec2 f_out;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (ripples_held(p)) { f_out = vec2(0.0); return; }
    float z, az, u;
    ripples_sync(p, z, az, u);
    float z1 = u_mu * z;
    float v1 = u_lambda * u + u_mu * 0.5 * u_dt_new * u_s2 * az;
    f_out = vec2(z1, z1 - u_dt_new * v1);
}

#elif defined(RIPPLES_SHIFT)
uniform ivec2 u_shift;    // cells: new(p) = old(p + shift)
out vec2 f_out;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 q = p + u_shift;
    // Held cells of the new window (edges, dry cells of the mask already uploaded for it) stay at 0; with a
    // zero shift this pass just applies a new mask.
    bool inside = all(greaterThan(q, ivec2(0))) && all(lessThan(q, ivec2(u_n - 1))) && !ripples_held(p);
    f_out = inside ? ripples_state(q) : vec2(0.0);
}

#else
uniform float u_alpha;    // per-step velocity factor e^(-2 gamma dt)
uniform float u_k;        // (1 + alpha)/2 * C^2
out vec2 f_out;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (ripples_held(p)) { f_out = vec2(0.0); return; }
    vec2 s = ripples_state(p);
    float z_new = s.x + u_alpha * (s.x - s.y) + u_k * (ripples_neighbours(p) - 4.0 * s.x);
    f_out = vec2(z_new, s.x);
}
#endif
