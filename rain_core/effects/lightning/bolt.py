"""The visible bolt: a seeded branching channel from the cloud base to the ground (NumPy, no GL).

Stochastic midpoint displacement (the fractal model of lightning channels; cf. Reed & Wyvill 1994, "Visual
simulation of lightning"): each segment is split at its midpoint, moved sideways by a Gaussian offset
proportional to the segment's length, for ``levels`` rounds; at the first rounds a midpoint may also start a
branch that heads down and away for a share of the remaining height and carries less current (light). The main
channel has weight 1; a branch has the weight of its parent times 0.15–0.4.
"""

from __future__ import annotations

import numpy as np

ROUGHNESS = 0.14  # sideways offset / segment length
BRANCH_PROBABILITY = 0.35  # per midpoint in the branching rounds
BRANCH_ROUNDS = 4


def _displace(points: np.ndarray, rng: np.random.Generator, levels: int) -> np.ndarray:
    """Refine the polyline ``points`` (n, 3) by ``levels`` rounds of midpoint displacement."""
    for _ in range(levels):
        a, b = points[:-1], points[1:]
        mid = 0.5 * (a + b)
        length = np.linalg.norm(b - a, axis=1, keepdims=True)
        offset = rng.normal(0.0, 1.0, mid.shape) * ROUGHNESS * length
        offset[:, 1] *= 0.3  # mostly sideways: the channel keeps going down
        refined = np.empty((2 * len(points) - 1, 3))
        refined[0::2] = points
        refined[1::2] = mid + offset
        points = refined
    return points


def bolt_segments(top, bottom, seed: int, levels: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """(segments (N, 2, 3) m, weights (N,)): the channel from ``top`` (m, at the cloud base) to ``bottom`` (m, the
    ground) and its branches, deterministic for ``seed``."""
    rng = np.random.default_rng(seed)
    top = np.asarray(top, dtype=np.float64)
    bottom = np.asarray(bottom, dtype=np.float64)
    height = max(float(top[1] - bottom[1]), 1.0)
    segments, weights = [], []
    pending = [(np.stack([top, bottom]), 1.0, levels)]
    while pending:
        points, weight, lv = pending.pop()
        points = _displace(points, rng, lv)
        segments.append(np.stack([points[:-1], points[1:]], axis=1))
        weights.append(np.full(len(points) - 1, weight))
        if weight < 0.05 or len(segments) > 24:
            continue
        # Branches start along the upper part of this channel and die out before the ground.
        for i in range(1, max(2, len(points) * 2 // 3), max(1, len(points) // (2 ** BRANCH_ROUNDS))):
            if rng.random() >= BRANCH_PROBABILITY:
                continue
            start = points[i]
            drop = height * rng.uniform(0.1, 0.35)
            heading = rng.uniform(0.0, 2.0 * np.pi)
            end = start + np.array([np.cos(heading) * drop * 0.5, -drop, np.sin(heading) * drop * 0.5])
            end[1] = max(end[1], bottom[1] + 0.05 * height)
            pending.append((np.stack([start, end]), weight * rng.uniform(0.15, 0.4), max(3, lv - 2)))
    return np.concatenate(segments), np.concatenate(weights)
