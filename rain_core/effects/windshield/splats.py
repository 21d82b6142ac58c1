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
    rows = []
    n = sim.count
    if n:
        # Written column by column into the float32 rows the GPU reads (one upload, no float64 (n, 8) copy);
        # only the few moving drops have a tail, the others' segment ends where it starts.
        out = np.zeros((n, 8), np.float32)
        pos, vel = sim.pos, sim.vel
        a = sim.radius()
        out[:, 0:2] = pos
        out[:, 2:4] = pos
        a_vis = np.maximum(a, 0.75 * texel_m)
        out[:, 4] = a_vis
        out[:, 5] = (1e3 * HEIGHT_PER_RADIUS) * a * (a / a_vis)  # a sub-texel drop: wider, lower lens
        vs, vt = vel[:, 0], vel[:, 1]
        moving = np.flatnonzero((vs != 0.0) | (vt != 0.0))
        if len(moving):
            v = vel[moving]
            speed = norm2(v)
            tail = a[moving] * np.minimum(speed / 0.25, 1.5)
            out[moving, 2:4] = pos[moving] - v / np.maximum(speed, 1e-9)[:, None] * tail[:, None]
        rows.append(out)
    direction = 1.0 if (sim.wipers.phase or 0.0) < 0.5 else -1.0
    for b, blade in enumerate(sim.blades):
        bead = sim.beads[b]
        if not bead.any():
            continue
        angle = float(blade.angle(sim.wipers.progress))
        bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        centres = sim.bead_bin_centres(blade, angle, ahead=direction * 0.004)
        d = np.array([math.cos(angle), math.sin(angle)]) * 0.5 * bin_len
        w = np.minimum(np.sqrt(2.0 * bead / (RHO_WATER * bin_len) / math.pi), 0.01)
        keep = w > 0
        w_vis = np.maximum(w, 0.75 * texel_m)
        rows.append(
            np.column_stack(
                [centres - d, centres + d, w_vis, 1e3 * w * (w / w_vis), np.ones(len(w)), np.zeros(len(w))]
            )[keep]
        )
    if len(rows) == 1:
        return rows[0]
    return np.concatenate(rows, dtype=np.float32) if rows else np.zeros((0, 8), np.float32)


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
