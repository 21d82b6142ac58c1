#version 330 core
// The frame without the glass, copied texel for texel (colour and depth) for the glass pass to refract: a draw,
// where a blit made the main thread wait for Mesa's driver thread (moderngl's blit reads GL state back).
uniform sampler2D u_color;
uniform sampler2D u_depth;  // the frame's depth, sampled without comparison
out vec4 frag_color;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    frag_color = texelFetch(u_color, texel, 0);
    gl_FragDepth = texelFetch(u_depth, texel, 0).r;
}
