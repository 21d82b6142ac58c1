"""One read-only street per (seed, detail), shared by every Scene of the process.

The street is fixed by its seed. Building it (~0.4 s) and what depends only on it (the drip sites, ~0.5 s,
cached per world object) once per process instead of once per Scene makes a new Scene cheap: the tests, the
Session and the sweep's workers make many. Its arrays are made read-only and its lamps a tuple, so no scene can
change another's street (a write raises); ``build_world`` still makes a private, writable one.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import numpy as np

from rain_core.world.build import World, build_world
from rain_core.world.occluders import OccluderMap

SHARED_WORLDS = 4  # streets kept (a few MB each)


@lru_cache(maxsize=SHARED_WORLDS)
def shared_world(seed: int = 1, detail: float = 1.0) -> World:
    """``build_world(seed, detail)``, built once per process and read-only (see the module docstring)."""
    return _frozen(build_world(seed=seed, detail=detail))


def _read_only(value):
    if isinstance(value, np.ndarray):
        value.setflags(write=False)
    elif isinstance(value, OccluderMap):
        value.grid.setflags(write=False)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            _read_only(getattr(value, f.name))
    return value


def _frozen(world: World) -> World:
    for f in dataclasses.fields(world):
        _read_only(getattr(world, f.name))
    world.lamps = tuple(world.lamps)
    for lamp in world.lamps:
        _read_only(lamp)
    return world
