"""The one table of texture units. A pass binds its textures to its own units, so nothing one effect binds can
be read by mistake by another's shader. Units the scene shader samples must differ from each other; offscreen
passes (simulation steps, tone map, blit) bind their inputs to the scratch units just before they draw and the
scene pass re-binds what it samples every frame.
"""

# Scratch units for offscreen passes (inputs bound right before a draw, never read by the scene shader).
SCRATCH = (0, 1, 2)
IMAGE = 0  # the renderer's tone map and blit: the image being read

# The renderer's own.
SHADOW_MAP = 2  # sun shadow depth, sampled by the scene shader (re-bound every scene draw)

# Road (sampled by the scene shader).
ROAD_RAIN_RINGS = 3
ROAD_HEIGHT = 4
ROAD_MAPS = 5
ROAD_REFLECTION = 6
ROAD_RIPPLES = 7

# Rainfall (vertex-shader inputs of the streak and splash passes: the drop table, the roof maps, the road heights).
RAINFALL_DROPS = 8
RAINFALL_ENV = 9
RAINFALL_OCCLUDER = 17
RAINFALL_OCCLUDER_COARSE = 18
RAINFALL_ROAD_HEIGHT = 19

# Atmosphere.
ATMOSPHERE_GLOW = 10
ATMOSPHERE_DEPTH = 11

# Windshield: each of its passes binds its (up to three) textures here; the fourth is spare.
WINDSHIELD = (12, 13, 14, 15)

# Spray.
SPRAY_DEPTH = 16

# Rainbow (its post pass: the P(θ) table and the scene's depth).
RAINBOW_LUT = 20
RAINBOW_DEPTH = 21

# Drips (vertex-shader inputs: the sites' two tables and the roofs' outflow).
DRIPS = (22, 23, 24)

# The renderer's light grid (gfx/light_grid.py) of the view being drawn: sampled by the scene, glass and drop shaders.
LIGHT_GRID = 25
LIGHT_GRID_DEPTH = 26  # the view's depth, read by the pass that builds the grid

# The door mirrors' view, sampled by the scene shader on the mirror glass: a scratch unit, bound right before the
# scene draw that shows it. (GL 3.3 lets a sampler name any unit below 48 and a fragment shader sample 16 at once.)
DOOR_MIRROR = 1

# What the scene shader samples in one draw: these must all differ (tests/gfx/test_units.py).
SCENE_SHADER = (SHADOW_MAP, ROAD_RAIN_RINGS, ROAD_HEIGHT, ROAD_MAPS, ROAD_REFLECTION, ROAD_RIPPLES, DOOR_MIRROR,
                LIGHT_GRID)
