// Standing water and the wet film on the road: the GLSL twin of rain_core/water_film.py (water_depths_mm,
// film_depth_mm). Keep the constants equal to the Python ones (tests/effects/road/test_film.py compares them).
// Positions are in the renderer's wrapped frame (world z − shift_z, a multiple of the period): every map is
// periodic in 1200 m along z, so the wrapped and world frames give the same water.
uniform sampler2D u_road_height;  // units.ROAD_HEIGHT: heightmap R (0 lowest), G smoothed (no cracks); clamp x, wrap z
uniform sampler2D u_road_maps;    // units.ROAD_MAPS: R puddle noise (uniform in 0..1), G shelter (1 under a roof)
uniform vec4 u_road_levels;       // wetness, crack level (cracks·CRACK_LEVEL), puddle level L, gutter k (m^⅝)
uniform vec2 u_road_height_extent;  // m: heightmap size across x, along z (14, 48)

const float ROAD_HALF_WIDTH_M = 7.0;
const float ROAD_PERIOD_M = 1200.0;
const float WET_FILM_MM = 0.2;
const float CRACK_MAX_MM = 3.0;
const float CRACK_DEPTH_SPAN = 0.2;
const float PUDDLE_MAX_MM = 10.0;
const float PUDDLE_NOISE_WEIGHT = 0.45;
const float PUDDLE_DEPTH_SPAN = 0.35;
const float MACROTEXTURE_MM = 2.0;

// (height01, smoothed height01) at xz (m).
vec2 road_height01(vec2 xz) {
    vec2 uv = vec2((xz.x + 0.5 * u_road_height_extent.x) / u_road_height_extent.x, xz.y / u_road_height_extent.y);
    return texture(u_road_height, uv).rg;
}

// (puddle noise, shelter) at xz (m).
vec2 road_maps(vec2 xz) {
    vec2 uv = vec2((xz.x + ROAD_HALF_WIDTH_M) / (2.0 * ROAD_HALF_WIDTH_M), xz.y / ROAD_PERIOD_M);
    return texture(u_road_maps, uv).rg;
}

// Kerb streams (rain_core/gutter.py): HEC-22 gutter flow, spread T = k·L^(3/8) from the inlet upstream, depth
// S_x·(T − s) at distance s from the kerb face, in mm.
const float GUTTER_CROSS_SLOPE = 0.02;
const float GUTTER_INLET_SPACING_M = 50.0;
const float GUTTER_MAX_MM = 40.0;
// The stream's spread T (m) at xz: k·L^(3/8), L the distance from the inlet upstream; 0 without streams.
float road_gutter_spread_m(vec2 xz) {
    if (u_road_levels.w <= 0.0) return 0.0;
    float offset = xz.x >= 0.0 ? 0.0 : 25.0;
    float upstream = GUTTER_INLET_SPACING_M - mod(xz.y - offset, GUTTER_INLET_SPACING_M);
    return u_road_levels.w * pow(upstream, 0.375);
}

float road_gutter_depth_mm(vec2 xz) {
    float s = ROAD_HALF_WIDTH_M - abs(xz.x);
    return min(GUTTER_CROSS_SLOPE * max(road_gutter_spread_m(xz) - s, 0.0) * 1000.0, GUTTER_MAX_MM);
}

// Mean speed (m/s) of the stream at xz, Manning's for the triangular gutter (HEC-22 eq. 4-5, SI):
// V = (0.752 / n)·S_L^½·S_x^⅔·T^⅔ with n = 0.016 and S_L = 0.005 (rain_core/gutter.py).
float road_gutter_speed_m_s(vec2 xz) {
    return 0.752 / 0.016 * sqrt(0.005) * pow(GUTTER_CROSS_SLOPE, 2.0 / 3.0) * pow(road_gutter_spread_m(xz), 2.0 / 3.0);
}

// (standing water in cracks and puddles, wet film) depths in mm at xz (m) on the road; 0 off the asphalt.
vec2 road_water_depths_mm(vec2 xz) {
    if (abs(xz.x) > ROAD_HALF_WIDTH_M) return vec2(0.0);
    vec2 h = road_height01(xz);
    vec2 maps = road_maps(xz);
    float crack = CRACK_MAX_MM * clamp((u_road_levels.y - h.x) / CRACK_DEPTH_SPAN, 0.0, 1.0);
    float ground = (1.0 - PUDDLE_NOISE_WEIGHT) * h.y + PUDDLE_NOISE_WEIGHT * maps.r;
    float puddle = PUDDLE_MAX_MM * clamp((u_road_levels.z - ground) / PUDDLE_DEPTH_SPAN, 0.0, 1.0);
    float dry = 1.0 - maps.g;
    return vec2(max(max(crack, puddle) * dry, road_gutter_depth_mm(xz)), WET_FILM_MM * u_road_levels.x * dry);
}

// Water film depth (mm, ≤ 10): what the ripples and the spray read.
float road_film_depth_mm(vec2 xz) {
    vec2 d = road_water_depths_mm(xz);
    return max(d.x, d.y);
}
