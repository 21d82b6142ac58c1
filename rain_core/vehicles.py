"""Vehicles: the ego car (kinematic bicycle model), traffic that follows the lanes, and an autopilot.

Frames and conventions (DESIGN §2): world +Y up, metres. ``yaw`` 0 faces −Z and positive yaw turns left
(counter-clockwise seen from above, +Y). A vehicle's local frame has forward −Z, right +X, up +Y and its origin on
the ground under the body centre; ``Vehicle.position`` is that origin in the world (y = 0, the road plane). The
axles sit symmetrically at ±wheelbase/2 about the body centre, so the body centre is also the midpoint between them.

Steering: ``steer_rad`` > 0 (and steer input > 0) turns left, like yaw.

The world is periodic along Z with ``layout.PERIOD_M``. The ego car's z stays continuous (the renderer draws the
periodic tiles); ``Traffic`` keeps the other vehicles within ±PERIOD_M/2 of the ego car and treats each lane as a
ring of that length when it looks for the vehicle ahead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import checks, layout
from rain_core.collision import kerb_crossings, kerb_speed

PERIOD_M = layout.PERIOD_M
KINDS = ("car", "van", "truck")

MAX_STEP_DT_S = 1.0  # s; a longer step (debugger pause, window drag) is simulated as this much time
EGO_SUBSTEP_S = 0.01  # s; the bicycle model integrates in sub-steps no longer than this
TRAFFIC_SUBSTEP_S = 0.05  # s; car-following (IDM) sub-step
HEADLIGHT_PITCH_RAD = math.radians(-1.5)  # low beams aim slightly down at the road


@dataclass(frozen=True)
class VehicleSpec:
    """Dimensions and performance of a vehicle type. Lengths in m, angles in rad, speeds m/s, accelerations m/s².

    ``drag_per_m`` is the aerodynamic deceleration per speed squared, ½·ρ·Cd·A/mass (1/m); ``rolling_m_s2`` the
    rolling-resistance deceleration. The engine is power-limited: its full-throttle acceleration is
    min(max_accel, p/|v|), with the specific power p chosen so that drag + rolling balance it exactly at
    ``max_speed_m_s`` (see ``engine_accel``). ``max_lat_accel_m_s2`` limits the steering angle at speed.
    """

    kind: str
    length_m: float
    width_m: float
    height_m: float
    wheelbase_m: float
    track_m: float
    wheel_radius_m: float
    tire_width_m: float
    max_steer_rad: float
    max_speed_m_s: float
    max_accel_m_s2: float
    max_brake_m_s2: float
    drag_per_m: float = 2.8e-4
    rolling_m_s2: float = 0.12
    max_lat_accel_m_s2: float = 7.5
    steer_rate_rad_s: float = 0.9
    max_reverse_m_s: float = 6.0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"VehicleSpec.kind must be one of {KINDS}, got {self.kind!r}")
        for name in ("length_m", "width_m", "height_m", "wheelbase_m", "track_m", "wheel_radius_m",
                     "tire_width_m", "max_steer_rad", "max_speed_m_s", "max_accel_m_s2", "max_brake_m_s2",
                     "max_lat_accel_m_s2", "steer_rate_rad_s", "max_reverse_m_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"VehicleSpec.{name} must be a finite number > 0, got {value!r}")
        if self.drag_per_m < 0 or self.rolling_m_s2 < 0:
            raise ValueError("VehicleSpec.drag_per_m and rolling_m_s2 must be ≥ 0")
        if not self.wheelbase_m < self.length_m or not self.track_m < self.width_m:
            raise ValueError("VehicleSpec: wheelbase must be < length and track < width")
        if not self.max_steer_rad < math.radians(60):
            raise ValueError("VehicleSpec.max_steer_rad must be in (0, 60°)")

    @property
    def specific_power(self) -> float:
        """Engine power per unit mass (W/kg = m²/s³) that gives exactly ``max_speed_m_s`` at full throttle."""
        v = self.max_speed_m_s
        return v * (self.drag_per_m * v * v + self.rolling_m_s2)

    def engine_accel(self, speed_m_s: float) -> float:
        """Full-throttle engine acceleration (m/s²) at ground speed ``speed_m_s`` (sign ignored)."""
        v = abs(speed_m_s)
        return self.max_accel_m_s2 if v < 1e-6 else min(self.max_accel_m_s2, self.specific_power / v)

    def resistance(self, speed_m_s: float) -> float:
        """Deceleration (m/s², ≥ 0) from drag and rolling resistance while moving at ``speed_m_s``."""
        v = abs(speed_m_s)
        return self.drag_per_m * v * v + (self.rolling_m_s2 if v > 0 else 0.0)

    def max_steer_at(self, speed_m_s: float) -> float:
        """Largest road-wheel steering angle (rad) allowed at this speed: full lock when slow, then limited so
        the kinematic lateral acceleration v²·tan(δ)/wheelbase stays within ``max_lat_accel_m_s2``."""
        v2 = speed_m_s * speed_m_s
        if v2 < 1e-9:
            return self.max_steer_rad
        return min(self.max_steer_rad, math.atan(self.max_lat_accel_m_s2 * self.wheelbase_m / v2))


# A mid-size saloon: top speed 200 km/h, 0–100 km/h in about 9 s, ~0.9 g braking.
CAR_SPEC = VehicleSpec(kind="car", length_m=4.6, width_m=1.84, height_m=1.45, wheelbase_m=2.70, track_m=1.58,
                       wheel_radius_m=0.32, tire_width_m=0.225, max_steer_rad=0.58, max_speed_m_s=200.0 / 3.6,
                       max_accel_m_s2=3.5, max_brake_m_s2=9.0)
# A panel van (Transit/Sprinter size).
VAN_SPEC = VehicleSpec(kind="van", length_m=5.4, width_m=2.0, height_m=2.35, wheelbase_m=3.3, track_m=1.72,
                       wheel_radius_m=0.35, tire_width_m=0.235, max_steer_rad=0.6, max_speed_m_s=160.0 / 3.6,
                       max_accel_m_s2=2.5, max_brake_m_s2=7.5, drag_per_m=4.5e-4, rolling_m_s2=0.13,
                       max_lat_accel_m_s2=6.0)
# A two-axle box lorry (7.5 t class).
TRUCK_SPEC = VehicleSpec(kind="truck", length_m=8.5, width_m=2.5, height_m=3.4, wheelbase_m=5.0, track_m=2.0,
                         wheel_radius_m=0.5, tire_width_m=0.3, max_steer_rad=0.6, max_speed_m_s=100.0 / 3.6,
                         max_accel_m_s2=1.2, max_brake_m_s2=6.0, drag_per_m=2.6e-4, rolling_m_s2=0.08,
                         max_lat_accel_m_s2=4.0, steer_rate_rad_s=0.6)
SPECS = {"car": CAR_SPEC, "van": VAN_SPEC, "truck": TRUCK_SPEC}


def wrap_z(z, around_z):
    """Shift z (m, scalar or array) by whole multiples of PERIOD_M so it lies nearest to ``around_z`` (m)."""
    return z - PERIOD_M * np.round((np.asarray(z, dtype=np.float64) - around_z) / PERIOD_M)


def wheel_contacts_local(spec: VehicleSpec) -> np.ndarray:
    """(4, 3) contact points in the vehicle's local frame (m), order FL, FR, RL, RR, on the ground (y = 0)."""
    hx, hz = spec.track_m / 2.0, spec.wheelbase_m / 2.0
    return np.array([[-hx, 0.0, -hz], [hx, 0.0, -hz], [-hx, 0.0, hz], [hx, 0.0, hz]])


