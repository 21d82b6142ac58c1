#version 330 core
// Glow, step 2: one direction of a separable Gaussian blur (normalised discrete weights, edges clamped). Alpha
// (glow_down's least kept light of the block) is carried through unblurred.
uniform sampler2D u_src;
uniform ivec2 u_step;      // (1, 0) horizontal, (0, 1) vertical
uniform float u_sigma_px;  // standard deviation in texels of this target
uniform int u_radius;      // taps each side (≈ 3σ)
out vec4 f_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 hi = textureSize(u_src, 0) - 1;
    float inv2s2 = 0.5 / max(u_sigma_px * u_sigma_px, 1e-6);
    vec3 sum = vec3(0.0);
    float wsum = 0.0;
    for (int k = -u_radius; k <= u_radius; ++k) {
        float w = exp(-float(k * k) * inv2s2);
        sum += w * texelFetch(u_src, clamp(p + k * u_step, ivec2(0), hi), 0).rgb;
        wsum += w;
    }
    f_color = vec4(sum / wsum, texelFetch(u_src, p, 0).a);
}
