"""Vehicles: their specs and meshes' anchors, the ego car (kinematic bicycle model); the traffic that follows the
lanes and the autopilot are in ``rain_core.traffic`` (their names are still importable from here).

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
import struct
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


_PACK_YAW = struct.Struct("d").pack


class Vehicle:
    """A vehicle on the road: spec, pose and motion. See the module docstring for frames and signs.

    position: (3,) m, the ground point under the body centre (midway between the axles), y = 0.
    yaw: rad. speed_m_s: signed speed of the rear-axle centre along ``forward()`` (negative = reversing).
    steer_rad: road-wheel angle of the (bicycle-model) front wheel, > 0 = left. yaw_rate_rad_s: rad/s.
    color: linear RGB body colour. odometer_m: distance rolled (m, signed), e.g. to spin the wheels.
    previous_wheel_contacts: (4, 3) world contacts at the start of the last step (for sweeping wheel paths).
    """

    # (pose key, spec, value) of what is derived from the pose alone and asked many times a frame (the step, the
    # ripples, the spray, the renderer's passes): kept, read-only, until the pose's bits or the spec change.
    _contacts_cache: tuple | None = None
    _model_cache: tuple | None = None
    _rotation_cache: tuple | None = None  # (yaw bits, to_world's transposed rotation)
    _turned_cache: tuple | None = None  # (yaw bits, spec, the local wheel contacts rotated by the yaw)

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

    def _pose_key(self) -> bytes:
        """The pose's exact bits (position, yaw; a −0.0 differs from a 0.0 here): the position is mutated in place
        (collisions, the period shift), so a cache compares values, not the array."""
        return self.position.tobytes() + _PACK_YAW(self.yaw)

    def model_matrix(self) -> np.ndarray:
        """(4, 4) float64 local→world transform (rotation about +Y by yaw, then translation to position);
        read-only (kept while the pose stays: copy it to change it)."""
        key = self._pose_key()
        cached = self._model_cache
        if cached is not None and cached[0] == key:
            return cached[1]
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x, y, z = self.position.tolist()  # Python floats, as float() of each
        model = np.array([[c, 0.0, s, x], [0.0, 1.0, 0.0, y], [-s, 0.0, c, z], [0.0, 0.0, 0.0, 1.0]])
        model.flags.writeable = False
        self._model_cache = (key, model)
        return model

    def _rotation_t(self, yaw: bytes) -> np.ndarray:
        """to_world's transposed rotation for the yaw whose bits are ``yaw`` (the traffic's yaw stays: made once)."""
        cached = self._rotation_cache
        if cached is not None and cached[0] == yaw:
            return cached[1]
        c, s = math.cos(self.yaw), math.sin(self.yaw)  # model_matrix's rotation, without the 4×4 per call
        rotation_t = np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])
        self._rotation_cache = (yaw, rotation_t)
        return rotation_t

    def to_world(self, points_local) -> np.ndarray:
        """Local-frame points (n, 3) m → world (n, 3) m."""
        return np.asarray(points_local, dtype=np.float64) @ self._rotation_t(_PACK_YAW(self.yaw)) + self.position

    def rear_axle(self) -> np.ndarray:
        """(3,) world ground point under the rear-axle centre (the bicycle model's reference point), m."""
        return self.position - self.forward() * (self.spec.wheelbase_m / 2.0)

    # --- motion ---------------------------------------------------------------------------------------------
    def _point_velocity(self, points_world: np.ndarray) -> np.ndarray:
        # Rigid planar motion: v_p = v·forward + ω ŷ × (p − rear axle); ŷ × (a, 0, c) = (c, 0, −a).
        rel = np.asarray(points_world, dtype=np.float64).reshape(-1, 3) - self.rear_axle()
        v = np.empty_like(rel)
        v[:] = self.forward() * self.speed_m_s  # every row the body's velocity along its heading
        v[:, 0] += self.yaw_rate_rad_s * rel[:, 2]
        v[:, 2] -= self.yaw_rate_rad_s * rel[:, 0]
        return v

    def velocity(self) -> np.ndarray:
        """(3,) world velocity of the body centre (``position``), m/s."""
        # _point_velocity for one point in scalars (the traffic asks every step): the same operations, so the
        # same bits, without the (1, 3) temporaries.
        fx, fz = -math.sin(self.yaw), -math.cos(self.yaw)
        half = self.spec.wheelbase_m / 2.0
        px, _, pz = self.position.tolist()
        rel_x, rel_z = px - (px - fx * half), pz - (pz - fz * half)
        w = self.yaw_rate_rad_s
        return np.array([fx * self.speed_m_s + w * rel_z, 0.0 * self.speed_m_s, fz * self.speed_m_s - w * rel_x])

    def wheel_contacts(self) -> np.ndarray:
        """(4, 3) world contact points (m), order FL, FR, RL, RR, on the road plane y = 0; read-only (kept while
        the pose and the spec stay)."""
        key = self._pose_key()
        cached = self._contacts_cache
        spec = self.spec
        if cached is not None and cached[0] == key and cached[1] is spec:
            return cached[2]
        # to_world(local contacts) = (local @ rotation) + position: the product is kept while the yaw and the spec
        # stay (the traffic moves along its lane without turning), and adding the position is to_world's last step.
        yaw = key[-8:]  # (the pose key ends with the yaw's bits)
        turned = self._turned_cache
        if turned is None or turned[0] != yaw or turned[1] is not spec:
            turned = self._turned_cache = (yaw, spec, _contacts_local(spec) @ self._rotation_t(yaw))
        contacts = turned[2] + self.position
        contacts.flags.writeable = False
        self._contacts_cache = (key, self.spec, contacts)
        return contacts

    def wheel_speeds(self) -> np.ndarray:
        """(4,) ground speed of each contact point (m/s), order FL, FR, RL, RR; negative while reversing.

        In a turn the outer wheels are faster than the inner ones and the front wheels faster than the rear."""
        v = self._point_velocity(self.wheel_contacts())
        speeds = np.sqrt(np.add.reduce(v * v, axis=1))  # np.linalg.norm(v, axis=1)'s operations
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


_INSIDE = np.zeros((4, 3))  # contacts standing for a pose whose wheels are all inside the kerb lines (x = 0)
_INSIDE.flags.writeable = False


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
        contacts = self.previous_wheel_contacts
        # Every wheel lies within ``reach`` of the centre across x: while |x| + reach stays inside the kerb lines
        # no wheel can cross one, and the sub-step's contacts are not made (a pose inside counts as _INSIDE).
        reach = self._wheel_reach()
        for _ in range(n):
            if self.collider is None:
                self._substep(h, throttle, brake, steer, bool(reverse))
                continue
            before = contacts
            self._substep(h, throttle, brake, steer, bool(reverse))
            contacts = self._contacts_near_kerb(reach)
            if before is not _INSIDE or contacts is not _INSIDE:
                up, down = kerb_crossings(before, contacts)
                if up or down:
                    self.speed_m_s = kerb_speed(self.speed_m_s, up, down)
            if self.collider.resolve(self):  # pushed out of something: the wheels moved with the body
                contacts = self._contacts_near_kerb(reach)

    def _wheel_reach(self) -> float:
        """An upper bound (m) of any wheel contact's |x − position x|: the contacts' local reach (|c·lx + s·lz| ≤
        hypot(lx, lz), wheel_contacts_local's ±track/2, ±wheelbase/2) and a µm for the rounding of to_world's."""
        return math.hypot(self.spec.track_m / 2.0, self.spec.wheelbase_m / 2.0) + 1e-6

    def _contacts_near_kerb(self, reach: float) -> np.ndarray:
        """wheel_contacts(), or _INSIDE (every wheel is inside the kerb lines, as they are) when the centre is
        further than ``reach`` inside them."""
        if abs(self.position.item(0)) + reach < layout.ROAD_HALF_WIDTH_M:
            return _INSIDE
        return self.wheel_contacts()

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
        px, _, pz = self.position.tolist()
        rx = px - -math.sin(yaw) * half + -math.sin(yaw + dpsi / 2.0) * chord
        rz = pz - -math.cos(yaw) * half + -math.cos(yaw + dpsi / 2.0) * chord
        self.yaw = yaw = math.remainder(yaw + dpsi, math.tau)
        self.position = np.array([rx + -math.sin(yaw) * half, 0.0, rz + -math.cos(yaw) * half])
        self.speed_m_s = v1
        self.steer_rad = delta
        self.yaw_rate_rad_s = v1 * math.tan(delta) / spec.wheelbase_m
        self.odometer_m += ds


# The traffic and the autopilot live in rain_core.traffic; their names stay importable from here (lazily: traffic
# imports this module).
_TRAFFIC_NAMES = frozenset({"Autopilot", "Traffic", "idm_accel", "IDM_TIME_GAP_S", "IDM_MIN_GAP_M",
                            "IDM_COMFORT_DECEL_M_S2", "HARD_MIN_GAP_M"})


def __getattr__(name: str):
    if name in _TRAFFIC_NAMES:
        from rain_core import traffic

        return getattr(traffic, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
