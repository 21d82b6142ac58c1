// Seeing through water on the windshield: the street behind the glass (the frame drawn so far), looked up along
// a view ray refracted into the water through the flat glass and out through the water's surface; total internal
// reflection and the Fresnel reflection at that surface show the dark cabin; glints of the sun and the lights.
// Shared by the glass pass (film, beads, blades) and the drop pass (each drop an analytic lens).
// Include after common/frame.glsl, common/lighting.glsl, common/atmosphere.glsl and windshield/glass_common.glsl.
#include "common/view_distance.glsl"
uniform sampler2D u_frame;    // the frame without the glass (pre-exposed HDR), mipmapped
uniform sampler2D u_depth;    // its depth
uniform vec2 u_near_far;      // camera near, far (m)
uniform float u_cabin_depth;  // m: what the frame shows nearer than this is the cabin, not the street
uniform vec3 u_axis_s;        // world direction of +s (the car's right)
uniform vec3 u_axis_t;        // world direction of +t (up the glass)
uniform float u_refraction;   // × the physical bending
uniform vec3 u_cabin;         // luminance seen by (total) internal reflection (the dark cabin), pre-exposed

const float N_WATER = 1.333;

vec2 screen_of(vec3 origin, vec3 dir) {
    vec4 clip = u_view_proj * vec4(origin + dir * 50.0, 1.0);
    if (clip.w <= 1e-4) return vec2(-1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}

float view_depth(vec2 uv) {
    return view_distance(textureLod(u_depth, uv, 0.0).r, u_near_far);
}

// What a ray leaving the glass at origin along dir sees: the frame where it shows the street, else (off screen,
// or where the frame shows the cabin in front of the glass) the sky and the lit ground through the rain.
vec3 behind_glass(vec3 origin, vec3 dir, float lod) {
    vec3 sky = apply_sky_atmosphere(sky_radiance(dir, false), dir) * u_exposure;
    vec2 uv = screen_of(origin, dir);
    vec2 edge = min(uv, 1.0 - uv);
    float on_screen = smoothstep(0.0, 0.02, min(edge.x, edge.y));
    if (on_screen <= 0.0) return sky;
    float street = on_screen * smoothstep(0.8, 1.0, view_depth(uv) / u_cabin_depth);
    return mix(sky, textureLod(u_frame, uv, lod).rgb, street);
}

// Glints: lights seen through the water along the refracted ray (a narrow lobe around each light's direction).
vec3 glints(vec3 origin, vec3 dir) {
    vec3 sum = u_sun_illum * 0.3 * pow(max(dot(dir, u_sun_dir), 0.0), 3000.0) * 3001.0 / 6.2832;
    for (uint m = light_mask(); m != 0u;) {
        int i = pop_bit(m);
        vec3 L, E;
        if (!light_at(i, origin, L, E)) continue;
        float c = dot(dir, L);
        if (c >= 0.99) sum += E * pow(c, 600.0) * 601.0 / 6.2832;
    }
    return sum;
}

// The glints along a tap's ray out of the water (ray.xyz), exposed and weighted by its transmittance (ray.w); none
// where the ray turned back (w = 0). Taken once a fragment, after its taps' loop: in the loop llvmpipe would run the
// lights' loop masked at every tap.
vec3 exposed_glints(vec3 origin, vec4 ray) {
    return ray.w > 0.0 ? glints(origin, ray.xyz) * u_exposure * ray.w : vec3(0.0);
}

// The glass's tangent frame at a point: outward normal N (away from the eye along V), Ts along +s, Tt along +t.
void glass_frame(vec3 V, vec3 n_geom, out vec3 N, out vec3 Ts, out vec3 Tt) {
    N = normalize(n_geom);
    if (dot(N, V) < 0.0) N = -N;
    Ts = normalize(u_axis_s - N * dot(N, u_axis_s));
    Tt = normalize(cross(N, Ts));
    if (dot(Tt, u_axis_t) < 0.0) Tt = -Tt;
}

// The view ray V in the water on the glass, whose outward normal is N: what through_water takes (made once per
// fragment: the taps of a fragment share it).
vec3 water_ray(vec3 V, vec3 N) {
    return refract(V, -N, 1.0 / N_WATER);
}

// Through water whose outer surface has slope (d height / ds, d height / dt): the refracted lookup of the frame
// behind, less the Fresnel reflection at the water–air surface, which shows the cabin instead (all of it past
// the critical angle). Returns the colour; out_dir is the ray leaving the water (zero where it is reflected) and
// transmit the Fresnel transmittance. in_water: the view ray refracted into the water through the glass
// (water_ray).
vec3 through_water(vec3 origin, vec3 in_water, vec3 N, vec3 Ts, vec3 Tt, vec2 slope, float lod,
                   out vec3 out_dir, out float transmit) {
    vec3 Nw = normalize(N - u_refraction * (slope.x * Ts + slope.y * Tt));
    out_dir = refract(in_water, -Nw, N_WATER);
    if (dot(out_dir, out_dir) < 0.5) {
        out_dir = vec3(0.0);
        transmit = 0.0;
        return u_cabin;  // total internal reflection: the ray turns back into the dark cabin
    }
    float cosx = abs(dot(out_dir, Nw));
    transmit = 1.0 - (0.02 + 0.98 * pow(1.0 - cosx, 5.0));
    return behind_glass(origin, out_dir, lod) * transmit + u_cabin * (1.0 - transmit);
}

// Five taps over a disc (unit radius): the eye's pupil or the pixel's footprint on the glass.
const vec2 DISC_TAPS[5] = vec2[5](vec2(0.0), vec2(0.7, 0.25), vec2(-0.25, 0.7), vec2(-0.7, -0.25),
                                  vec2(0.25, -0.7));

// Share of a disc of radius b (the pupil's blur disc on the glass, m) whose centre lies at distance r (m) from
// the centre of a disc of radius a (a drop) that the drop covers: their overlap area over π b².
float disc_overlap(float r, float a, float b) {
    if (r >= a + b) return 0.0;
    if (r <= abs(a - b)) return a < b ? (a * a) / (b * b) : 1.0;
    float ca = clamp((r * r + a * a - b * b) / (2.0 * r * a), -1.0, 1.0);
    float cb = clamp((r * r + b * b - a * a) / (2.0 * r * b), -1.0, 1.0);
    float alpha = acos(ca), beta = acos(cb);
    float area = a * a * (alpha - ca * sqrt(1.0 - ca * ca)) + b * b * (beta - cb * sqrt(1.0 - cb * cb));
    return area / (3.14159265 * b * b);
}
