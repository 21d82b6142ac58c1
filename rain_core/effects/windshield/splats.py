"""The instance rows the effect splats into its water textures, built from the simulation's state (NumPy only).

Each row is 8 floats, the layout of ``shaders/windshield/splat.vert``: a segment (s0, t0, s1, t1) m on the glass,
a radius (m), an amount, a kind (0 a drop cap with its tail, 1 a line: bead or wet trail, 2 splash speckle) and
a seed. ``texel_m`` is the size of one texel of the water texture: drops smaller than a texel are drawn wider and
lower so they do not flicker between texels.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import BEAD_BINS, HEIGHT_PER_RADIUS, TRAIL_FILM_M, norm2
from rain_core.physics import RHO_WATER


def drop_splats(sim, texel_m: float) -> np.ndarray:
    """Instances (n, 8) float32 for the drop-height texture: drops as caps with tails, beads as lines (mm)."""
    n = sim.count
    beads = []
    direction = 1.0 if (sim.wipers.phase or 0.0) < 0.5 else -1.0
    for b, blade in enumerate(sim.blades):
        bead = sim.beads[b]
        if bead.any():
            bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
            w = np.minimum(np.sqrt(2.0 * bead / (RHO_WATER * bin_len) / math.pi), 0.01)
            keep = np.flatnonzero(w > 0)
            if len(keep):
                beads.append((blade, w, keep))
    # Written column by column into the float32 rows the GPU reads (one array for drops and beads: one upload, no
    # float64 (n, 8) copy, no concatenation).
    out = np.zeros((n + sum(len(k) for *_, k in beads), 8), np.float32)
    if n:
        # Only the few moving drops have a tail, the others' segment ends where it starts.
        pos, vel = sim.pos, sim.vel
        a = sim.radius()
        # Column by column: a cast into an (n, 2) block loops over its rows (~5× slower than four columns).
        s, t = pos[:, 0], pos[:, 1]
        out[:n, 0] = s
        out[:n, 1] = t
        out[:n, 2] = out[:n, 0]
        out[:n, 3] = out[:n, 1]
        a_vis = np.maximum(a, 0.75 * texel_m)
        out[:n, 4] = a_vis
        height = a * (1e3 * HEIGHT_PER_RADIUS)
        height *= a / a_vis
        out[:n, 5] = height  # a sub-texel drop: wider, lower lens
        # (vs, vt) as one complex number: one comparison a drop (the columns are strided rows of the drop array).
        moving = np.flatnonzero(vel.view(np.complex128)[:, 0] != 0.0 if vel.strides[1] == 8 else vel.any(axis=1))
        if len(moving):
            v = vel[moving]
            speed = norm2(v)
            tail = a[moving] * np.minimum(speed / 0.25, 1.5)
            out[moving, 2:4] = pos[moving] - v / np.maximum(speed, 1e-9)[:, None] * tail[:, None]
    row = n
    for blade, w, keep in beads:
        angle = float(blade.angle(sim.wipers.progress))
        bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        centres = sim.bead_bin_centres(blade, angle, ahead=direction * 0.004)[keep]
        d = np.array([math.cos(angle), math.sin(angle)]) * 0.5 * bin_len
        w = w[keep]
        w_vis = np.maximum(w, 0.75 * texel_m)
        rows = out[row : row + len(keep)]
        rows[:, 0:2] = centres - d
        rows[:, 2:4] = centres + d
        rows[:, 4] = w_vis
        rows[:, 5] = 1e3 * w * (w / w_vis)
        rows[:, 6] = 1.0
        row += len(keep)
    return out


def film_splats(sim, texel_m: float) -> np.ndarray:
    """Instances (n, 8) float32 added to the film texture (µm): wet trail lines (which also stamp the beads a
    sliding drop leaves behind) and splash speckle."""
    trails = sim.frame_trails()
    impacts = sim.frame_impacts()
    if len(impacts):
        impacts = impacts[impacts[:, 2] >= 0.5 * texel_m][:4096]
    k = len(trails)
    out = np.zeros((k + len(impacts), 8), np.float32)  # written in place: the rows the GPU reads
    if k:
        # A line narrower than a texel is drawn wider and thinner (the same water), so that it, and the beads its
        # drop leaves along it (the film target's second channel), reach the texels it crosses.
        out[:k, 0:4] = trails[:, 0:4]
        a = trails[:, 4]
        a_vis = np.maximum(a, 0.6 * texel_m)
        out[:k, 4] = a_vis
        out[:k, 5] = TRAIL_FILM_M * 1e6 * 4 / math.pi * a / a_vis
        out[:k, 6] = 1.0
    if len(impacts):
        rows = out[k:]
        rows[:, 0:2] = impacts[:, :2]
        rows[:, 2:4] = impacts[:, :2]
        rows[:, 4] = impacts[:, 2]
        rows[:, 5] = impacts[:, 3] * 1e6
        rows[:, 6] = 2.0
        rows[:, 7] = (np.arange(len(impacts)) + 7 * sim.arrival_count) % 65536
    return out
