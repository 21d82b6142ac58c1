// Distance along the eye ray from the scene's depth buffer: the post passes of the atmosphere and the rainbow.
uniform sampler2D u_depth;       // the scene's depth (window depth in [0, 1]), sampled without compare
uniform mat4 u_inv_view_proj;    // clip → wrapped world frame

// Eye ray of a pixel (unit, wrapped world frame) and the distance (m) to what it sees; far (sky) pixels get
// sky_m. pixel: integer pixel coordinates in the full-resolution frame; size: the frame size in pixels.
float atmosphere_pixel_ray(ivec2 pixel, vec2 size, vec3 eye, float sky_m, out vec3 dir, out bool sky) {
    float depth = texelFetch(u_depth, pixel, 0).r;
    vec2 ndc = (vec2(pixel) + 0.5) / size * 2.0 - 1.0;
    sky = depth >= 1.0;
    vec4 p = u_inv_view_proj * vec4(ndc, sky ? 1.0 : depth * 2.0 - 1.0, 1.0);
    vec3 d = p.xyz / p.w - eye;
    float dist = length(d);
    dir = d / max(dist, 1e-6);
    return sky ? sky_m : dist;
}
