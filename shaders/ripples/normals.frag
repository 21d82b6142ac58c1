#version 330 core
// Height (R channel, metres) -> slopes RG = (dh/dx, dh/dz), central differences, clamped at the window edge.
// The road blends these onto its water normal: n = normalize(vec3(-dh/dx, 1, -dh/dz)) in world axes.
uniform sampler2D u_height;
uniform float u_inv_2h;  // 1 / (2 * cell size in metres)
out vec2 f_slope;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 hi = textureSize(u_height, 0) - 1;
    float xp = texelFetch(u_height, clamp(p + ivec2(1, 0), ivec2(0), hi), 0).r;
    float xm = texelFetch(u_height, clamp(p - ivec2(1, 0), ivec2(0), hi), 0).r;
    float zp = texelFetch(u_height, clamp(p + ivec2(0, 1), ivec2(0), hi), 0).r;
    float zm = texelFetch(u_height, clamp(p - ivec2(0, 1), ivec2(0), hi), 0).r;
    f_slope = vec2(xp - xm, zp - zm) * u_inv_2h;
}
