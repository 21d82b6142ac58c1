#version 330 core
// Spray parcels: a Gaussian cloud of drops (optical depth tau), blended premultiplied over the HDR frame.
// Thin parts scatter singly (forward-peaked: they glow towards the sun and in headlight beams); dense parts,
// near the tyre, shade like a white body with a pseudo-normal, which gives them their roundness. The scene's
// depth (read as a texture: the pass writes through a colour-only framebuffer) hides parcels behind geometry
// and fades them softly where they meet it.
#include "common/frame.glsl"
#include "common/sky.glsl"
#include "common/atmosphere.glsl"

uniform sampler2D u_depth;
uniform vec2 u_viewport;
uniform float u_near;
uniform float u_far;

in vec2 v_coord;
in float v_view_depth;
flat in vec4 v_shape;
flat in float v_fade;
flat in vec4 v_misc;
flat in vec3 v_axis_a;
flat in vec3 v_axis_b;
flat in vec3 v_view;
flat in vec3 v_sun_ss;
flat in vec3 v_lights_ss;
flat in vec3 v_lights_diffuse;
flat in vec3 v_glint;
flat in vec3 v_amb_iso;
flat in float v_pixel_m;
out vec4 f_color;

const float PI_S = 3.14159265358979;

float linear_depth(float d) {
    float z = d * 2.0 - 1.0;
    return 2.0 * u_near * u_far / (u_far + u_near - z * (u_far - u_near));
}

float hash12(vec2 p) {
    vec3 p3 = fract(vec3(p.xyx) * 0.1031);
    p3 += dot(p3, p3.yzx + 33.33);
    return fract((p3.x + p3.y) * p3.z);
}

void main() {
    float half_len = v_shape.x;
    vec2 sigma2 = v_shape.yz;
    float sigma = v_shape.z;  // across: the smaller size, for the depth fade
    bool mist = v_misc.x > 0.5;
    float along = max(abs(v_coord.x) - half_len, 0.0);
    vec2 r = vec2(along, v_coord.y) / sigma2;
    float r2 = dot(r, r);
    float edge = mist ? 2.5 : 3.0;
    float cut = exp(-0.5 * edge * edge);
    float density = max(exp(-0.5 * r2) - cut, 0.0) / (1.0 - cut);
    float tau = v_shape.w * density;

    // Depth: behind the scene → hidden; close in front of it → faded over about a sigma.
    float scene = linear_depth(texture(u_depth, gl_FragCoord.xy / u_viewport).r);
    float soft = clamp((scene - v_view_depth) / max(sigma * (mist ? 0.7 : 1.0), 0.02), 0.0, 1.0);
    float near = mist ? clamp((v_view_depth - 0.3) / 1.7, 0.0, 1.0) : clamp((v_view_depth - 0.05) / 0.25, 0.0, 1.0);
    float alpha = (1.0 - exp(-tau)) * v_fade * soft * near;
    if (alpha < 1.0 / 1024.0) discard;

    // Pseudo-normal of a fuzzy sphere (stretched along the streak).
    vec2 q = r / edge;
    q.x *= sign(v_coord.x);
    vec3 n = normalize(q.x * v_axis_a + q.y * v_axis_b + sqrt(max(1.0 - dot(q, q), 0.0)) * v_view);
    // Multiple-scattering weight: where the cloud is optically thick it shades like a white body.
    float m = 1.0 - exp(-0.5 * tau);
    // Wrapped diffuse: light scattered many times inside the cloud also reaches its far side.
    float wrap = max((dot(n, u_sun_dir) + 0.6) / 1.6, 0.0);
    vec3 sun = mix(v_sun_ss, u_sun_illum * wrap * (0.9 / PI_S), m);
    vec3 amb = mix(v_amb_iso, sky_ambient(n) * 0.9, m);
    vec3 lights = mix(v_lights_ss, v_lights_diffuse, m);
    // Glints: the reflection lobe gathered into a few sparkle cells (mean 1), for the splash drops.
    float sparkle = 1.0;
    if (!mist) {
        vec2 cell = floor(v_coord / max(0.6 * sigma, 1.5 * v_pixel_m));
        sparkle = hash12(cell + v_misc.y * 517.0) < SPRAY_GLINT_CHANCE ? 1.0 / SPRAY_GLINT_CHANCE : 0.0;
    }
    vec3 radiance = sun + amb + lights + v_glint * sparkle;
    radiance = apply_atmosphere_dir(radiance, v_misc.z, -v_view);  // as the scene: u_airlight_sun etc. where set
    f_color = vec4(radiance * u_exposure * alpha, alpha);
}
