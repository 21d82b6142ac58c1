"""The street's fixed layout, shared by the world builder, vehicles and effects.

World frame: right-handed, +Y up, metres. The road runs along Z. The world is periodic along Z with
period ``PERIOD_M`` so the autopilot can drive forever: everything placed at z also exists at z + k·PERIOD_M.
Right-hand traffic: vehicles heading −Z (yaw 0) use lanes at +X; vehicles heading +Z (yaw π) use lanes at −X.
"""

PERIOD_M = 1200.0  # m, length of one world tile along Z
LANE_WIDTH_M = 3.5  # m
LANES_PER_DIRECTION = 2
ROAD_HALF_WIDTH_M = LANE_WIDTH_M * LANES_PER_DIRECTION  # m, kerb face at |x| = 7.0
KERB_HEIGHT_M = 0.15  # m
KERB_WIDTH_M = 0.3  # m
SIDEWALK_WIDTH_M = 3.0  # m, beyond the kerb
BUILDING_SETBACK_M = ROAD_HALF_WIDTH_M + KERB_WIDTH_M + SIDEWALK_WIDTH_M + 1.0  # m, nearest façade |x|

# Lane centre x (m) and heading (yaw, rad; yaw 0 faces −Z). Index 0/1: −Z-bound (right, x>0); 2/3: +Z-bound.
LANE_CENTRES_X = (1.75, 5.25, -1.75, -5.25)
LANE_YAW = (0.0, 0.0, 3.141592653589793, 3.141592653589793)

# Where the fixed props sit along one tile (m, z in [0, PERIOD_M)). The underpass bridge spans the road, the
# fuel-station canopy stands over the outer −Z-bound lane and the sidewalk.
BRIDGE_Z_M = 300.0
BRIDGE_DEPTH_M = 14.0  # m along Z
BRIDGE_CLEARANCE_M = 5.2  # m, underside above the road
CANOPY_Z_M = 700.0
CANOPY_LENGTH_M = 24.0  # m along Z
CANOPY_X_RANGE_M = (3.5, 16.0)  # m
CANOPY_HEIGHT_M = 5.0  # m, underside
