"""The procedural street: one periodic tile of road, kerbs, sidewalks, buildings (with shop signs), trees, lamps,
a railway underpass and a fuel station, cars parked half on the sidewalks, road signs and zebra crossings
(``kerbside``), plus the two maps the rain effects read (roof heights and the road heightmap).

Frame and units: +Y up, metres, the road along Z (see ``rain_core.layout``). The world repeats along Z with period
``PERIOD_M``; :func:`build_world` makes ONE tile covering z in [0, PERIOD_M) and the renderer draws it at
z offsets k·PERIOD_M. Objects never overlap their copies in the neighbouring tiles. A Scene takes its street from
:func:`shared_world`: the same read-only tile for every scene of a seed in the process.

Emissive surfaces (``MAT_EMISSIVE``) store emitted radiance in W/sr/m² at 683 lm/W, i.e. luminance in cd/m²
divided by :data:`LUMINOUS_EFFICACY_LM_PER_W`. On that scale a white Lambertian surface in 100 klx sunlight is
about 47, a lamp lens is ~60, a lit window ~0.1. Lamp colours are linear RGB with Rec.709 luminance 1, so
``intensity_cd * color`` is the per-channel intensity.

The road heightmap convention: ``height01 = 0`` is the lowest point of the road surface (water collects there
first: cracks, then ruts and the gutter), ``1`` the highest (crown of dry asphalt). A water level ``f`` in [0, 1]
covers the texels with ``height01 < f``; the crack fill of DESIGN §3 reads ``min(flood_cracks, 1 - height01)``.
"""

from rain_core.world.build import World, build_world
from rain_core.world.heightmap import HEIGHTMAP_EXTENT_M, HEIGHTMAP_TEXEL_M, make_road_heightmap, sample_heightmap
from rain_core.world.occluders import OCCLUDER_CELL_M, OCCLUDER_COARSE_CELL_M, OCCLUDER_HALF_X_M, OccluderMap
from rain_core.world.primitives import _rects_up
from rain_core.world.shared import shared_world
from rain_core.world.street import GROUND_HALF_X_M, LUMINOUS_EFFICACY_LM_PER_W, StreetLamp

__all__ = ["GROUND_HALF_X_M", "HEIGHTMAP_EXTENT_M", "HEIGHTMAP_TEXEL_M", "LUMINOUS_EFFICACY_LM_PER_W",
           "OCCLUDER_CELL_M", "OCCLUDER_COARSE_CELL_M", "OCCLUDER_HALF_X_M", "OccluderMap", "StreetLamp", "World",
           "_rects_up", "build_world", "make_road_heightmap", "sample_heightmap", "shared_world"]
