#version 330 core
// Height (R channel, metres) -> slopes RG = (dh/dx, dh/dz), central differences, clamped at the window edge, and
// the height itself in B (m): the road blends the slopes onto its water normal, n = normalize(vec3(-dh/dx, 1,
// -dh/dz)) in world axes, and adds the height to the standing water's depth (a tyre's trough bares the asphalt).
uniform sampler2D u_height;
uniform float u_inv_2h;  // 1 / (2 * cell size in metres)
out vec4 f_slope;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 hi = textureSize(u_height, 0) - 1;
    float xp = texelFetch(u_height, clamp(p + ivec2(1, 0), ivec2(0), hi), 0).r;
    float xm = texelFetch(u_height, clamp(p - ivec2(1, 0), ivec2(0), hi), 0).r;
    float zp = texelFetch(u_height, clamp(p + ivec2(0, 1), ivec2(0), hi), 0).r;
    float zm = texelFetch(u_height, clamp(p - ivec2(0, 1), ivec2(0), hi), 0).r;
    float h = texelFetch(u_height, clamp(p, ivec2(0), hi), 0).r;
    f_slope = vec4((xp - xm) * u_inv_2h, (zp - zm) * u_inv_2h, h, 0.0);
}
