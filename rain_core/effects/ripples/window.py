"""Where the ripple field lies (DESIGN §3): its grid (cells and cell size) and its window's centre, ahead of the
car along its heading so that the wakes of the cars a driver follows are simulated.

NumPy only.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import checks
from rain_core.effects.ripples.constants import MAX_CELLS_PER_SIDE, WINDOW_EDGE_FADE


def field_grid(n: int, extent_m: float) -> tuple[int, float, float]:
    """(n, extent in m, cell size in m) of a field of n cells per side (≥ 8) spanning extent_m; ValueError if
    either is bad."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 8 <= n <= MAX_CELLS_PER_SIDE:
        raise ValueError(f"n must be an int in [8, {MAX_CELLS_PER_SIDE}] (cells per side), got {checks.quote(n)}")
    extent = checks.number("extent_m", extent_m, 1e-3, 1e5, "m")
    return int(n), extent, extent / (int(n) - 1)


def window_offset_m(extent_m: float, camera_along_m: float | None, car_half_length_m: float,
                    margin_m: float = 0.0) -> float:
    """How far ahead of the car's centre, in m along its heading, the window's centre goes: the window's rear
    edge sits ``margin_m`` + WINDOW_EDGE_FADE × extent behind whichever lies further back of the car's rear
    (``car_half_length_m`` behind its centre) and the camera (``camera_along_m``: the camera's position along
    the heading, m from the car's centre; None: a camera that does not look ahead along the heading), and the
    window reaches forward from there: the rest of the extent lies ahead, where a driver looks.

    The effect passes its re-centring hysteresis as ``margin_m`` (4 cells: 0.2 m on the default 512-cell, 25 m
    grid). The driver's eye (0.4 m behind the centre) puts the rear edge behind the car's: the window spans
    −3.75 … +21.25 m, so the wakes of the cars 10–20 m ahead are simulated. The chase camera (7 m behind) puts
    it behind the camera: −8.45 … +16.55 m, the car and the road the camera sees near it. Never negative: the
    window stays centred on the car, as before, when the camera does not look ahead, is far behind (a fixed
    camera), or the window is too short to reach past the car."""
    if camera_along_m is None:
        return 0.0
    rear = min(float(camera_along_m), -float(car_half_length_m)) - float(margin_m) - WINDOW_EDGE_FADE * extent_m
    return max(0.0, 0.5 * extent_m + rear)


def window_centre_xz(position_xz, heading_xz, extent_m: float, camera_position=None, camera_forward=None,
                     car_half_length_m: float = 2.3, margin_m: float = 0.0) -> tuple[float, float]:
    """World (x, z) in m of the window's centre for a car at ``position_xz`` (m) heading along ``heading_xz``
    (a horizontal direction, any length) seen from a camera at ``camera_position`` (3-vector, world m) looking
    along ``camera_forward``: the car's position plus the heading × ``window_offset_m``. No camera, or one
    looking backwards along the heading: centred on the car."""
    x, z = float(position_xz[0]), float(position_xz[1])
    hx, hz = float(heading_xz[0]), float(heading_xz[1])
    norm = math.hypot(hx, hz)
    if norm == 0.0 or not math.isfinite(norm):
        return x, z
    hx, hz = hx / norm, hz / norm
    along = None
    if camera_position is not None and camera_forward is not None:
        if float(camera_forward[0]) * hx + float(camera_forward[2]) * hz > 0.0:  # the camera looks ahead
            along = (float(camera_position[0]) - x) * hx + (float(camera_position[2]) - z) * hz
    offset = window_offset_m(extent_m, along, car_half_length_m, margin_m)
    return x + hx * offset, z + hz * offset