_CONTACTS_LOCAL: dict[int, tuple[VehicleSpec, np.ndarray]] = {}


def _contacts_local(spec: VehicleSpec) -> np.ndarray:
    """wheel_contacts_local(spec) as a shared read-only array (every vehicle asks every step)."""
    hit = _CONTACTS_LOCAL.get(id(spec))
    if hit is None or hit[0] is not spec:
        if len(_CONTACTS_LOCAL) > 64:
            _CONTACTS_LOCAL.clear()
        local = wheel_contacts_local(spec)
        local.flags.writeable = False
        hit = _CONTACTS_LOCAL[id(spec)] = (spec, local)
    return hit[1]


def light_positions_local(spec: VehicleSpec) -> tuple[np.ndarray, np.ndarray]:
    """Lens centres (m, local frame) of the (2, 3) headlights and the (2, 3) tail lights, left first.

    ``car_mesh`` puts the emissive lenses here, so the light sources and what is drawn agree."""
    hw, hl = spec.width_m / 2.0, spec.length_m / 2.0
    if spec.kind == "car":
        head_x, head_y, tail_x, tail_y = hw - 0.27, 0.66, hw - 0.2, 0.82
    elif spec.kind == "van":
        head_x, head_y, tail_x, tail_y = hw - 0.25, 0.88, hw - 0.1, 1.05
    else:
        head_x, head_y, tail_x, tail_y = hw - 0.3, 0.72, hw - 0.2, 0.8
    head = np.array([[-head_x, head_y, -hl], [head_x, head_y, -hl]])
    tail = np.array([[-tail_x, tail_y, hl], [tail_x, tail_y, hl]])
    return head, tail


