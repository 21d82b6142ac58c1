"""The instance rows the effect splats into its water textures, built from the simulation's state: by NumPy, or
by the compiled kernels of ``render_kernels`` where they run (the same bits).

The film rows are 8 numbers, the layout of ``shaders/windshield/splat.vert``: a segment (s0, t0, s1, t1) m on the
glass, a radius (m), an amount, a kind (1 a line: wet trail, 2 splash speckle) and a seed. ``texel_m`` is the size
of one texel of the water texture: lines and splashes smaller than a texel are drawn wider and thinner (or left
out) so they do not flicker between texels.

The drop rows (thousands a frame, the largest upload of the frame) are ``DROP_ROW``, five float32: for a drop its
position and velocity (s, t, vs, vt) and contact radius, copied from the simulation's rows as they are; for a
wiper bead a line (s0, t0, s1, t1) and its radius negated. The shaders lay a drop's tail behind it and widen the
sub-texel ones (``shaders/windshield/drop_row.glsl``, ``drop_splat.vert``): per drop the CPU only copies.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit
from rain_core.effects.windshield import render_kernels
from rain_core.effects.windshield.constants import BEAD_BINS, TRAIL_FILM_M
from rain_core.effects.windshield.drop_rows import VT as _VT
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.sim import RHO_PI, SPLASH_R_PER_MM
from rain_core.physics import RHO_WATER

# A drop buffer instance (the vertex format "4f 1f/i"): (s, t, vs, vt) m, m/s and the contact radius (m) of a
# drop, or (s0, t0, s1, t1) m and minus the radius (m) of a bead's line.
DROP_ROW = np.dtype([("seg", "<f4", (4,)), ("radius", "<f4")])
_HALF_BIAS = (127 - 15) << 10  # float32's exponent bias over float16's, in a float16's bit positions


def half_bits(x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """The float16 bit patterns (as uint32) of non-negative float32 ``x``: rounded to nearest (ties up), values
    below the smallest normal half (6.1e-5) as 0 or that smallest one; ``x`` must stay below 65504. NumPy's
    float16 cast costs ~10 ns a value (no SIMD); this is a few integer operations on float32's bits. ``out``: a
    uint32 array of x's shape to write them to (may be ``x.view(np.uint32)`` itself)."""
    bits = np.add(x.view(np.uint32), np.uint32(1 << 12), out=out)  # half of the 13 dropped bits: rounds to nearest
    bits >>= 13
    signed = bits.view(np.int32)
    signed -= _HALF_BIAS
    np.maximum(signed, 0, out=signed)
    return bits


