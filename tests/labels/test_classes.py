"""Class ids: stable, complete over the world; the world's parts are told apart (GL-free)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rain_core.labels import CLASS_COLORS, CLASS_IDS, CLASS_NAMES, world_classes
from rain_core.labels.classes import material_classes
from rain_core.mesh import MAT_ASPHALT, MAT_CAR_PAINT, MAT_FOLIAGE, MAT_PAINT

SHADERS = Path(__file__).resolve().parents[2] / "shaders"


def test_ids_are_stable_and_unique():
    # Recorded datasets keep their meaning: these numbers never change (new classes go at the end).
    assert CLASS_IDS == {"unlabeled": 0, "road": 1, "marking": 2, "kerb": 3, "sidewalk": 4, "terrain": 5,
                         "building": 6, "bridge": 7, "pole": 8, "vegetation": 9, "vehicle": 10, "ego_vehicle": 11,
                         "ego_cabin": 12, "sky": 13, "traffic_sign": 14}
    assert len(set(CLASS_IDS.values())) == len(CLASS_IDS)
    assert set(CLASS_COLORS) == set(CLASS_IDS)
    assert len(set(CLASS_COLORS.values())) == len(CLASS_COLORS)
    assert {CLASS_NAMES[i] for i in CLASS_IDS.values()} == set(CLASS_IDS)


@pytest.fixture(scope="module")
def world():
    from rain_core.world import build_world

    return build_world(seed=3)


def test_world_classes_follow_the_parts(world, caplog):
    classes = world_classes(world)
    assert "could not be rebuilt" not in caplog.text  # the parts reproduced the world exactly
    assert classes.shape == (len(world.vertices),) and classes.dtype == np.uint8
    mat = np.round(world.vertices["params"][:, 2]).astype(int)
    assert np.all(classes[mat == MAT_ASPHALT] == CLASS_IDS["road"])
    x = world.vertices["position"][:, 0]
    y = world.vertices["position"][:, 1]
    on_road = (np.abs(x) < 7.0) & (y < 0.01)
    assert np.all(classes[(mat == MAT_PAINT) & on_road] == CLASS_IDS["marking"])
    assert np.all(classes[(mat == MAT_PAINT) & ~on_road] == CLASS_IDS["traffic_sign"])  # signs are painted
    assert np.all(y[classes == CLASS_IDS["traffic_sign"]] > 1.0)
    assert np.all(classes[mat == MAT_CAR_PAINT] == CLASS_IDS["vehicle"])  # parked cars
    assert np.all(classes[mat == MAT_FOLIAGE] == CLASS_IDS["vegetation"])
    for name in ("kerb", "sidewalk", "terrain", "building", "bridge", "pole", "vegetation", "vehicle",
                 "traffic_sign"):
        assert np.any(classes == CLASS_IDS[name]), name
    kerb = classes == CLASS_IDS["kerb"]
    assert np.all((np.abs(x[kerb]) >= 6.99) & (np.abs(x[kerb]) <= 7.31))  # between the road and the sidewalk
    assert np.all(np.abs(x[classes == CLASS_IDS["sidewalk"]]) >= 7.29)
    assert np.all(y[classes == CLASS_IDS["pole"]] > -0.2)
    assert not np.any(classes == CLASS_IDS["unlabeled"])


def test_a_world_that_cannot_be_rebuilt_falls_back_to_materials(world, caplog):
    from dataclasses import replace

    other = replace(world, vertices=world.vertices[:-3])  # not what seed 3 builds
    classes = world_classes(other)
    assert "could not be rebuilt" in caplog.text
    assert np.array_equal(classes, material_classes(other.vertices))


def test_region_threshold_matches_the_road():
    from rain_core.effects.road.surface import WET_MIN

    src = (SHADERS / "labels" / "geometry.frag").read_text()
    assert float(re.search(r"const float WET_MIN = ([0-9.]+);", src).group(1)) == WET_MIN
    assert '#include "road/film.glsl"' in src  # the film model itself is the road's, not a copy
