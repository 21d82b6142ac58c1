"""The instance rows the effect splats into its water textures, built from the simulation's state (NumPy only).

Each row is 8 numbers, the layout of ``shaders/windshield/splat.vert``: a segment (s0, t0, s1, t1) m on the glass,
a radius (m), an amount, a kind (0 a drop cap with its tail, 1 a line: bead or wet trail, 2 splash speckle) and
a seed. ``texel_m`` is the size of one texel of the water texture: drops smaller than a texel are drawn wider and
lower so they do not flicker between texels.

The drop rows (thousands a frame, the largest upload of the frame) are ``DROP_ROW``: the segment in float32 (a
half float would move a drop by up to ~0.25 mm) and radius, height, kind and seed in float16 (relative 5e-4; the
heights land in a half-float texture anyway): 24 bytes a row instead of 32. The film rows keep float32 (their
seed counts to 65535).
"""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.windshield.constants import BEAD_BINS, HEIGHT_PER_RADIUS, TRAIL_FILM_M, norm2
from rain_core.physics import RHO_WATER

# A drop texture instance: the segment s0, t0, s1, t1 (m) as float32, radius (m), height (mm), kind, seed as float16
# (the vertex formats "4f 4f2/i"; the shaders read both as vec4).
DROP_ROW = np.dtype([("seg", "<f4", (4,)), ("info", "<f2", (4,))])
_HALF_BIAS = (127 - 15) << 10  # float32's exponent bias over float16's, in a float16's bit positions
_HALF_ONE = 0x3C00  # 1.0 as a float16


def half_bits(x: np.ndarray) -> np.ndarray:
    """The float16 bit patterns (as uint32) of non-negative float32 ``x``: rounded to nearest (ties up), values
    below the smallest normal half (6.1e-5) as 0 or that smallest one; ``x`` must stay below 65504. NumPy's
    float16 cast costs ~10 ns a value (no SIMD); this is a few integer operations on float32's bits."""
    bits = x.view(np.uint32) + np.uint32(1 << 12)  # half of the 13 mantissa bits dropped: rounds to nearest
    bits >>= 13
    signed = bits.view(np.int32)
    signed -= _HALF_BIAS
    np.maximum(signed, 0, out=signed)
    return bits


def drop_splats(sim, texel_m: float) -> np.ndarray:
    """Instances (n,) of ``DROP_ROW`` for the drop-height texture: drops as caps with tails, beads as lines (mm)."""
    n = sim.count
    beads = []
    direction = 1.0 if (sim.wipers.phase or 0.0) < 0.5 else -1.0
    for b, blade in enumerate(sim.blades):
        bead = sim.beads[b]
        if bead.any():
            bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
            w = np.minimum(np.sqrt(2.0 * bead / (RHO_WATER * bin_len) / math.pi), 0.01)
            keep = (w > 0).nonzero()[0]
            if len(keep):
                beads.append((blade, w, keep))
    # Written column by column into the rows the GPU reads (one array for drops and beads: one upload, no float64
    # (n, 8) copy, no concatenation): 6 words a row, the segment's four float32 and two pairs of float16 (radius
    # and height, from float32 through ``half_bits``; kind and seed).
    total = n + sum(len(k) for *_, k in beads)
    rows = np.zeros((total, 6), np.uint32)
    seg = rows[:, :4].view(np.float32)
    size = np.empty((total, 2), np.float32)  # radius as splatted (m), height (mm)
    if n:
        # Only the few moving drops have a tail, the others' segment ends where it starts.
        pos, vel = sim.pos, sim.vel
        a = sim.radius()
        # Column by column: a cast into an (n, 2) block loops over its rows (~5× slower than four columns).
        s, t = pos[:, 0], pos[:, 1]
        seg[:n, 0] = s
        seg[:n, 1] = t
        seg[:n, 2] = seg[:n, 0]
        seg[:n, 3] = seg[:n, 1]
        a_vis = np.maximum(a, 0.75 * texel_m)
        size[:n, 0] = a_vis
        height = a * (1e3 * HEIGHT_PER_RADIUS)
        height *= a
        height /= a_vis
        size[:n, 1] = height  # a sub-texel drop: wider, lower lens
        # (vs, vt) as one complex number: one comparison a drop (the columns are strided rows of the drop array).
        moving = (vel.view(np.complex128)[:, 0] != 0.0 if vel.strides[1] == 8 else vel.any(axis=1)).nonzero()[0]
        if len(moving):
            v = vel[moving]
            speed = norm2(v)
            tail = a[moving] * np.minimum(speed / 0.25, 1.5)
            seg[moving, 2:4] = pos[moving] - v / np.maximum(speed, 1e-9)[:, None] * tail[:, None]
    row = n
    for blade, w, keep in beads:
        angle = float(blade.angle(sim.wipers.progress))
        bin_len = (blade.r_outer_m - blade.r_inner_m) / BEAD_BINS
        centres = sim.bead_bin_centres(blade, angle, ahead=direction * 0.004)[keep]
        d = np.array([math.cos(angle), math.sin(angle)]) * 0.5 * bin_len
        w = w[keep]
        w_vis = np.maximum(w, 0.75 * texel_m)
        end = row + len(keep)
        seg[row:end, 0:2] = centres - d
        seg[row:end, 2:4] = centres + d
        size[row:end, 0] = w_vis
        size[row:end, 1] = 1e3 * w * (w / w_vis)
        rows[row:end, 5] = _HALF_ONE  # kind 1, seed 0
        row = end
    rows[:, 4] = half_bits(size).astype(np.uint16).view(np.uint32)[:, 0]  # the two halves, in memory order
    return rows.view(DROP_ROW)[:, 0]


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
