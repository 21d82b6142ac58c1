"""Drop shapes: Beard & Chuang's (1987) equilibrium shapes of falling drops, as the side-view projected area and
horizontal width the streaks are drawn with (the shader gets the same table: ``u_shape_area``, ``u_shape_width``)."""

from __future__ import annotations

import numpy as np

# Beard & Chuang (1987) equilibrium shapes r(θ) = a·(1 + Σ C_n cos nθ), C_n × 1e4, D = 2 … 6 mm (in 0.5 mm
# steps; the table of /work/shared/reference/beard_chuang.csv).
# Beard & Chuang (1987) equilibrium shapes r(θ) = a·(1 + Σ C_n cos nθ), C_n × 1e4, D = 2 … 6 mm (in 0.5 mm
# steps; the table of /work/shared/reference/beard_chuang.csv).
_BC_D_MM = np.arange(2.0, 6.01, 0.5)
_BC_C = np.array([
    [-131, -120, -376, -96, -4, 15, 5, 0, -2, 0, 1],
    [-201, -172, -567, -137, 3, 29, 8, -2, -4, 0, 1],
    [-282, -230, -779, -175, 21, 46, 11, -6, -7, 0, 3],
    [-369, -285, -998, -207, 48, 68, 13, -13, -10, 0, 5],
    [-458, -335, -1211, -227, 83, 89, 12, -21, -13, 1, 8],
    [-549, -377, -1421, -240, 126, 110, 9, -31, -16, 4, 11],
    [-644, -416, -1629, -246, 176, 131, 2, -44, -18, 9, 14],
    [-742, -454, -1837, -244, 234, 150, -7, -58, -19, 15, 19],
    [-840, -480, -2034, -237, 297, 166, -21, -72, -19, 24, 23],
]) * 1e-4


def _shape_factors() -> tuple[np.ndarray, np.ndarray]:
    """(side-view area / πD²/4, horizontal width / D) of Beard & Chuang's shapes at _BC_D_MM.

    Seen from the side the silhouette is the meridian curve r(θ): area ½∮r² dθ, width 2·max r(θ)·sin θ."""
    theta = np.linspace(0.0, 2.0 * np.pi, 2049)[:-1]
    n = np.arange(11)
    r = 1.0 + _BC_C @ np.cos(np.outer(n, theta))  # (9, 2048), in units of a = D/2
    area = 0.5 * (r**2).mean(axis=1) * 2.0 * np.pi / np.pi  # / (π a²)
    width = (r * np.abs(np.sin(theta))).max(axis=1)  # half-width / a = width / D
    return area, width


SHAPE_AREA, SHAPE_WIDTH = _shape_factors()
# mm, the diameters of the shape table (a sphere at 1 mm, then Beard & Chuang's): the shader's u_shape_* arrays.
SHAPE_DIAMETERS_MM = np.concatenate([[1.0], _BC_D_MM])


def drop_shape_factors(d_mm) -> tuple[np.ndarray, np.ndarray]:
    """Side-view projected area (÷ πD²/4) and horizontal width (÷ D) of a falling drop of diameter d_mm (mm).

    Spheres below 1 mm; Beard & Chuang's flattened shapes from 2 mm (linear in between, held above 6 mm)."""
    d = np.asarray(d_mm, dtype=np.float64)
    xs = SHAPE_DIAMETERS_MM
    area = np.interp(d, xs, np.concatenate([[1.0], SHAPE_AREA]))
    width = np.interp(d, xs, np.concatenate([[1.0], SHAPE_WIDTH]))
    return area, width
