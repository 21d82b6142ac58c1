// A frame's raindrops on the ripple field, stateless (issue 13): drop `index` of the frame whose key is
// u_rain_key falls on an interior cell and a point in it, with a diameter, all from an integer hash; the
// float64 NumPy twin is rain_core/effects/ripples/raindrops.py (same hash, same integer cell and offset maths,
// the same inverse CDF and momentum table). Needs ripples/stencil.glsl (u_n, u_mask) included first.
const int DROP_CDF_NODES = 513;       // raindrops.DROP_CDF_NODES (2^9 + 1: nine halvings find the interval)
const int DROP_MOMENTUM_NODES = 4097; // raindrops.DROP_MOMENTUM_NODES

uniform uint u_rain_key;         // the frame's key: pcg(frame ^ pcg(seed ^ RAIN_SALT))
uniform float u_rain_peak;       // dent in m per kg·m/s of momentum (< 0), × the drops each one represents
uniform float u_crater_cells;    // crater radius in cells per mm of diameter
uniform vec3 u_drop_range;       // D_MIN mm, D_MAX mm, the narrowest footprint radius in cells
uniform sampler2D u_drop_law;    // R32F: row 0 the flux-weighted CDF at DROP_CDF_NODES equal diameter steps,
                                 // row 1 the momentum (kg·m/s) at DROP_MOMENTUM_NODES equal diameter steps

uint ripples_pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// 1 + floor(k·(n − 2) / 2^24) for the top 24 bits k of h, exactly in 32 bits: a cell in [1, n − 2].
int ripples_interior_cell(uint h) {
    uint k = h >> 8u;
    uint m = uint(u_n - 2);
    uint q = (k >> 12u) * m + (((k & 0xFFFu) * m) >> 12u);
    return int(q >> 12u) + 1;
}

float ripples_drop_law(int i, int row) {
    return texelFetch(u_drop_law, ivec2(i, row), 0).r;
}

// The bump of drop `index` (x, z, radius in cells — widened to u_drop_range.z with its volume kept —, peak
// in m); false (peak 0) when its centre's cell holds no water.
bool ripples_raindrop(uint index, out vec4 bump) {
    uint h0 = ripples_pcg(index ^ u_rain_key);
    uint h1 = ripples_pcg(h0);
    uint h2 = ripples_pcg(h1);
    uint h3 = ripples_pcg(h2);
    ivec2 cell = ivec2(ripples_interior_cell(h1), ripples_interior_cell(h2));
    ivec2 offset = ivec2(int(h3 & 0xFFFu), int((h3 >> 12u) & 0xFFFu)) - 2048;
    vec2 centre = vec2(cell) + vec2(offset) * (1.0 / 4096.0);  // exact in float32 below 4096 cells
    if (texelFetch(u_mask, cell, 0).r < 0.5) {
        bump = vec4(centre, 1.0, 0.0);
        return false;
    }
    // Diameter: the inverse of the piecewise-linear CDF at u (the largest node with cdf <= u, then linear).
    float u = float(h0 >> 8u) * (1.0 / 16777216.0);
    int lo = 0;
    int hi = DROP_CDF_NODES - 1;
    for (int s = 0; s < 9; ++s) {
        int mid = (lo + hi) >> 1;
        if (ripples_drop_law(mid, 0) <= u) lo = mid; else hi = mid;
    }
    float c0 = ripples_drop_law(lo, 0);
    float c1 = ripples_drop_law(lo + 1, 0);
    float t = c1 > c0 ? (u - c0) / (c1 - c0) : 0.0;
    float span = u_drop_range.y - u_drop_range.x;
    float diam = u_drop_range.x + (float(lo) + t) * (span / float(DROP_CDF_NODES - 1));
    // Momentum: the table on equal diameter steps, linear between nodes.
    float tm = (diam - u_drop_range.x) * (float(DROP_MOMENTUM_NODES - 1) / span);
    int i = min(int(tm), DROP_MOMENTUM_NODES - 2);
    float momentum = mix(ripples_drop_law(i, 1), ripples_drop_law(i + 1, 1), tm - float(i));
    float r = u_crater_cells * diam;
    float r_eff = max(r, u_drop_range.z);
    bump = vec4(centre, r_eff, u_rain_peak * momentum * (r / r_eff) * (r / r_eff));
    return true;
}