class DropRows:
    """Builds the drop buffer's rows (``DROP_ROW``) of a simulation frame after frame into one array it keeps
    (grown when the drops outnumber it): each call's rows are valid until the next call. With the compiled kernels,
    the rows the simulation's last sort wrote (``drop_rows32``) where they hold: those are valid until the
    simulation changes (the effect keys its rows on its version)."""

    def __init__(self):
        self._out = np.zeros((0, 5), np.float32)
        self._blades = None  # the blades the tables below are for
        self._w_scale = self._ends = None

    def _bead_tables(self, blades) -> None:
        """Per blade and bead bin: 2 / (ρ·π·bin length) (the bin's kg → its half-cylinder radius²) and the radii
        (m) of the bin's ends along the blade, (blades, BEAD_BINS, 1, 2). A blade's bins do not change."""
        self._blades = blades
        lengths = np.array([(b.r_outer_m - b.r_inner_m) / BEAD_BINS for b in blades])[:, None]
        self._w_scale = 2.0 / (RHO_WATER * lengths) / math.pi
        inner = np.array([b.r_inner_m for b in blades])[:, None]
        centre = inner + (np.arange(BEAD_BINS) + 0.5) * lengths
        self._ends = np.stack([centre - 0.5 * lengths, centre + 0.5 * lengths], axis=-1)[:, :, :, None]
        # The same tables for the compiled path: contiguous float64, (blades,) and (blades, BEAD_BINS, 2).
        self._w_scale_flat = np.ascontiguousarray(self._w_scale[:, 0])
        self._ends_flat = np.ascontiguousarray(self._ends[..., 0])
        self._no_frames = np.zeros((len(blades), 4))

    def rows(self, sim) -> np.ndarray:
        """The rows (n,) ``DROP_ROW`` of ``sim``'s drops, then its beads' lines (the bins with water)."""
        block = getattr(sim, "_buf", None)  # the fast path's drop array (drop_rows' columns): no copies
        if block is not None and jit.active():
            return self._compiled_rows(sim, block)
        n = sim.count
        beads = sim.beads
        lines = None
        if np.count_nonzero(beads):  # (ndarray.any goes through Python)
            if self._blades is not sim.blades:
                self._bead_tables(sim.blades)
            # The bead's cross-section as a half cylinder (m) of its bin's water, at most 1 cm.
            w = np.minimum(np.sqrt(beads * self._w_scale), 0.01).ravel()
            lines = (w > 0).nonzero()[0]
        total = n + (len(lines) if lines is not None else 0)
        if total > len(self._out):
            self._out = np.zeros((max(total, 2 * len(self._out), 1024), 5), np.float32)
        out = self._out
        if n:
            if block is not None:
                # The drop array's rows are 128 bytes and cold in the cache by now: one pass over the (n, 4) block
                # reads them once (~45 us for 5,700 drops against ~60 for column by column; warm both ~27 us).
                out[:n, 0:4] = block[:n, _S : _VT + 1]  # S, T, VS, VT: adjacent columns (drop_rows)
                out[:n, 4] = block[:n, _A]
            else:
                out[:n, 0:2] = sim.pos
                out[:n, 2:4] = sim.vel
                out[:n, 4] = sim.radius()
        if lines is not None and len(lines):
            frames = np.array(_blade_frames(sim)).reshape(-1, 1, 1, 2, 2)  # (blades, 1, 1, direction/pivot, s/t)
            ends = (self._ends * frames[..., 0, :] + frames[..., 1, :]).reshape(-1, 4)  # (s0, t0, s1, t1) a bin
            out[n:total, 0:4] = ends[lines]
            np.negative(w[lines], out=out[n:total, 4])
        return out[:total].view(DROP_ROW)[:, 0]

    def _compiled_rows(self, sim, block: np.ndarray) -> np.ndarray:
        """``rows`` by ``render_kernels.drop_rows``: one pass over the drop array's rows and the bead bins."""
        n = sim.count
        beads = sim.beads
        if self._blades is not sim.blades:
            self._bead_tables(sim.blades)
        if n + beads.size > len(self._out):
            self._out = np.zeros((max(n + beads.size, 2 * len(self._out), 1024), 5), np.float32)
        if np.count_nonzero(beads):
            frames = np.array(_blade_frames(sim))
        else:  # no bin has water: the kernel draws no line, whatever the blades' frames
            frames = self._no_frames
        sorted_rows = sim.drop_rows32() if hasattr(sim, "drop_rows32") else None
        if sorted_rows is not None and len(sorted_rows) >= n + beads.size:
            # The drops' rows as the step's last sort wrote them: only the beads' rows are written after them.
            total = n + render_kernels.drop_rows(block, 0, _S, _A, beads, self._w_scale_flat, self._ends_flat,
                                                 frames, sorted_rows[n:])
            return sorted_rows[:total].view(DROP_ROW)[:, 0]
        total = render_kernels.drop_rows(block, n, _S, _A, beads, self._w_scale_flat, self._ends_flat, frames,
                                         self._out)
        return self._out[:total].view(DROP_ROW)[:, 0]


def _blade_frames(sim) -> list[tuple[float, float, float, float]]:
    """Per blade: the cos and sin of its angle now and its pivot (s, t) m moved 4 mm ahead along its normal
    (towards the stroke's direction), where its bead bins' lines lie: WindshieldSimReference.bead_bin_centres ±
    half a bin along the blade, i.e. pivot + ahead·normal + r·direction for each bin's two ends."""
    ahead = 0.004 if (sim.wipers.phase or 0.0) < 0.5 else -0.004
    frames = []
    for blade, angle in zip(sim.blades, sim.blade_angles(), strict=True):  # (float(blade.angle(progress)) each)
        c, s = math.cos(angle), math.sin(angle)
        frames.append((c, s, blade.pivot[0] - ahead * s, blade.pivot[1] + ahead * c))
    return frames


