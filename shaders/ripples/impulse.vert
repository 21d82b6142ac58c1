#version 330 core
// One raised-cosine bump per instance (WaveSolverGPU.add_impulses_unchecked): a quad over the cells the bump
// covers, one cell wider on each side so every cell centre inside the rim gets a fragment. Cell (ix, iz) is
// the pixel whose centre is at (ix + 0.5, iz + 0.5) in the n×n state target.
in vec4 in_bump;     // x, z of the centre and the radius, in cells (cell centres at integers); peak, metres
uniform int u_n;     // cells per side
flat out vec4 v_bump;

void main() {
    vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1)) * 2.0 - 1.0;  // strip order
    vec2 cells = in_bump.xy + 0.5 + corner * (in_bump.z + 1.0);
    v_bump = in_bump;
    gl_Position = vec4(cells / float(u_n) * 2.0 - 1.0, 0.0, 1.0);
}
