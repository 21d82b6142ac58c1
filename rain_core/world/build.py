"""One tile of the street: the World value and build_world."""


from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import trimesh

from rain_core.mesh import (
    concat,
)
from rain_core.world.facades import shop_signs
from rain_core.world.heightmap import HEIGHTMAP_EXTENT_M, make_road_heightmap, sample_heightmap
from rain_core.world.kerbside import kerbside
from rain_core.world.occluders import (
    OCCLUDER_CELL_M,
    OCCLUDER_COARSE_CELL_M,
    OCCLUDER_HALF_X_M,
    OccluderMap,
    _rasterise_top,
)
from rain_core.world.street import (
    _LAMP_POLE_D,
    GROUND_HALF_X_M,
    StreetLamp,
    _bridge,
    _buildings,
    _road_and_streetside,
    _station,
    _street_lamps,
    _trees,
)


@dataclass(eq=False)
class World:
    """One tile of the street. See the module docstring for frames, units and conventions."""

    seed: int
    vertices: np.ndarray  # VERTEX_DTYPE triangles: all static lit geometry of the tile
    lamps: list[StreetLamp]
    occluders: trimesh.Trimesh  # roofs rain cannot pass: bridge deck + embankment, canopy, roofs, awnings, kiosk,
    # parked cars (two rolled boxes each: lower body and greenhouse)
    road_heightmap: np.ndarray  # float32 (H, W) in [0, 1]; rows along z, columns along x; 0 = lowest
    heightmap_extent_m: tuple[float, float]  # (size_x_m, size_z_m) of the whole heightmap
    occluder_map: OccluderMap  # 0.25 m cells over |x| < OCCLUDER_HALF_X_M
    occluder_map_coarse: OccluderMap  # 2 m cells over |x| < GROUND_HALF_X_M + margin
    # Posts and trunks a car cannot drive through: (N, 3) x, z (m, in the tile), radius (m) (rain_core.collision).
    solid_circles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    # Parked cars' footprints a car cannot drive through: (M, 4) x0, x1, z0, z1 (m, in the tile).
    solid_boxes: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))

    def occluder_height(self, x, z) -> np.ndarray:
        """Height (m) at which a raindrop falling straight down at (x, z) (m) first meets a roof; ``-inf`` where
        it reaches the road or the ground. z is periodic. Resolution: 0.25 m cells (nearest cell centre) for
        |x| < 48 m, 2 m cells beyond; so roof edges are exact to half a cell."""
        fine, inside = self.occluder_map.lookup(x, z)
        coarse, _ = self.occluder_map_coarse.lookup(x, z)
        return np.where(inside, fine, coarse)

    def occluder_height_at(self, x: float, z: float) -> float:
        """``occluder_height`` at one point (x, z) m, in Python scalars (the same cells; m, ``-inf`` for none)."""
        for grid in (self.occluder_map, self.occluder_map_coarse):
            h = grid.height_at(x, z)
            if h is not None:
                return h
        return -math.inf

    def road_height01(self, x, z) -> np.ndarray:
        """Bilinear sample of ``road_heightmap`` at x, z (m), exactly as a GL texture with LINEAR filtering,
        CLAMP_TO_EDGE across x and REPEAT along z, sampled at u = (x + ROAD_HALF_WIDTH_M) / size_x,
        v = z / size_z, with the array uploaded row 0 first (row j ↔ v, column i ↔ u)."""
        return sample_heightmap(self.road_heightmap, self.heightmap_extent_m, x, z)


# ----------------------------------------------------------------------------------------------------------------


@dataclass(eq=False)
class _Parts:
    """build_world's pieces before they are joined: ``groups`` (label class name or None for the street side
    classed by material, vertex arrays) in vertex order, occluder soups, lamps and solids."""

    groups: list
    occ: list
    lamps: list
    solid_circles: np.ndarray
    solid_boxes: np.ndarray


