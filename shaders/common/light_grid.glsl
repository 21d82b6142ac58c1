// The view's light grid (rain_core/gfx/light_grid.py), for fragment shaders: use_light_grid() narrows the lights
// that the loops of common/lighting.glsl visit to those whose range reaches into this pixel's tile (a light left
// out gives nothing there: the same pixels, fewer loop trips). A view without a grid (u_light_grid_px 0) keeps
// every light. Include after common/lighting.glsl.
uniform usampler2D u_light_grid;  // R32UI, a texel per tile: bit i where light i may reach

void use_light_grid() {
    if (u_light_grid_px > 0) g_light_mask = texelFetch(u_light_grid, ivec2(gl_FragCoord.xy) / u_light_grid_px, 0).r;
}
