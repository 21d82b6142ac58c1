"""Semantic class ids of the label images, and the class of every vertex of the world, the vehicles and the cabin.

GL-free. The ids are stable (recorded datasets keep their meaning across versions): add new classes at the end,
never renumber. 0 is "unlabeled" (nothing in this renderer draws it today), ``sky`` is where no opaque surface is.

| id | name        | what                                                                    |
|----|-------------|-------------------------------------------------------------------------|
|  0 | unlabeled   |                                                                         |
|  1 | road        | the asphalt carriageway                                                 |
|  2 | marking     | painted lane and edge lines                                             |
|  3 | kerb        | the kerb stones between road and sidewalk (top and road-facing face)    |
|  4 | sidewalk    | sidewalk slabs and their outer face                                     |
|  5 | terrain     | the grass ground beyond the sidewalks                                   |
|  6 | building    | buildings, their windows, doors and awnings; the fuel station           |
|  7 | bridge      | the railway underpass: deck, wing walls, embankment, railings, its lamps |
|  8 | pole        | street lamps: pole, arm and head                                        |
|  9 | vegetation  | trees: trunks and crowns                                                |
| 10 | vehicle     | other vehicles                                                          |
| 11 | ego_vehicle | the ego car's outside: its body in the chase camera, hood and mirrors  |
|    |             | seen from the driver's seat                                             |
| 12 | ego_cabin   | the ego car's interior (dashboard, pillars, roof lining, seats)         |
| 13 | sky         | no opaque surface along the ray                                         |
| 14 | traffic_sign| road sign plates (their posts are poles)                                |

Parked cars are vehicles; zebra crossings are markings; sign posts are poles.
"""

from __future__ import annotations

import logging

import numpy as np

from rain_core import layout
from rain_core.mesh import MAT_ASPHALT, MAT_CAR_PAINT, MAT_CONCRETE, MAT_FOLIAGE, MAT_GLASS, MAT_METAL, MAT_PAINT

CLASS_IDS: dict[str, int] = {
    "unlabeled": 0, "road": 1, "marking": 2, "kerb": 3, "sidewalk": 4, "terrain": 5, "building": 6, "bridge": 7,
    "pole": 8, "vegetation": 9, "vehicle": 10, "ego_vehicle": 11, "ego_cabin": 12, "sky": 13, "traffic_sign": 14,
}
CLASS_NAMES: dict[int, str] = {v: k for k, v in CLASS_IDS.items()}
# False colours for sheets and viewers (sRGB uint8), Cityscapes-like where a class exists there.
CLASS_COLORS: dict[str, tuple[int, int, int]] = {
    "unlabeled": (0, 0, 0), "road": (128, 64, 128), "marking": (255, 255, 255), "kerb": (196, 196, 0),
    "sidewalk": (244, 35, 232), "terrain": (152, 251, 152), "building": (70, 70, 70), "bridge": (150, 100, 100),
    "pole": (153, 153, 153), "vegetation": (107, 142, 35), "vehicle": (0, 0, 142), "ego_vehicle": (0, 60, 100),
    "ego_cabin": (120, 10, 10), "sky": (70, 130, 180), "traffic_sign": (220, 220, 0),
}

_log = logging.getLogger(__name__)
_KERB_OUT_M = layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M


def _street_side_classes(parts) -> list[np.ndarray]:
    """Classes of _road_and_streetside's parts: by material, and for concrete by |x| (kerb inside the sidewalk)."""
    out = []
    for part in parts:
        mat = np.round(part["params"][:, 2]).astype(int)
        # Per triangle: its centroid's |x| (a kerb box's faces all lie at |x| ≤ the kerb's back).
        x = np.abs(part["position"][:, 0].reshape(-1, 3).mean(axis=1)).repeat(3)
        cls = np.full(len(part), CLASS_IDS["terrain"], np.uint8)
        cls[mat == MAT_ASPHALT] = CLASS_IDS["road"]
        cls[mat == MAT_PAINT] = CLASS_IDS["marking"]
        concrete = mat == MAT_CONCRETE
        cls[concrete & (x <= _KERB_OUT_M + 1e-3)] = CLASS_IDS["kerb"]
        cls[concrete & (x > _KERB_OUT_M + 1e-3)] = CLASS_IDS["sidewalk"]
        out.append(cls)
    return out


def _rebuilt_parts(seed: int) -> list[tuple[list[np.ndarray], str | None]]:
    """build_world's parts in its order, each group with its class (None: by material, the street side): the
    world builder's own grouping at detail 1 (rain_core.world.build._world_parts); world_classes checks the
    result equals the world's vertices."""
    from rain_core.world.build import _world_parts

    return [(group, name) for name, group in _world_parts(seed, 1.0).groups]


def material_classes(vertices: np.ndarray) -> np.ndarray:
    """A coarse class per vertex from its material alone (the fallback when a world's parts cannot be told apart):
    asphalt road, paint marking, concrete sidewalk, metal pole, foliage vegetation, glass building, else building."""
    mat = np.round(vertices["params"][:, 2]).astype(int)
    cls = np.full(len(vertices), CLASS_IDS["building"], np.uint8)
    for m, name in ((MAT_ASPHALT, "road"), (MAT_PAINT, "marking"), (MAT_CONCRETE, "sidewalk"), (MAT_METAL, "pole"),
                    (MAT_FOLIAGE, "vegetation"), (MAT_GLASS, "building")):
        cls[mat == m] = CLASS_IDS[name]
    return cls


def world_classes(world) -> np.ndarray:
    """uint8 class id per vertex of ``world.vertices`` (a rain_core.world.World). The world is one concatenation of
    parts (road and street side, bridge, station, lamps, trees, buildings, zebra crossings, sign posts and plates,
    parked cars, shop signs); the parts are rebuilt from the world's seed to learn where each ends. If they do not
    reproduce the world (another detail level, a changed builder), the classes come from the materials alone and a
    warning is logged."""
    from rain_core.mesh import concat

    groups = _rebuilt_parts(int(world.seed))
    parts = [p for group, _ in groups for p in group]
    rebuilt = concat(parts)
    if len(rebuilt) != len(world.vertices) or not np.array_equal(rebuilt["position"], world.vertices["position"]):
        _log.warning("labels: the world's parts could not be rebuilt (seed %s); classes from materials only",
                     world.seed)
        return material_classes(world.vertices)
    out = []
    for group, name in groups:
        group = [p for p in group if len(p)]
        if name is None:
            out += _street_side_classes(group)
        else:
            out += [np.full(len(p), CLASS_IDS[name], np.uint8) for p in group]
    return np.concatenate(out)


def cabin_classes(vertices: np.ndarray) -> np.ndarray:
    """Class per vertex of rain_core.car_mesh.cabin_mesh: the painted outside (hood, mirrors) is the ego vehicle,
    the rest its cabin."""
    outside = np.round(vertices["params"][:, 2]) == MAT_CAR_PAINT
    return np.where(outside, CLASS_IDS["ego_vehicle"], CLASS_IDS["ego_cabin"]).astype(np.uint8)
