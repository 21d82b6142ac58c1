"""``Capture``: one frame as the API hands it out, and the camera geometry of its labels (GL-free).

Camera convention of the labels (the one perception code expects, OpenCV's): pixel coordinates (u, v) start at
the top-left corner of the image, u to the right, v down, pixel (i, j) covers [i, i+1) × [j, j+1) so its centre is
(i + 0.5, j + 0.5); camera axes x right, y down, z forward (along the view). A point X_c in camera axes (m)
projects to K @ X_c / z. ``camera_to_world`` maps camera axes to world metres (+Y up, the renderer's frame).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Capture:
    """One rendered frame.

    rgb: (H, W, 3) uint8 sRGB, top row first — what the screen shows. depth_m: (H, W) float32 metres along the
    view ray to the first opaque surface (inf for sky), None unless captured with labels=True. masks: dict of
    (H, W) arrays (see rain_core.labels.LabelImages: "rain", "glass_water", "road_water", "spray", "class"), empty
    unless labels=True. labels: dict of this frame's ground truth in SI units (always filled; see
    Session.capture).
    """

    rgb: np.ndarray
    depth_m: np.ndarray | None = None
    masks: dict[str, np.ndarray] = field(default_factory=dict)
    labels: dict = field(default_factory=dict)

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) in pixels."""
        return self.rgb.shape[1], self.rgb.shape[0]


def camera_intrinsics(fov_y_deg: float, size: tuple[int, int]) -> np.ndarray:
    """3×3 pinhole matrix K (pixels) for vertical field of view ``fov_y_deg`` (deg) and ``size`` (W, H) px:
    square pixels, principal point at the image centre (W/2, H/2) in the convention of the module docstring."""
    w, h = size
    f = 0.5 * h / math.tan(math.radians(fov_y_deg) / 2.0)
    return np.array([[f, 0.0, 0.5 * w], [0.0, f, 0.5 * h], [0.0, 0.0, 1.0]])


def camera_to_world(camera) -> np.ndarray:
    """4×4 rigid transform from camera axes (x right, y down, z forward; m) to world (m) for a
    rain_core.camera.Camera: columns right, −up, forward and the eye position."""
    right, up, forward = camera.basis()
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = right, -up, forward
    m[:3, 3] = np.asarray(camera.position, dtype=np.float64)
    return m


def project(points_world, intrinsics: np.ndarray, cam_to_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (…, 2) and depth along the optical axis z (m, …) of world points (…, 3)."""
    p = np.asarray(points_world, dtype=np.float64)
    world_to_cam = np.linalg.inv(cam_to_world)
    cam = p @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
    uvw = cam @ np.asarray(intrinsics, dtype=np.float64).T
    return uvw[..., :2] / uvw[..., 2:3], cam[..., 2]