def _forward(yaw: float) -> np.ndarray:
    return np.array([-math.sin(yaw), 0.0, -math.cos(yaw)])


class Vehicle:
    """A vehicle on the road: spec, pose and motion. See the module docstring for frames and signs.

    position: (3,) m, the ground point under the body centre (midway between the axles), y = 0.
    yaw: rad. speed_m_s: signed speed of the rear-axle centre along ``forward()`` (negative = reversing).
    steer_rad: road-wheel angle of the (bicycle-model) front wheel, > 0 = left. yaw_rate_rad_s: rad/s.
    color: linear RGB body colour. odometer_m: distance rolled (m, signed), e.g. to spin the wheels.
    previous_wheel_contacts: (4, 3) world contacts at the start of the last step (for sweeping wheel paths).
    """

    def __init__(self, spec: VehicleSpec = CAR_SPEC, position=None, yaw: float = 0.0, speed_m_s: float = 0.0,
                 color=(0.35, 0.02, 0.02)):
        self.spec = spec
        self.position = np.zeros(3) if position is None else np.array(position, dtype=np.float64).reshape(3)
        self.position[1] = 0.0
        self.yaw = float(yaw)
        self.speed_m_s = float(speed_m_s)
        if not (np.all(np.isfinite(self.position)) and math.isfinite(self.yaw) and math.isfinite(self.speed_m_s)):
            raise ValueError("Vehicle position, yaw and speed_m_s must be finite")
        self.steer_rad = 0.0
        self.yaw_rate_rad_s = 0.0
        self.color = np.array(color, dtype=np.float32).reshape(3)
        self.odometer_m = 0.0
        self.previous_wheel_contacts = self.wheel_contacts()

    # --- frame ----------------------------------------------------------------------------------------------
    def forward(self) -> np.ndarray:
        """(3,) unit vector the vehicle faces (world)."""
        return _forward(self.yaw)

    def right(self) -> np.ndarray:
        """(3,) unit vector to the vehicle's right (world)."""
        return np.array([math.cos(self.yaw), 0.0, -math.sin(self.yaw)])

    def model_matrix(self) -> np.ndarray:
        """(4, 4) float64 local→world transform (rotation about +Y by yaw, then translation to position)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        m = np.eye(4)
        m[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
        m[:3, 3] = self.position
        return m

    def to_world(self, points_local) -> np.ndarray:
        """Local-frame points (n, 3) m → world (n, 3) m."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)  # model_matrix's rotation, without the 4×4 per call
        rotation_t = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])
        return np.asarray(points_local, dtype=np.float64) @ rotation_t + self.position

    def rear_axle(self) -> np.ndarray:
        """(3,) world ground point under the rear-axle centre (the bicycle model's reference point), m."""
        return self.position - self.forward() * (self.spec.wheelbase_m / 2.0)

    # --- motion ---------------------------------------------------------------------------------------------
    def _point_velocity(self, points_world: np.ndarray) -> np.ndarray:
        # Rigid planar motion: v_p = v·forward + ω ŷ × (p − rear axle); ŷ × (a, 0, c) = (c, 0, −a).
        rel = np.atleast_2d(points_world) - self.rear_axle()
        v = np.outer(np.ones(len(rel)), self.forward() * self.speed_m_s)
        v[:, 0] += self.yaw_rate_rad_s * rel[:, 2]
        v[:, 2] -= self.yaw_rate_rad_s * rel[:, 0]
        return v

    def velocity(self) -> np.ndarray:
        """(3,) world velocity of the body centre (``position``), m/s."""
        # _point_velocity for one point in scalars (the traffic asks every step): the same operations, so the
        # same bits, without the (1, 3) temporaries.
        fx, fz = -math.sin(self.yaw), -math.cos(self.yaw)
        half = self.spec.wheelbase_m / 2.0
        px, pz = float(self.position[0]), float(self.position[2])
        rel_x, rel_z = px - (px - fx * half), pz - (pz - fz * half)
        w = self.yaw_rate_rad_s
        return np.array([fx * self.speed_m_s + w * rel_z, 0.0 * self.speed_m_s, fz * self.speed_m_s - w * rel_x])

    def wheel_contacts(self) -> np.ndarray:
        """(4, 3) world contact points (m), order FL, FR, RL, RR, on the road plane y = 0."""
        return self.to_world(_contacts_local(self.spec))

    def wheel_speeds(self) -> np.ndarray:
        """(4,) ground speed of each contact point (m/s), order FL, FR, RL, RR; negative while reversing.

        In a turn the outer wheels are faster than the inner ones and the front wheels faster than the rear."""
        speeds = np.linalg.norm(self._point_velocity(self.wheel_contacts()), axis=1)
        return speeds * (-1.0 if self.speed_m_s < 0 else 1.0)

    def wheel_widths(self) -> np.ndarray:
        """(4,) tyre width per wheel (m), order FL, FR, RL, RR."""
        return np.full(4, self.spec.tire_width_m)

    # --- lights ---------------------------------------------------------------------------------------------
    def headlights(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Low-beam sources: list of (position (3,) m, unit direction (3,)) in the world, left then right."""
        head, _ = light_positions_local(self.spec)
        pitch = HEADLIGHT_PITCH_RAD
        direction = self.forward() * math.cos(pitch) + np.array([0.0, math.sin(pitch), 0.0])
        return [(p, direction.copy()) for p in self.to_world(head)]

    def taillights(self) -> np.ndarray:
        """(2, 3) world positions (m) of the tail-light lenses; they shine backwards (−forward())."""
        _, tail = light_positions_local(self.spec)
        return self.to_world(tail)

    def _shift_z(self, dz: float) -> None:
        """Move by a whole number of periods without breaking the swept wheel paths."""
        self.position[2] += dz
        self.previous_wheel_contacts = self.previous_wheel_contacts + np.array([0.0, 0.0, dz])


def _check_dt(dt_s: float) -> float:
    return checks.time_step(dt_s, MAX_STEP_DT_S)


_check_input = checks.clamped


class EgoCar(Vehicle):
    """The driven car: a kinematic bicycle model about the rear axle.

    ``step`` takes throttle [0, 1], brake [0, 1], steer [−1, 1] (+1 = full left) and a reverse gear flag. The
    steering input picks a fraction of ``spec.max_steer_at(speed)``; the road-wheel angle follows it at most at
    ``spec.steer_rate_rad_s``. Inputs outside their range are clamped; NaN/inf raises ValueError.
    """

    def __init__(self, spec: VehicleSpec = CAR_SPEC, position=None, yaw: float = 0.0, speed_m_s: float = 0.0,
                 color=(0.35, 0.02, 0.02)):
        if position is None:
            position = (layout.LANE_CENTRES_X[0], 0.0, 0.0)
        super().__init__(spec, position, yaw, speed_m_s, color)
        self.collider = None  # rain_core.collision.StreetCollider: the street's kerbs, walls and posts (None: none)

    def step(self, dt_s: float, throttle: float, brake: float, steer: float, reverse: bool = False) -> None:
        """Advance dt_s seconds (≥ 0, clamped to MAX_STEP_DT_S; sub-stepped at EGO_SUBSTEP_S)."""
        dt_s = _check_dt(dt_s)
        throttle = _check_input("throttle", throttle, 0.0, 1.0)
        brake = _check_input("brake", brake, 0.0, 1.0)
        steer = _check_input("steer", steer, -1.0, 1.0)
        self.previous_wheel_contacts = self.wheel_contacts()
        if dt_s == 0.0:
            return
        n = max(1, math.ceil(dt_s / EGO_SUBSTEP_S - 1e-9))
        h = dt_s / n
        for _ in range(n):
            if self.collider is None:
                self._substep(h, throttle, brake, steer, bool(reverse))
                continue
            before = self.wheel_contacts()
            self._substep(h, throttle, brake, steer, bool(reverse))
            up, down = kerb_crossings(before, self.wheel_contacts())
            if up or down:
                self.speed_m_s = kerb_speed(self.speed_m_s, up, down)
            self.collider.resolve(self)

    def _substep(self, h: float, throttle: float, brake: float, steer: float, reverse: bool) -> None:
        spec = self.spec
        v = self.speed_m_s
        # Steering: rate-limited toward the commanded fraction of the speed-dependent maximum.
        limit = spec.max_steer_at(v)
        target = steer * limit
        max_change = spec.steer_rate_rad_s * h
        delta = self.steer_rad + min(max(target - self.steer_rad, -max_change), max_change)
        delta = min(max(delta, -limit), limit)
        # Longitudinal: engine and drag first, then brake + rolling resistance as friction that cannot push
        # the car through zero speed (so a braked car stops and stays stopped).
        engine = throttle * spec.engine_accel(v)
        if reverse:
            engine = -engine if v > -spec.max_reverse_m_s else 0.0
        v1 = v + h * (engine - spec.drag_per_m * v * abs(v))
        friction = h * (brake * spec.max_brake_m_s2 + spec.rolling_m_s2)
        v1 = max(0.0, v1 - friction) if v1 > 0 else min(0.0, v1 + friction)
        v1 = min(max(v1, -spec.max_reverse_m_s), spec.max_speed_m_s)
        # Kinematics: the rear axle runs on an arc of radius L/tan(δ) at the mean speed; exact chord.
        v_mean = 0.5 * (v + v1)
        omega = v_mean * math.tan(delta) / spec.wheelbase_m
        dpsi = omega * h
        ds = v_mean * h
        chord = ds * (math.sin(dpsi / 2.0) / (dpsi / 2.0) if abs(dpsi) > 1e-9 else 1.0)
        # rear_axle() + _forward(yaw + dpsi/2)·chord, then the new centre rear + forward()·wheelbase/2: the same
        # operations on x and z in scalars (the same bits), without five 3-vectors per sub-step (y is 0).
        half = spec.wheelbase_m / 2.0
        yaw = self.yaw
        px, pz = float(self.position[0]), float(self.position[2])
        rx = px - -math.sin(yaw) * half + -math.sin(yaw + dpsi / 2.0) * chord
        rz = pz - -math.cos(yaw) * half + -math.cos(yaw + dpsi / 2.0) * chord
        self.yaw = yaw = math.remainder(yaw + dpsi, math.tau)
        self.position = np.array([rx + -math.sin(yaw) * half, 0.0, rz + -math.cos(yaw) * half])
        self.speed_m_s = v1
        self.steer_rad = delta
        self.yaw_rate_rad_s = v1 * math.tan(delta) / spec.wheelbase_m
        self.odometer_m += ds


# --- car following ----------------------------------------------------------------------------------------------
IDM_TIME_GAP_S = 1.5
IDM_MIN_GAP_M = 4.0  # bumper to bumper at standstill
IDM_COMFORT_DECEL_M_S2 = 2.5
HARD_MIN_GAP_M = 1.0  # traffic is never placed closer than this to the vehicle ahead


def idm_accel(speed_m_s: float, desired_m_s: float, gap_m: float, closing_m_s: float, max_accel_m_s2: float,
              max_brake_m_s2: float) -> float:
    """Intelligent Driver Model acceleration (m/s²) (Treiber et al. 2000).

    gap_m: bumper-to-bumper distance to the vehicle ahead (math.inf for a free road); closing_m_s: own speed
    minus the leader's speed along the lane. The result is clamped to [−max_brake, max_accel]."""
    v = max(speed_m_s, 0.0)
    free = 1.0 - (v / max(desired_m_s, 0.1)) ** 4
    if math.isfinite(gap_m):
        s_star = IDM_MIN_GAP_M + max(0.0, v * IDM_TIME_GAP_S
                                     + v * closing_m_s / (2.0 * math.sqrt(max_accel_m_s2 * IDM_COMFORT_DECEL_M_S2)))
        interaction = (s_star / max(gap_m, 0.1)) ** 2
    else:
        interaction = 0.0
    return min(max(max_accel_m_s2 * (free - interaction), -max_brake_m_s2), max_accel_m_s2)


def _lane_direction_array(yaw: float) -> np.ndarray:
    d = _forward(yaw)
    d.flags.writeable = False  # shared: every caller only reads it
    return d


_LANE_DIRECTIONS = tuple(_lane_direction_array(yaw) for yaw in layout.LANE_YAW)


def _lane_direction(lane_index: int) -> np.ndarray:
    """Unit vector (3,) along a lane's driving direction (a shared read-only array: the traffic asks per step)."""
    return _LANE_DIRECTIONS[lane_index]


def _in_lane(vehicle: Vehicle, lane_index: int) -> bool:
    """Whether a vehicle overlaps the lane by more than 0.3 m sideways."""
    dx = abs(float(vehicle.position[0]) - layout.LANE_CENTRES_X[lane_index])
    return dx < 0.5 * (layout.LANE_WIDTH_M + vehicle.spec.width_m) - 0.3


def _leader(s_self: float, half_len_self: float, others) -> tuple[float, float]:
    """(bumper gap m, leader speed m/s along the lane) to the nearest of ``others`` ahead on the lane ring.

    others: iterable of (s m, half length m, speed along lane m/s). A free road gives (inf, 0)."""
    best_gap, best_speed, best_ds = math.inf, 0.0, math.inf
    for s, half_len, speed in others:
        ds = (s - s_self) % PERIOD_M
        if 0.0 < ds < best_ds:
            best_ds, best_gap, best_speed = ds, ds - half_len - half_len_self, speed
    return best_gap, best_speed


class Autopilot:
    """Drives a car along one lane: pure-pursuit steering on the lane centre and speed hold (deterministic).

    lane_index: index into layout.LANE_CENTRES_X / LANE_YAW. target_speed_m_s: cruise speed (m/s). seed: sets the
    phases of a slow lateral wander of ±wander_m (m) that keeps the wheel tracks from being ruler-straight
    (wander_m=0 drives exactly on the centre line). Given ``others`` (vehicles), it also keeps an IDM gap to
    whatever is ahead in its lane.
    """

    def __init__(self, lane_index: int = 0, target_speed_m_s: float = 100.0 / 3.6, seed: int = 0,
                 wander_m: float = 0.08, lookahead_s: float = 0.9, min_lookahead_m: float = 6.0):
        if lane_index not in range(len(layout.LANE_CENTRES_X)):
            raise ValueError(f"lane_index must be in [0, {len(layout.LANE_CENTRES_X) - 1}], got {lane_index!r}")
        if not (math.isfinite(target_speed_m_s) and 0.0 <= target_speed_m_s <= 60.0):
            raise ValueError(f"target_speed_m_s must be in [0, 60] m/s, got {target_speed_m_s!r}")
        if not (math.isfinite(wander_m) and 0.0 <= wander_m <= 0.5):
            raise ValueError(f"wander_m must be in [0, 0.5] m, got {wander_m!r}")
        self.lane_index = lane_index
        self.target_speed_m_s = float(target_speed_m_s)
        self.wander_m = float(wander_m)
        self.lookahead_s = float(lookahead_s)
        self.min_lookahead_m = float(min_lookahead_m)
        rng = np.random.default_rng(seed)
        self._phases = rng.uniform(0.0, math.tau, 2)
        self.time_s = 0.0
        self.reverse = False  # backing away from a wall (recovery): the gear the caller passes to the car

    def lateral_target_m(self) -> float:
        """Where the autopilot aims now, m to the right of the lane centre (seeded slow wander)."""
        t = self.time_s
        return self.wander_m * (0.6 * math.sin(math.tau * t / 17.0 + self._phases[0])
                                + 0.4 * math.sin(math.tau * t / 7.3 + self._phases[1]))

    def controls(self, car: Vehicle, dt_s: float, others=None) -> tuple[float, float, float]:
        """(throttle [0,1], brake [0,1], steer [−1,1]) for ``car`` this frame; dt_s (s) advances the wander clock."""
        self.time_s += _check_dt(dt_s)
        spec = car.spec
        v = car.speed_m_s
        lane = self.lane_index
        d = _lane_direction(lane)
        lane_right = np.array([-d[2], 0.0, d[0]])  # right of the lane direction (d rotated clockwise)
        rear = car.rear_axle()
        # Pure pursuit (Coulter 1992): aim the rear axle at a point on the (wandering) lane line ahead.
        lookahead = max(self.min_lookahead_m, self.lookahead_s * abs(v))
        lane_point = np.array([layout.LANE_CENTRES_X[lane], 0.0, rear[2]])
        target = lane_point + d * lookahead + lane_right * self.lateral_target_m()
        w = target - rear
        fwd = car.forward()
        left = -car.right()
        alpha = math.atan2(float(w @ left), float(w @ fwd))
        delta = math.atan(2.0 * spec.wheelbase_m * math.sin(alpha) / max(float(np.linalg.norm(w)), 1e-6))
        steer = min(max(delta / spec.max_steer_at(v), -1.0), 1.0)
        recovery = self._recover(car, fwd, alpha)
        if recovery is not None:
            return recovery
        # Speed: P control on speed, feed-forward of drag and rolling, capped by an IDM gap to the car ahead.
        accel = min(max(0.8 * (self.target_speed_m_s - v), -spec.max_brake_m_s2), spec.max_accel_m_s2)
        if others:
            accel = min(accel, self._follow_accel(car, others, d))
        need = accel + spec.resistance(v)
        if need >= 0.0:
            return min(need / spec.engine_accel(v), 1.0), 0.0, steer
        return 0.0, min(-need / spec.max_brake_m_s2, 1.0), steer

    def _recover(self, car: Vehicle, fwd: np.ndarray, alpha: float) -> tuple[float, float, float] | None:
        """From a pose off its lane (across the kerb, facing a façade): brake before the wall, back away with the
        wheels turned so the nose swings towards the lane, then drive on. None: drive normally."""
        from rain_core.collision import WALL_X_M

        v = car.speed_m_s
        heading_x = float(fwd[0])
        ahead = math.inf  # m along the heading to the wall it points at
        if abs(heading_x) > 1e-3:
            ahead = (WALL_X_M - math.copysign(1.0, heading_x) * float(car.position[0])) / abs(heading_x)
        front = ahead - car.spec.length_m / 2.0
        if self.reverse and (abs(alpha) < math.radians(40.0) or front > 8.0):
            self.reverse = False
        elif not self.reverse and front < 2.5 + max(v, 0.0) ** 2 / 8.0 and abs(alpha) > math.radians(25.0):
            if v > 0.5:
                return 0.0, 1.0, 0.0  # stop short of the wall first
            self.reverse = True
        if not self.reverse:
            return None
        if v > 0.2:
            return 0.0, 1.0, 0.0
        return 0.5, 0.0, -math.copysign(1.0, alpha)  # reversing: turning against alpha swings the nose to it

    def _follow_accel(self, car: Vehicle, others, d: np.ndarray) -> float:
        s_self = float(car.position @ d)
        ahead = [(float(o.position @ d), o.spec.length_m / 2.0, float(o.velocity() @ d))
                 for o in others if o is not car and _in_lane(o, self.lane_index)]
        gap, lead_speed = _leader(s_self, car.spec.length_m / 2.0, ahead)
        if gap > 250.0:  # ring distances beyond sight are not "ahead"
            return math.inf
        v = float(car.velocity() @ d)
        return idm_accel(v, max(self.target_speed_m_s, 0.1), gap, v - lead_speed, car.spec.max_accel_m_s2,
                         car.spec.max_brake_m_s2)


# Body colours of traffic (linear RGB): white, black, silver, dark grey, blue, red, green-grey, beige.
_PALETTE = np.array([[0.80, 0.80, 0.78], [0.02, 0.02, 0.022], [0.45, 0.46, 0.48], [0.10, 0.10, 0.11],
                     [0.03, 0.07, 0.25], [0.40, 0.02, 0.02], [0.12, 0.16, 0.13], [0.55, 0.45, 0.30]])
_SPEED_RANGE_KMH = {"car": (40.0, 110.0), "van": (40.0, 100.0), "truck": (40.0, 85.0)}


class Traffic:
    """Other vehicles following the four lanes with the Intelligent Driver Model.

    count: number of vehicles (default 5); every fifth from the third on is a truck and every fifth from the fifth
    on a van, so any count ≥ 3 has at least one larger vehicle. seed: lanes, desired speeds (40–110 km/h for cars,
    less for vans and trucks), spacing and colours. ego: the driven car; traffic keeps a gap to it when it is in
    their lane, starts around it, and is kept within ±PERIOD_M/2 of its z. Without an ego, traffic stays around
    z = 0.
    """

    SPAWN_HALF_RANGE_M = 300.0  # m around the ego car where traffic starts
    SPAWN_SPACING_M = 25.0  # m, minimum start distance between centres in a lane (plus half lengths)

    def __init__(self, count: int = 5, seed: int = 0, ego: Vehicle | None = None):
        count = int(count)
        max_count = len(layout.LANE_CENTRES_X) * int(PERIOD_M // 40.0)
        if not 0 <= count <= max_count:
            raise ValueError(f"count must be in [0, {max_count}] vehicles, got {count}")
        rng = np.random.default_rng(seed)
        self.ego = ego
        self.vehicles: list[Vehicle] = []
        self.lanes: list[int] = []
        self.desired_speeds_m_s: list[float] = []
        lane_order = rng.permutation(len(layout.LANE_CENTRES_X))
        centre_z = float(ego.position[2]) if ego is not None else 0.0
        for i in range(count):
            kind = "truck" if i % 5 == 2 else "van" if i % 5 == 4 else "car"
            spec = SPECS[kind]
            lane = int(lane_order[i % len(lane_order)])
            lo, hi = _SPEED_RANGE_KMH[kind]
            desired = min(rng.uniform(lo, hi) / 3.6, spec.max_speed_m_s)
            z = self._spawn_z(rng, lane, spec, centre_z)
            color = _PALETTE[rng.integers(len(_PALETTE))] * rng.uniform(0.85, 1.0)
            if kind == "truck":
                color = np.array([0.75, 0.75, 0.72]) * rng.uniform(0.85, 1.0)  # white box body
            v = Vehicle(spec, (layout.LANE_CENTRES_X[lane], 0.0, z), layout.LANE_YAW[lane], desired, color)
            self.vehicles.append(v)
            self.lanes.append(lane)
            self.desired_speeds_m_s.append(float(desired))
        self._wrap()
        for v in self.vehicles:
            v.previous_wheel_contacts = v.wheel_contacts()

    def _spawn_z(self, rng, lane: int, spec: VehicleSpec, centre_z: float) -> float:
        """A start z (m) in ``lane`` clear of the vehicles placed so far and of the ego car."""
        occupied = [(float(v.position[2]), v.spec.length_m / 2.0)
                    for v, l in zip(self.vehicles, self.lanes, strict=True) if l == lane]
        if self.ego is not None and _in_lane(self.ego, lane):
            occupied.append((float(self.ego.position[2]), self.ego.spec.length_m / 2.0 + 10.0))
        half = spec.length_m / 2.0

        def clear(z: float) -> bool:
            return all(abs(float(wrap_z(z, oz)) - oz) >= self.SPAWN_SPACING_M + half + oh for oz, oh in occupied)

        for _ in range(200):
            z = centre_z + rng.uniform(-self.SPAWN_HALF_RANGE_M, self.SPAWN_HALF_RANGE_M)
            if clear(z):
                return z
        # Crowded: the middle of the largest free stretch of the lane ring.
        zs = np.sort(np.array([float(wrap_z(oz, centre_z)) for oz, _ in occupied]))
        gaps = np.diff(np.append(zs, zs[0] + PERIOD_M))
        k = int(np.argmax(gaps))
        return float(wrap_z(zs[k] + gaps[k] / 2.0, centre_z))

    def _wrap(self) -> None:
        around = float(self.ego.position[2]) if self.ego is not None else 0.0
        for v in self.vehicles:
            z = float(v.position[2])
            # wrap_z for one float: Python's round, like np.round, rounds halves to even.
            dz = (z - PERIOD_M * round((z - around) / PERIOD_M)) - z
            if dz != 0.0:
                v._shift_z(dz)

    def step(self, dt_s: float) -> None:
        """Advance traffic by dt_s seconds (≥ 0, clamped to MAX_STEP_DT_S; IDM sub-steps of ≤ 0.05 s)."""
        dt_s = _check_dt(dt_s)
        for v in self.vehicles:
            v.previous_wheel_contacts = v.wheel_contacts()
        if dt_s == 0.0 or not self.vehicles:
            return
        n = max(1, math.ceil(dt_s / TRAFFIC_SUBSTEP_S - 1e-9))
        h = dt_s / n
        for _ in range(n):
            self._substep(h)
        self._wrap()

    def _lane_members(self, lane: int, d: np.ndarray) -> list[tuple[Vehicle, float, float, float]]:
        """(vehicle, s m, half length m, speed along the lane m/s) for every vehicle in the lane, ego included."""
        members = [(v, float(v.position @ d), v.spec.length_m / 2.0, v.speed_m_s)
                   for v, l in zip(self.vehicles, self.lanes, strict=True) if l == lane]
        if self.ego is not None and _in_lane(self.ego, lane):
            members.append((self.ego, float(self.ego.position @ d), self.ego.spec.length_m / 2.0,
                            float(self.ego.velocity() @ d)))
        return members

    def _substep(self, h: float) -> None:
        members = [self._lane_members(lane, _lane_direction(lane)) for lane in range(len(layout.LANE_CENTRES_X))]
        accels = []
        for v, lane, desired in zip(self.vehicles, self.lanes, self.desired_speeds_m_s, strict=True):
            s = float(v.position @ _lane_direction(lane))
            gap, lead_speed = _leader(s, v.spec.length_m / 2.0, [m[1:] for m in members[lane] if m[0] is not v])
            accels.append(idm_accel(v.speed_m_s, desired, gap, v.speed_m_s - lead_speed, v.spec.max_accel_m_s2,
                                    v.spec.max_brake_m_s2))
        for v, a in zip(self.vehicles, accels, strict=True):
            v1 = max(0.0, v.speed_m_s + a * h)
            ds = 0.5 * (v.speed_m_s + v1) * h
            p = v.position  # position + forward()·ds, in scalars (the same bits, no temporaries)
            v.position = np.array([p[0] + -math.sin(v.yaw) * ds, p[1] + 0.0 * ds, p[2] + -math.cos(v.yaw) * ds])
            v.speed_m_s = v1
            v.odometer_m += ds
        self._enforce_gaps()

    def _enforce_gaps(self) -> None:
        """Never let a vehicle overlap the one ahead: if the IDM could not brake hard enough (e.g. the ego car
        stopped dead in front), hold it HARD_MIN_GAP_M behind at the leader's speed. A few passes settle chains."""
        for _ in range(4):
            moved = False
            for lane in range(len(layout.LANE_CENTRES_X)):
                d = _lane_direction(lane)
                members = self._lane_members(lane, d)
                for v, s, half, _ in members:
                    if v is self.ego:
                        continue
                    ahead = [(o, (so - s) % PERIOD_M, ho) for o, so, ho, _ in members if o is not v]
                    if not ahead:
                        continue
                    o, ds, ho = min(ahead, key=lambda a: a[1])
                    gap = ds - half - ho
                    if gap < HARD_MIN_GAP_M:
                        v.position = v.position - d * (HARD_MIN_GAP_M - gap)
                        v.speed_m_s = max(0.0, min(v.speed_m_s, float(o.velocity() @ d)))
                        moved = True
            if not moved:
                break
