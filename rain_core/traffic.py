"""Traffic and the autopilot: car following (the intelligent driver model), vehicles that keep their lanes, and
the ego car's autopilot. Moved out of ``rain_core.vehicles`` (which still exports these names).

Frames and conventions as ``rain_core.vehicles``; the lanes are ``layout.LANE_CENTRES_X`` / ``LANE_YAW``, each a
ring of ``layout.PERIOD_M`` when a vehicle looks for the one ahead.
"""

from __future__ import annotations

import math

import numpy as np

from rain_core import layout
from rain_core.collision import WALL_X_M
from rain_core.vehicles import (
    PERIOD_M,
    SPECS,
    TRAFFIC_SUBSTEP_S,
    Vehicle,
    VehicleSpec,
    _check_dt,
    _forward,
    wrap_z,
)

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
    dx = abs(vehicle.position.item(0) - layout.LANE_CENTRES_X[lane_index])
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

    _phase_floats: tuple | None = None  # (the phases array, its two values as floats): see lateral_target_m

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
        # The phases as Python floats, made on first use (an autopilot pickled before them has none): the float64
        # scalars' arithmetic is the floats' (the same bits) at several times the cost, every frame.
        phases = self._phase_floats
        if phases is None or phases[0] is not self._phases:
            phases = self._phase_floats = (self._phases, *self._phases.tolist())
        _, p0, p1 = phases
        return self.wander_m * (0.6 * math.sin(math.tau * t / 17.0 + p0) + 0.4 * math.sin(math.tau * t / 7.3 + p1))

    def controls(self, car: Vehicle, dt_s: float, others=None) -> tuple[float, float, float]:
        """(throttle [0,1], brake [0,1], steer [−1,1]) for ``car`` this frame; dt_s (s) advances the wander clock."""
        self.time_s += _check_dt(dt_s)
        spec = car.spec
        v = car.speed_m_s
        lane = self.lane_index
        d = _lane_direction(lane)
        # Pure pursuit (Coulter 1992): aim the rear axle at a point on the (wandering) lane line ahead.
        lookahead = max(self.min_lookahead_m, self.lookahead_s * abs(v))
        # w = lane point (lane x, 0, rear z) + d·lookahead + (right of d)·lateral − rear axle, with right of d =
        # (−d_z, 0, d_x) and rear axle = position − forward·wheelbase/2: the arrays' operations on scalars, in
        # their order (the same bits); the dot products and the norm stay NumPy's.
        d0, d1, d2 = d.tolist()
        lateral = self.lateral_target_m()
        half = spec.wheelbase_m / 2.0
        yaw = car.yaw
        p0, p1, p2 = car.position.tolist()
        rear0, rear1, rear2 = p0 - -math.sin(yaw) * half, p1 - 0.0 * half, p2 - -math.cos(yaw) * half
        w = np.array([(layout.LANE_CENTRES_X[lane] + d0 * lookahead) + -d2 * lateral - rear0,
                      (0.0 + d1 * lookahead) + 0.0 * lateral - rear1,
                      (rear2 + d2 * lookahead) + d0 * lateral - rear2])
        fwd = car.forward()
        left = -car.right()
        alpha = math.atan2(float(w @ left), float(w @ fwd))
        # np.linalg.norm(w) is sqrt(w.dot(w)) (its own formula for a float vector), without its Python-level checks.
        delta = math.atan(2.0 * spec.wheelbase_m * math.sin(alpha) / max(math.sqrt(w.dot(w)), 1e-6))
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
        around = self.ego.position.item(2) if self.ego is not None else 0.0
        for v in self.vehicles:
            z = v.position.item(2)
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

    def _all_lane_members(self) -> list[list[tuple[Vehicle, float, float, float]]]:
        """For each lane, (vehicle, s m, half length m, speed along the lane m/s) of every vehicle in it, the ego
        included in each lane it is in (between two: both), in one pass over the vehicles."""
        members: list[list] = [[] for _ in _LANE_DIRECTIONS]
        for v, lane in zip(self.vehicles, self.lanes, strict=True):
            members[lane].append((v, float(v.position @ _LANE_DIRECTIONS[lane]), v.spec.length_m / 2.0, v.speed_m_s))
        ego = self.ego
        if ego is not None:
            velocity = None
            for lane, d in enumerate(_LANE_DIRECTIONS):
                if _in_lane(ego, lane):
                    velocity = ego.velocity() if velocity is None else velocity
                    members[lane].append((ego, float(ego.position @ d), ego.spec.length_m / 2.0,
                                          float(velocity @ d)))
        return members

    def _substep(self, h: float) -> None:
        members = self._all_lane_members()
        accels = []
        for v, lane, desired in zip(self.vehicles, self.lanes, self.desired_speeds_m_s, strict=True):
            others = []
            for m in members[lane]:  # v is among its lane's members, with its s = position · lane direction
                if m[0] is v:
                    s = m[1]
                else:
                    others.append(m[1:])
            gap, lead_speed = _leader(s, v.spec.length_m / 2.0, others)
            accels.append(idm_accel(v.speed_m_s, desired, gap, v.speed_m_s - lead_speed, v.spec.max_accel_m_s2,
                                    v.spec.max_brake_m_s2))
        for v, a in zip(self.vehicles, accels, strict=True):
            v1 = max(0.0, v.speed_m_s + a * h)
            ds = 0.5 * (v.speed_m_s + v1) * h
            p0, p1, p2 = v.position.tolist()  # position + forward()·ds, in scalars (the same bits, no temporaries)
            v.position = np.array([p0 + -math.sin(v.yaw) * ds, p1 + 0.0 * ds, p2 + -math.cos(v.yaw) * ds])
            v.speed_m_s = v1
            v.odometer_m += ds
        self._enforce_gaps()

    def _enforce_gaps(self) -> None:
        """Never let a vehicle overlap the one ahead: if the IDM could not brake hard enough (e.g. the ego car
        stopped dead in front), hold it HARD_MIN_GAP_M behind at the leader's speed. A few passes settle chains."""
        for _ in range(4):
            moved = False
            # All lanes' members at once: a vehicle moved here is a member of its own lane alone (the ego, which
            # may be in two, is never moved), so the later lanes' lists are what they would be made after it.
            for lane, members in enumerate(self._all_lane_members()):
                d = _lane_direction(lane)
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
