// The windshield's own frame (rain_core.effects.windshield.glass.GlassGeometry): s (m) to the car's right, t (m)
// up the glass, UV u = s / width(t) + 1/2, v = t / H. Plus the procedural patterns the water texture uses.
uniform vec3 u_glass;  // width at the bottom (m), width at the top (m), height H along the glass (m)

float glass_width(float t) { return u_glass.x + (u_glass.y - u_glass.x) * t / u_glass.z; }
vec2 glass_st(vec2 uv) { float t = uv.y * u_glass.z; return vec2((uv.x - 0.5) * glass_width(t), t); }
vec2 glass_uv(vec2 st) { return vec2(st.x / glass_width(st.y) + 0.5, st.y / u_glass.z); }

// Integer hash (PCG output permutation): platform-exact, unlike sin()-based hashes.
uint ws_hash(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
float ws_rand(ivec2 p, uint seed) {
    return float(ws_hash(uint(p.x) * 1973u ^ ws_hash(uint(p.y) * 9277u ^ seed))) / 4294967295.0;
}
float ws_noise1(float x, uint seed) {
    float i = floor(x);
    float f = x - i;
    float a = ws_rand(ivec2(int(i), 0), seed), b = ws_rand(ivec2(int(i) + 1, 0), seed);
    return mix(a, b, f * f * (3.0 - 2.0 * f));
}

// Residue a wiper rubber leaves along its length: streaks (concentric arcs) of mm and cm scale, mean ≈ 1.
float wiper_streaks(float r_m, uint seed) {
    float fine = ws_noise1(r_m / 0.003, seed);
    float coarse = ws_noise1(r_m / 0.012, seed + 17u);
    return 0.2 + 1.6 * fine * fine * 1.5 * (0.5 + coarse) ;
}

// A thin film left alone pulls into micro-droplets: a speckle of ~1.5 mm cells, each a droplet, mean ≈ 1.
float bead_pattern(vec2 st) {
    vec2 g = st / 0.0015;
    ivec2 c = ivec2(floor(g));
    vec2 f = g - vec2(c);
    vec2 centre = vec2(0.2) + 0.6 * vec2(ws_rand(c, 5u), ws_rand(c, 11u));
    float r = 0.18 + 0.22 * ws_rand(c, 23u);
    float d = length(f - centre) / r;
    float cap = max(1.0 - d * d, 0.0);
    return cap * 2.0 / (3.14159265 * r * r) * 0.9 + 0.1;  // the cap holds the cell's water
}
