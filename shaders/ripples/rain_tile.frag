#version 330 core
// Animated, tiling rain-ring slope map for puddles beyond the simulated window (rain_core/ripples.py,
// RainRippleTexture). Output RG = (dh/dx, dh/dz), dimensionless slopes, like ripples_normals.frag.
// Each layer is a periodic grid of cells; in every cycle of u_cycle_s a cell hosts, with probability
// u_density[layer], one ring at a random point, expanding and fading over the cycle. Cells wrap around the
// tile, and each cell's phase is random, so the tile repeats seamlessly and the rings do not pulse together.
const int MAX_LAYERS = 8;
const float RING_MAX_RADIUS = 0.6;  // cells, at the end of the cycle (keeps rings inside the 3x3 cells looked at)
const float RING_WIDTH = 0.1;       // cells, Gaussian half-width of the wave packet
const float RING_WAVELENGTH = 0.22; // cells

uniform float u_time;                 // s
uniform float u_cycle_s;              // s, life of one ring
uniform float u_density[MAX_LAYERS];  // probability that a cell of the layer hosts a ring in a cycle
uniform float u_strength;             // peak slope of a fresh ring
uniform int u_layers;
uniform uint u_seed;
uniform vec2 u_size;                  // texels of the target
out vec2 f_slope;

uint pcg(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

float rnd(ivec2 cell, int layer, uint cycle, uint salt) {
    uint h = pcg(uint(cell.x) ^ pcg(uint(cell.y) ^ pcg(uint(layer) ^ pcg(cycle ^ pcg(salt ^ u_seed)))));
    return float(h >> 8u) * (1.0 / 16777216.0);  // [0, 1)
}

void main() {
    vec2 uv = gl_FragCoord.xy / u_size;  // [0, 1) over the tile
    vec2 slope = vec2(0.0);
    for (int layer = 0; layer < u_layers && layer < MAX_LAYERS; ++layer) {
        int g = 5 + 3 * layer;  // cells per side of this layer: different scales, all tile the unit square
        vec2 pg = uv * float(g);
        ivec2 c0 = ivec2(floor(pg));
        for (int j = -1; j <= 1; ++j) {
            for (int i = -1; i <= 1; ++i) {
                ivec2 c = c0 + ivec2(i, j);
                ivec2 cw = (c + g) % g;  // wrapped cell (c >= -1): the same ring on both sides of a seam
                float t = u_time / u_cycle_s + rnd(cw, layer, 0u, 1u);
                uint cycle = uint(floor(t));
                float age = fract(t);
                if (rnd(cw, layer, cycle, 2u) >= u_density[layer]) continue;
                vec2 centre = vec2(c) + vec2(rnd(cw, layer, cycle, 3u), rnd(cw, layer, cycle, 4u));
                vec2 d = pg - centre;
                float r = length(d);
                float x = r - age * RING_MAX_RADIUS;
                float fade = (1.0 - age) * (1.0 - age);
                float s = fade * exp(-(x * x) / (RING_WIDTH * RING_WIDTH)) * sin(6.2831853 * x / RING_WAVELENGTH);
                slope += s * d / max(r, 1e-4);
            }
        }
    }
    f_slope = slope * u_strength;
}
