"""Façade touches over the buildings' shop fronts, placed from the seed: a fascia board over each shop front with
a lit lettering band (emissive: bright at night, a faint colour by day). Cheap: two boxes and a quad per shop."""

from __future__ import annotations

import numpy as np

from rain_core.mesh import MAT_CONCRETE, MAT_EMISSIVE, MAT_GENERIC
from rain_core.world.primitives import NX_, NY_, NZ_, PX_, PY_, PZ_, _boxes, _facade_quads, _span
from rain_core.world.street import LUMINOUS_EFFICACY_LM_PER_W, Frontage

_BOARD_PALETTE = np.array([(0.02, 0.10, 0.05), (0.02, 0.03, 0.12), (0.30, 0.02, 0.02), (0.03, 0.03, 0.03),
                           (0.60, 0.60, 0.58), (0.45, 0.30, 0.04), (0.20, 0.04, 0.18)])
# Lettering colours (linear RGB, luminance 1 after scaling): warm white, red, cool white, green, amber, blue.
_LETTER_RGB = np.array([(1.0, 0.80, 0.55), (1.0, 0.10, 0.06), (0.85, 0.92, 1.0), (0.25, 1.0, 0.35),
                        (1.0, 0.55, 0.10), (0.25, 0.45, 1.0)])
_LETTER_RGB = _LETTER_RGB / (_LETTER_RGB @ np.array([0.2126, 0.7152, 0.0722]))[:, None]
FASCIA_Y_M = (3.35, 3.95)  # m, the board's bottom and top: above the awnings (3.1–3.25 m), below the first floor
FASCIA_DEPTH_M = 0.10  # m, the board stands this far proud of the wall


def shop_signs(rng: np.random.Generator, frontage: Frontage) -> list[np.ndarray]:
    """Vertex arrays of the fascia boards and their lettering over ``frontage.shops``."""
    shops = np.asarray(frontage.shops, dtype=np.float64).reshape(-1, 5)
    n = len(shops)
    if n == 0:
        return []
    side, d0, z0, z1 = shops[:, 0], shops[:, 1], shops[:, 2], shops[:, 3]
    width = z1 - z0
    length = np.minimum(width - 0.6, rng.uniform(3.0, 9.0, n))
    zc = (z0 + z1) / 2 + rng.uniform(-0.5, 0.5, n) * np.maximum(width - 0.6 - length, 0.0)
    ok = length > 1.5
    board = _BOARD_PALETTE[rng.integers(len(_BOARD_PALETTE), size=n)] * rng.uniform(0.85, 1.1, (n, 1))
    colour = _LETTER_RGB[rng.integers(len(_LETTER_RGB), size=n)]
    lum = rng.uniform(60.0, 220.0, n)  # cd/m², a lit sign
    fill = rng.uniform(0.55, 0.9, n)  # share of the board the lettering covers
    side, d0, zc, length, board, colour, lum, fill = (a[ok] for a in (side, d0, zc, length, board, colour, lum, fill))
    x0, x1 = _span(side, d0 - FASCIA_DEPTH_M, d0)
    ya, yb = FASCIA_Y_M
    lo = np.stack([x0, np.full(len(x0), ya), zc - length / 2], 1)
    hi = np.stack([x1, np.full(len(x0), yb), zc + length / 2], 1)
    parts = []
    for s in (-1.0, 1.0):  # the face towards the wall is hidden
        m = side == s
        if m.any():
            faces = (NX_ if s > 0 else PX_, NY_, PY_, NZ_, PZ_)
            parts.append(_boxes(lo[m], hi[m], board[m], 0.5, 0.0, MAT_GENERIC, faces=faces))
    # Lettering: a lit band 1 cm in front of the board.
    xf = side * (d0 - FASCIA_DEPTH_M - 0.01)
    half = length * fill / 2
    pad = 0.12
    parts.append(_facade_quads(xf, -side, ya + pad, yb - pad, zc - half, zc + half,
                               colour * (lum / LUMINOUS_EFFICACY_LM_PER_W)[:, None], 0.2, MAT_EMISSIVE))
    # A slim cap on the board's top edge (a lip of the fascia's frame).
    cx0, cx1 = _span(side, d0 - FASCIA_DEPTH_M - 0.03, d0)
    parts.append(_boxes(np.stack([cx0, np.full(len(x0), yb), zc - length / 2 - 0.03], 1),
                        np.stack([cx1, np.full(len(x0), yb + 0.05), zc + length / 2 + 0.03], 1),
                        (0.25, 0.25, 0.25), 0.6, 0.0, MAT_CONCRETE, faces=(NX_, PX_, PY_, NZ_, PZ_)))
    return parts
