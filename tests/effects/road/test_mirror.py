"""The reflection's camera: mirror_about_road gives what the array formula gives, bit for bit."""

import dataclasses

import numpy as np

from rain_core.camera import Camera
from rain_core.effects.road.mirror import mirror_about_road


def _reference(camera):
    flip = np.array([1.0, -1.0, 1.0])
    return dataclasses.replace(camera, position=np.asarray(camera.position, dtype=np.float64) * flip,
                               forward=np.asarray(camera.forward, dtype=np.float64) * flip,
                               up=np.array([0.0, 1.0, 0.0]), inside_car=False)


@dataclasses.dataclass
class _TaggedCamera(Camera):
    tag: str = "rig"


def test_mirror_about_road_is_the_array_formula_bit_for_bit():
    rng = np.random.default_rng(3)
    cameras = [Camera(position=np.array([1.0, -0.0, np.nan]), forward=np.array([0.0, 0.0, -1.0]), inside_car=True,
                      focus_m=3.0),
               Camera(position=[2, 1, -5], forward=np.array([0.5, -0.0, 0.5], np.float32), fov_y_deg=40.0),
               _TaggedCamera(position=np.array([0.0, 1.2, 3.0]), tag="seat")]
    cameras += [Camera(position=rng.normal(size=3) * 50, forward=rng.normal(size=3), near_m=0.1, far_m=900.0)
                for _ in range(50)]
    for camera in cameras:
        got, expected = mirror_about_road(camera), _reference(camera)
        assert type(got) is type(expected)
        for f in dataclasses.fields(expected):
            a, b = getattr(got, f.name), getattr(expected, f.name)
            if isinstance(b, np.ndarray):
                assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), f.name
            else:
                assert a == b, f.name
