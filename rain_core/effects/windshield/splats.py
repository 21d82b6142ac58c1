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
    """Instances (n, 8) for the drop-height texture: drops as caps with tails, beads as lines (mm)."""
    rows = []
    if sim.count:
        a = sim.radius()
        a_vis = np.maximum(a, 0.75 * texel_m)
        h_mm = 1e3 * HEIGHT_PER_RADIUS * a * (a / a_vis)  # a sub-texel drop: wider, lower lens
        speed = norm2(sim.vel)
        tail = a * np.minimum(speed / 0.25, 1.5)
        back = -sim.vel / np.maximum(speed, 1e-9)[:, None] * tail[:, None]
        rows.append(np.column_stack([sim.pos, sim.pos + back, a_vis, h_mm, np.zeros(len(a)), np.zeros(len(a))]))
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
    return np.concatenate(rows) if rows else np.zeros((0, 8))


def film_splats(sim, texel_m: float) -> np.ndarray:
    """Instances (n, 8) added to the film texture (µm): wet trail lines and splash speckle."""
    rows = []
    trails = sim.frame_trails()
    if len(trails):
        rows.append(
            np.column_stack(
                [
                    trails[:, :4],
                    trails[:, 4],
                    np.full(len(trails), TRAIL_FILM_M * 1e6 * 4 / math.pi),
                    np.ones(len(trails)),
                    np.zeros(len(trails)),
                ]
            )
        )
    impacts = sim.frame_impacts()
    if len(impacts):
        impacts = impacts[impacts[:, 2] >= 0.5 * texel_m][:4096]
        seeds = np.arange(len(impacts)) + 7 * sim.arrival_count
        rows.append(
            np.column_stack(
                [
                    impacts[:, :2],
                    impacts[:, :2],
                    impacts[:, 2],
                    impacts[:, 3] * 1e6,
                    np.full(len(impacts), 2.0),
                    seeds % 65536,
                ]
            )
        )
    return np.concatenate(rows) if rows else np.zeros((0, 8))
