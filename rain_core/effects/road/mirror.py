"""The planar reflection's geometry: the road plane y = 0 as a mirror. GL-free.

The ``prepare`` pass draws the scene mirrored about y = 0 (view × diag(1, −1, 1), clipped below the road, at
``reflection_scale`` of the frame, mipmapped). The water samples it where its mirrored reflected ray projects, so
wave and ripple normals distort it; a rough film blurs it over the GGX lobe, ±α vertically and ±α·cosθ across
(vertical smears at grazing angles, as on wet streets). Where that ray leaves the texture (or off the road
plane) the sky takes over.

The sun, lamps and headlights reach the water as GGX highlights of the layer (roughness ≥ LIGHT_MIN_ROUGHNESS):
the long streaks of lights on a wet road at night. Their lenses are drawn dim in the reflection pass so they are
not counted twice (emissive albedo above LIGHT_SOURCE_RADIANCE, drawn MIRROR_LENS_FACTOR as bright).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rain_core.camera import Camera

MIRROR_CLIP_Y_M = 0.01  # m, the reflection pass keeps geometry above the road plane (markings are 4 mm)
LIGHT_SOURCE_RADIANCE = 2.0  # emissive albedo (×683 cd/m²) above which a surface is a lamp or headlight lens
MIRROR_LENS_FACTOR = 0.05  # lenses drawn this bright in the reflection: their light comes as highlights

# The reflection about y = 0 (world and wrapped frame alike): the mirror view is the main view times this.
MIRROR_Y = np.diag([1.0, -1.0, 1.0, 1.0])
# What the reflection pass keeps: the positive side of this plane (a, b, c, d), above the road surface.
MIRROR_CLIP_PLANE = (0.0, 1.0, 0.0, -MIRROR_CLIP_Y_M)


def mirror_about_road(camera: Camera) -> Camera:
    """The camera mirrored about the road plane y = 0 (position and forward; ``up`` stays +Y). Used for the
    reflection pass's lights and eye position; its view matrix is the original's times diag(1, −1, 1)."""
    # In floats (each frame): the products an array times (1, −1, 1) makes, elementwise, so the same bits
    px, py, pz = _floats(camera.position)
    fx, fy, fz = _floats(camera.forward)
    position = np.array((px * 1.0, py * -1.0, pz * 1.0))
    forward = np.array((fx * 1.0, fy * -1.0, fz * 1.0))
    return dataclasses.replace(camera, position=position, forward=forward, up=np.array([0.0, 1.0, 0.0]),
                               inside_car=False)


def _floats(v) -> list:
    """A 3-vector as Python floats (an ndarray by one tolist: float32 widens exactly, as np.asarray does)."""
    if type(v) is np.ndarray and v.dtype.kind == "f":
        return v.tolist()
    return [float(x) for x in v]