def _world_parts(seed: int, detail: float = 1.0) -> _Parts:
    """The tile's parts for ``seed`` at ``detail``, grouped by label class (rain_core.labels.world_classes rebuilds
    them to tell the parts apart)."""
    rng = np.random.default_rng(seed)
    # Independent streams per part, so changing one part's draws does not reshuffle the others. spawn(n)'s
    # children depend only on their index: the first four are what spawn(4) gave before the kerbside came.
    streams = [np.random.default_rng(s) for s in rng.bit_generator.seed_seq.spawn(7)]
    r_road, r_hmap, r_build, r_trees, r_signs, r_park, r_facade = streams
    segments = max(4, int(round(8 * detail)))
    subdiv = 0 if detail < 0.5 else (1 if detail < 2.0 else 2)

    groups, occ = [(None, _road_and_streetside(r_road))], []
    p, o, bridge_lamps = _bridge()
    groups.append(("bridge", p))
    occ += o
    p, o, station_lamps = _station()
    groups.append(("building", p))
    occ += o
    p, lamps = _street_lamps(segments)
    groups.append(("pole", p))
    p, trunks = _trees(r_trees, segments, subdiv)
    groups.append(("vegetation", p))
    posts = np.array([[math.copysign(_LAMP_POLE_D, lamp.position[0]), lamp.position[2], 0.12] for lamp in lamps])
    posts = posts.reshape(-1, 3)
    p, o, frontage = _buildings(r_build, detail)
    groups.append(("building", p))
    occ += o
    kerb = kerbside(r_signs, r_park, posts, trunks, frontage.doors)
    groups += kerb.groups
    occ += kerb.occ
    groups.append(("building", shop_signs(r_facade, frontage)))
    return _Parts(groups, occ, lamps + bridge_lamps + station_lamps,
                  np.concatenate([posts, trunks, kerb.circles]), kerb.boxes)


def build_world(seed: int = 1, detail: float = 1.0) -> World:
    """Build one tile (z in [0, PERIOD_M) m) of the street, deterministically for ``seed``.

    detail in [0.25, 4] scales tessellation: cylinder segments (8 at 1), foliage sphere subdivisions (1 at 1,
    2 from 2), window granularity (ribbons only below 0.5). The road heightmap does not depend on detail.
    """
    if not (0.25 <= detail <= 4.0):
        raise ValueError(f"detail must be in [0.25, 4], got {detail}")
    parts = _world_parts(seed, detail)
    vertices = concat([p for _, group in parts.groups for p in group])

    occ_tris = np.concatenate(parts.occ)
    occluders = trimesh.Trimesh(vertices=occ_tris.reshape(-1, 3), faces=np.arange(3 * len(occ_tris)).reshape(-1, 3),
                                process=False)
    fine_nx = int(round(2 * OCCLUDER_HALF_X_M / OCCLUDER_CELL_M))
    fine = OccluderMap(_rasterise_top(occ_tris, -OCCLUDER_HALF_X_M, OCCLUDER_CELL_M, fine_nx), -OCCLUDER_HALF_X_M,
                       OCCLUDER_CELL_M)
    half = GROUND_HALF_X_M + 8.0
    coarse_nx = int(round(2 * half / OCCLUDER_COARSE_CELL_M))
    coarse = OccluderMap(_rasterise_top(occ_tris, -half, OCCLUDER_COARSE_CELL_M, coarse_nx), -half,
                         OCCLUDER_COARSE_CELL_M)

    rng = np.random.default_rng(seed)
    r_hmap = np.random.default_rng(rng.bit_generator.seed_seq.spawn(2)[1])
    hmap, _ = make_road_heightmap(r_hmap)
    return World(seed=seed, vertices=vertices, lamps=parts.lamps, occluders=occluders,
                 road_heightmap=hmap, heightmap_extent_m=HEIGHTMAP_EXTENT_M, occluder_map=fine,
                 occluder_map_coarse=coarse, solid_circles=parts.solid_circles, solid_boxes=parts.solid_boxes)
