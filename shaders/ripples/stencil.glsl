// Shared by the ripple passes (rain_core/ripples.py): the (current, previous) height texture and the cells
// held at rest. Held cells (the fixed grid edges, and dry cells where the water film depth is zero) always
// store 0, so the plain 4-neighbour sum already treats them as fixed (Dirichlet) cells.
uniform sampler2D u_state;  // RG32F: (z current, z previous) in metres; row = z cell, column = x cell
uniform sampler2D u_mask;   // R8: 1 where the film holds water, 0 where the cell is held at rest
uniform int u_n;            // cells per side, edges included

bool ripples_held(ivec2 p) {
    return p.x <= 0 || p.y <= 0 || p.x >= u_n - 1 || p.y >= u_n - 1 || texelFetch(u_mask, p, 0).r < 0.5;
}

vec2 ripples_state(ivec2 p) {
    return texelFetch(u_state, p, 0).rg;
}

// Sum of the current heights of the 4 neighbours (only called for interior cells, so all are in range).
float ripples_neighbours(ivec2 p) {
    return texelFetch(u_state, p + ivec2(1, 0), 0).r + texelFetch(u_state, p - ivec2(1, 0), 0).r
         + texelFetch(u_state, p + ivec2(0, 1), 0).r + texelFetch(u_state, p - ivec2(0, 1), 0).r;
}
