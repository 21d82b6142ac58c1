"""The roofs of the drip-site search (``edges._roofs``): 4-connected components of the low-roof cells."""

from __future__ import annotations

from collections import deque

import numpy as np

from rain_core.effects.drips.edges import _roofs


def _flood_fill(mask: np.ndarray) -> np.ndarray:
    """Oracle: each component by breadth-first search from its first cell (row-major), numbered in that order."""
    index = np.full(mask.shape, -1, dtype=np.int64)
    count = 0
    for start in zip(*mask.nonzero(), strict=True):
        if index[start] >= 0:
            continue
        index[start] = count
        todo = deque([start])
        while todo:
            r, c = todo.popleft()
            for q in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
                if 0 <= q[0] < mask.shape[0] and 0 <= q[1] < mask.shape[1] and mask[q] and index[q] < 0:
                    index[q] = count
                    todo.append(q)
        count += 1
    return index


def test_roofs_are_the_4_connected_components_in_order_of_their_first_cell():
    rng = np.random.default_rng(5)
    for _ in range(400):
        shape = tuple(rng.integers(1, 24, 2))
        mask = rng.random(shape) < rng.uniform(0.1, 0.9)
        index, count = _roofs(mask)
        expected = _flood_fill(mask)
        assert np.array_equal(index, expected) and count == expected.max() + 1


def test_a_u_and_a_spiral_are_one_roof_and_diagonals_are_not_joined():
    u = np.array([[1, 0, 1],
                  [1, 0, 1],
                  [1, 1, 1]], bool)  # two arms met by the bottom row: joined after both were started
    index, count = _roofs(u)
    assert count == 1 and (index[u] == 0).all()
    spiral = np.array([[1, 1, 1, 1, 1],
                       [0, 0, 0, 0, 1],
                       [1, 1, 1, 0, 1],
                       [1, 0, 0, 0, 1],
                       [1, 1, 1, 1, 1]], bool)
    assert _roofs(spiral)[1] == 1
    diagonal = np.eye(4, dtype=bool)
    index, count = _roofs(diagonal)
    assert count == 4 and list(index[diagonal]) == [0, 1, 2, 3]
    assert _roofs(np.zeros((3, 3), bool))[1] == 0