def drop_splats(sim, texel_m: float | None = None) -> np.ndarray:
    """Instances (n,) of ``DROP_ROW`` for the drop-height texture and the drop lenses: drops, then beads as lines.
    A new array each call (the effect keeps a ``DropRows``). ``texel_m`` is not needed: the shaders widen the
    sub-texel drops."""
    return DropRows().rows(sim).copy()


_MAX_SPLASHES = 4096  # the most splash speckles a frame draws
_NO_IMPACTS = np.zeros((0, 4))
_TRAIL_UM = TRAIL_FILM_M * 1e6 * 4 / math.pi  # a trail line's film (µm) × its visible width / the drop radius


class FilmRows:
    """Builds ``film_splats``'s rows of a simulation frame after frame: with the compiled kernels into one array
    it keeps (grown when needed; each call's rows are valid until the next call), else ``film_splats`` itself."""

    def __init__(self):
        self._out = np.zeros((0, 8), np.float32)

    def rows(self, sim, texel_m: float) -> np.ndarray:
        """The rows (n, 8) float32 of ``film_splats(sim, texel_m)``."""
        if not jit.active():
            return film_splats(sim, texel_m)
        trails = np.ascontiguousarray(sim.frame_trails(), np.float64)  # (the fast path's are already)
        blocks = sim.impact_columns() if hasattr(sim, "impact_columns") else None
        # The fast path's impacts straight from their columns: frame_impacts' (m, 4) array costs a dozen NumPy
        # calls over a frame's ~1,500 impacts.
        impacts = _NO_IMPACTS if blocks is not None else np.ascontiguousarray(sim.frame_impacts(), np.float64)
        n_impacts = len(impacts) if blocks is None else sum(len(cols[0]) for cols in blocks)
        need = len(trails) + min(n_impacts, _MAX_SPLASHES)
        if need > len(self._out):
            self._out = np.zeros((max(need, 2 * len(self._out), 256), 8), np.float32)
        out = self._out
        seed0 = 7 * sim.arrival_count
        total = render_kernels.film_rows(trails, impacts, 0.6 * texel_m, _TRAIL_UM, 0.5 * texel_m, _MAX_SPLASHES,
                                         seed0, out)
        if blocks:
            k = len(trails)
            for s, t, d_mm, splash, obj, a_obj, to_film in blocks:
                total = render_kernels.impact_rows(s, t, d_mm, splash, obj, a_obj, to_film, SPLASH_R_PER_MM, RHO_PI,
                                                   0.5 * texel_m, _MAX_SPLASHES, k, seed0, total, out)
        return out[:total]


def film_splats(sim, texel_m: float) -> np.ndarray:
    """Instances (n, 8) float32 added to the film texture (µm): wet trail lines (which also stamp the beads a
    sliding drop leaves behind) and splash speckle."""
    trails = sim.frame_trails()
    impacts = sim.frame_impacts()
    if len(impacts):
        impacts = impacts.compress(impacts[:, 2] >= 0.5 * texel_m, axis=0)[:_MAX_SPLASHES]  # (faster than a mask)
    k = len(trails)
    out = np.zeros((k + len(impacts), 8), np.float32)  # written in place: the rows the GPU reads
    if k:
        # A line narrower than a texel is drawn wider and thinner (the same water), so that it, and the beads its
        # drop leaves along it (the film target's second channel), reach the texels it crosses.
        out[:k, 0:4] = trails[:, 0:4]
        a = trails[:, 4]
        a_vis = np.maximum(a, 0.6 * texel_m)
        out[:k, 4] = a_vis
        out[:k, 5] = _TRAIL_UM * a / a_vis
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
