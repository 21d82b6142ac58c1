"""Vehicles: bicycle-model kinematics, wheel contacts, dt robustness, autopilot, traffic and the periodic world."""

import math

import numpy as np
import pytest

from rain_core import layout
from rain_core.vehicles import (
    CAR_SPEC,
    PERIOD_M,
    TRUCK_SPEC,
    VAN_SPEC,
    Autopilot,
    EgoCar,
    Traffic,
    Vehicle,
    VehicleSpec,
    wrap_z,
)


def _fit_circle(xz: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares circle (Kåsa fit) through (n, 2) points → (centre, radius)."""
    x, z = xz[:, 0], xz[:, 1]
    a = np.column_stack([2 * x, 2 * z, np.ones_like(x)])
    (cx, cz, c), *_ = np.linalg.lstsq(a, x * x + z * z, rcond=None)
    return np.array([cx, cz]), math.sqrt(c + cx * cx + cz * cz)


def _hold_speed(car: EgoCar, target: float) -> float:
    """Throttle that holds ``target`` m/s against drag and rolling resistance (test helper)."""
    need = 2.0 * (target - car.speed_m_s) + car.spec.resistance(car.speed_m_s)
    return min(max(need / car.spec.engine_accel(car.speed_m_s), 0.0), 1.0)


@pytest.mark.parametrize("steer", [1.0, 0.5, -0.4])
def test_turn_radius_matches_bicycle_model(steer):
    car = EgoCar(speed_m_s=3.0)
    for _ in range(300):  # let the rate-limited steering settle
        car.step(0.01, _hold_speed(car, 3.0), 0.0, steer)
    delta = steer * CAR_SPEC.max_steer_rad  # full lock is allowed at 3 m/s
    assert car.steer_rad == pytest.approx(delta, rel=1e-6)
    path = []
    for _ in range(1500):
        car.step(0.02, _hold_speed(car, 3.0), 0.0, steer)
        path.append(car.rear_axle()[[0, 2]])
    centre, radius = _fit_circle(np.array(path))
    expected = CAR_SPEC.wheelbase_m / math.tan(abs(delta))
    assert radius == pytest.approx(expected, rel=0.02)
    # Positive steer turns left: seen from the car (yaw ≈ heading), the centre lies on its left.
    to_centre = np.array([centre[0], 0.0, centre[1]]) - car.rear_axle()
    assert np.sign(to_centre @ -car.right()) == np.sign(steer)
    assert np.sign(car.yaw_rate_rad_s) == np.sign(steer)


def test_top_speed_is_200_kmh_and_acceleration_plausible():
    car = EgoCar()
    t, t100 = 0.0, None
    while t < 180.0:
        car.step(1.0 / 30.0, 1.0, 0.0, 0.0)
        t += 1.0 / 30.0
        if t100 is None and car.speed_m_s >= 100.0 / 3.6:
            t100 = t
    assert car.speed_m_s * 3.6 == pytest.approx(200.0, rel=0.05)
    assert car.speed_m_s <= CAR_SPEC.max_speed_m_s + 1e-9
    assert 6.0 < t100 < 14.0  # 0–100 km/h of a mid-size saloon


def test_larger_vehicles_are_slower():
    for spec in (VAN_SPEC, TRUCK_SPEC):
        car = EgoCar(spec=spec)
        for _ in range(4000):
            car.step(0.05, 1.0, 0.0, 0.0)
        assert car.speed_m_s == pytest.approx(spec.max_speed_m_s, rel=0.05)
        assert spec.max_speed_m_s < CAR_SPEC.max_speed_m_s


def test_steering_is_limited_at_speed():
    car = EgoCar(speed_m_s=50.0)
    for _ in range(200):
        car.step(0.01, _hold_speed(car, 50.0), 0.0, 1.0)
    v = car.speed_m_s
    lateral = v * v * math.tan(car.steer_rad) / CAR_SPEC.wheelbase_m
    assert 0.0 < lateral <= CAR_SPEC.max_lat_accel_m_s2 * 1.001
    assert car.steer_rad < 0.05 * CAR_SPEC.max_steer_rad


def test_steering_is_rate_limited():
    car = EgoCar(speed_m_s=2.0)
    car.step(0.1, 0.0, 0.0, 1.0)
    assert car.steer_rad == pytest.approx(CAR_SPEC.steer_rate_rad_s * 0.1, rel=1e-6)


def test_wheel_contacts_lie_on_the_road_at_the_track():
    rng = np.random.default_rng(3)
    for spec in (CAR_SPEC, VAN_SPEC, TRUCK_SPEC):
        for _ in range(20):
            v = Vehicle(spec, position=(rng.uniform(-7, 7), 0.0, rng.uniform(-2000, 2000)),
                        yaw=rng.uniform(-4, 4))
            c = v.wheel_contacts()
            assert c.shape == (4, 3)
            np.testing.assert_allclose(c[:, 1], 0.0, atol=1e-12)
            rel = c - v.position
            np.testing.assert_allclose(rel @ v.right(), [-spec.track_m / 2, spec.track_m / 2] * 2, atol=1e-9)
            np.testing.assert_allclose(rel @ v.forward(), [spec.wheelbase_m / 2] * 2 + [-spec.wheelbase_m / 2] * 2,
                                       atol=1e-9)
            local = np.c_[c, np.ones(4)] @ np.linalg.inv(v.model_matrix()).T
            np.testing.assert_allclose(local[:, 1], 0.0, atol=1e-9)
            np.testing.assert_allclose(v.wheel_widths(), spec.tire_width_m)


def test_model_matrix_axes():
    v = Vehicle(CAR_SPEC, position=(1.0, 0.0, 2.0), yaw=0.7)
    m = v.model_matrix()
    assert m.dtype == np.float64 and m.shape == (4, 4)
    np.testing.assert_allclose(m[:3, :3] @ [0, 0, -1], v.forward(), atol=1e-12)
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], v.right(), atol=1e-12)
    np.testing.assert_allclose(m[:3, 3], v.position)
    # yaw 0 faces −Z; a small positive yaw turns the nose toward −X (left).
    assert Vehicle(CAR_SPEC, yaw=0.1).forward()[0] < 0
    np.testing.assert_allclose(Vehicle(CAR_SPEC).forward(), [0, 0, -1], atol=1e-12)


def test_wheel_speeds_outer_faster_in_a_turn():
    car = EgoCar(speed_m_s=8.0)
    for _ in range(200):
        car.step(0.01, _hold_speed(car, 8.0), 0.0, 0.6)  # left turn
    fl, fr, rl, rr = car.wheel_speeds()
    assert fr > fl and rr > rl  # right wheels are outside
    assert fl > rl and fr > rr  # front wheels run on a larger radius than the rear ones
    # Rear axle centre moves at the model speed, so the rear wheels straddle it.
    assert 0.5 * (rl + rr) == pytest.approx(car.speed_m_s, rel=1e-9)
    # In a kinematic turn each wheel's speed is ω · its distance from the turn centre.
    radius = CAR_SPEC.wheelbase_m / math.tan(car.steer_rad)
    assert rr / rl == pytest.approx((radius + CAR_SPEC.track_m / 2) / (radius - CAR_SPEC.track_m / 2), rel=1e-9)
    straight = EgoCar(speed_m_s=10.0)
    np.testing.assert_allclose(straight.wheel_speeds(), 10.0)
    assert np.all(EgoCar(speed_m_s=-2.0).wheel_speeds() < 0)


def test_previous_wheel_contacts_sweep_the_last_step():
    car = EgoCar(speed_m_s=30.0)
    before = car.wheel_contacts()
    car.step(0.1, 0.5, 0.0, 0.2)
    np.testing.assert_array_equal(car.previous_wheel_contacts, before)
    travelled = np.linalg.norm(car.wheel_contacts() - car.previous_wheel_contacts, axis=1)
    assert np.all(travelled == pytest.approx(3.0, rel=0.05))


def test_velocity_matches_motion():
    car = EgoCar(speed_m_s=20.0)
    for _ in range(50):
        car.step(0.01, 0.3, 0.0, 0.3)
    p0, v0 = car.position.copy(), car.velocity()
    car.step(0.001, 0.3, 0.0, 0.3)
    np.testing.assert_allclose((car.position - p0) / 0.001, v0, rtol=1e-3, atol=1e-3)


def test_dt_stress_stays_finite_and_bounded():
    rng = np.random.default_rng(7)
    car = EgoCar(speed_m_s=20.0)
    for _ in range(600):
        dt = float(10 ** rng.uniform(-6, 0))
        car.step(dt, rng.uniform(0, 1), rng.uniform(0, 1) * (rng.uniform() < 0.2), rng.uniform(-1, 1),
                 reverse=bool(rng.uniform() < 0.05))
        assert np.all(np.isfinite(car.position)) and math.isfinite(car.yaw) and math.isfinite(car.speed_m_s)
        assert -CAR_SPEC.max_reverse_m_s <= car.speed_m_s <= CAR_SPEC.max_speed_m_s
        assert car.position[1] == 0.0
        assert abs(car.steer_rad) <= CAR_SPEC.max_steer_rad + 1e-12
    for dt in (1e-6, 1.0, 0.0):
        car.step(dt, 1.0, 0.0, 1.0)
        assert np.all(np.isfinite(car.wheel_contacts()))


def test_huge_dt_is_clamped_and_bad_input_rejected():
    car = EgoCar(speed_m_s=50.0)
    z0 = car.position[2]
    car.step(1e6, 1.0, 0.0, 0.0)
    assert abs(car.position[2] - z0) <= CAR_SPEC.max_speed_m_s * 1.0 + 1e-6
    for bad in (float("nan"), float("inf"), -0.1):
        with pytest.raises(ValueError):
            car.step(bad, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError):
        car.step(0.1, float("nan"), 0.0, 0.0)
    with pytest.raises(ValueError):
        car.step(0.1, 0.0, 0.0, float("inf"))
    with pytest.raises(ValueError):
        Autopilot().controls(car, float("nan"))
    with pytest.raises(ValueError):
        Traffic(count=3).step(float("nan"))


def test_result_does_not_depend_much_on_dt():
    def drive(dt):
        car = EgoCar(speed_m_s=10.0)
        for second in range(12):  # inputs held for whole seconds, so both frame rates see the same inputs
            for _ in range(round(1.0 / dt)):
                car.step(dt, 0.6, 0.0, 0.4 * math.sin(second))
        return car.position.copy()

    a, b = drive(1.0 / 240.0), drive(0.25)
    assert np.linalg.norm(a - b) < 0.3  # after ~200 m of curvy driving


def test_brake_stops_and_holds_and_reverse_goes_back():
    car = EgoCar(speed_m_s=30.0)
    z0 = car.position[2]
    for _ in range(600):
        car.step(0.01, 0.0, 1.0, 0.0)
    assert car.speed_m_s == 0.0
    stop = z0 - car.position[2]
    assert stop == pytest.approx(30.0 ** 2 / (2 * CAR_SPEC.max_brake_m_s2), rel=0.1)
    z1 = car.position[2]
    for _ in range(100):
        car.step(0.05, 0.0, 0.0, 0.0)
    assert car.position[2] == z1  # rolling resistance holds a stopped car; no creeping
    for _ in range(300):
        car.step(0.05, 1.0, 0.0, 0.0, reverse=True)
    assert car.position[2] > z1  # backwards is +Z at yaw 0
    assert car.speed_m_s == pytest.approx(-CAR_SPEC.max_reverse_m_s, rel=0.02)


def _run_autopilot(lane, seconds, start_offset=0.0, yaw_error=0.0, dt=1.0 / 60.0, seed=0):
    x = layout.LANE_CENTRES_X[lane]
    yaw = layout.LANE_YAW[lane] + yaw_error
    car = EgoCar(position=(x + start_offset, 0.0, 30.0), yaw=yaw, speed_m_s=100.0 / 3.6)
    pilot = Autopilot(lane_index=lane, target_speed_m_s=100.0 / 3.6, seed=seed)
    t, rows = 0.0, []
    while t < seconds:
        throttle, brake, steer = pilot.controls(car, dt)
        car.step(dt, throttle, brake, steer)
        t += dt
        rows.append((t, car.position[0] - x, car.position[2], car.speed_m_s))
    return car, np.array(rows)


@pytest.mark.parametrize("lane", [0, 3])
def test_autopilot_keeps_lane_at_100_kmh_through_a_wrap(lane):
    car, rows = _run_autopilot(lane, 60.0, start_offset=0.8, yaw_error=-0.02)
    settled = rows[rows[:, 0] > 8.0]
    assert np.max(np.abs(settled[:, 1])) < 0.3
    assert np.abs(settled[:, 3] * 3.6 - 100.0).max() < 3.0
    travelled = abs(rows[-1, 2] - 30.0)
    assert travelled > PERIOD_M  # the raw z crossed at least one period boundary
    assert np.floor(rows[0, 2] / PERIOD_M) != np.floor(rows[-1, 2] / PERIOD_M)


def test_autopilot_is_deterministic_and_seeded():
    _, a = _run_autopilot(1, 20.0, seed=5)
    _, b = _run_autopilot(1, 20.0, seed=5)
    _, c = _run_autopilot(1, 20.0, seed=6)
    np.testing.assert_array_equal(a, b)
    assert np.abs(a[:, 1] - c[:, 1]).max() > 1e-3  # the seed sets the lateral wander


def test_autopilot_follows_a_slower_car():
    ego = EgoCar(position=(layout.LANE_CENTRES_X[0], 0.0, 0.0), speed_m_s=100.0 / 3.6)
    slow = Vehicle(CAR_SPEC, position=(layout.LANE_CENTRES_X[0], 0.0, -80.0), speed_m_s=50.0 / 3.6)
    pilot = Autopilot(lane_index=0, target_speed_m_s=100.0 / 3.6, wander_m=0.0)
    gaps = []
    for _ in range(60 * 40):
        throttle, brake, steer = pilot.controls(ego, 1.0 / 60.0, others=[slow])
        ego.step(1.0 / 60.0, throttle, brake, steer)
        slow.position = slow.position + slow.velocity() / 60.0
        gaps.append((ego.position[2] - slow.position[2]) - CAR_SPEC.length_m)
    assert min(gaps) > 5.0
    assert ego.speed_m_s == pytest.approx(slow.speed_m_s, abs=0.5)


def test_wrap_z():
    assert wrap_z(0.0, 0.0) == 0.0
    assert wrap_z(PERIOD_M * 3 + 5.0, 10.0) == pytest.approx(5.0)
    assert wrap_z(-PERIOD_M * 0.6, 0.0) == pytest.approx(PERIOD_M * 0.4)
    z = np.linspace(-5000, 5000, 101)
    w = wrap_z(z, 777.0)
    assert np.all(np.abs(w - 777.0) <= PERIOD_M / 2 + 1e-9)
    k = (w - z) / PERIOD_M
    np.testing.assert_allclose(k, np.round(k), atol=1e-12)  # shifted by whole periods only


def test_traffic_composition_and_lanes():
    ego = EgoCar()
    traffic = Traffic(count=5, seed=0, ego=ego)
    assert len(traffic.vehicles) == 5
    kinds = [v.spec.kind for v in traffic.vehicles]
    assert "truck" in kinds or "van" in kinds
    assert any(v.spec.kind in ("van", "truck") for v in Traffic(count=3, seed=9).vehicles)
    for v, lane in zip(traffic.vehicles, traffic.lanes, strict=True):
        assert v.position[0] == pytest.approx(layout.LANE_CENTRES_X[lane])
        assert v.yaw == pytest.approx(layout.LANE_YAW[lane])
        assert abs(v.position[2] - ego.position[2]) <= PERIOD_M / 2
        assert np.all(np.isfinite(v.color))
    speeds = np.array(traffic.desired_speeds_m_s) * 3.6
    assert np.all((speeds >= 40.0) & (speeds <= 110.0))
    assert len(np.unique(np.round(speeds, 3))) == 5
    assert len(Traffic(count=0).vehicles) == 0
    with pytest.raises(ValueError):
        Traffic(count=-1)
    with pytest.raises(ValueError):
        Traffic(count=10_000)


def _lane_gaps(traffic: Traffic, ego: EgoCar) -> float:
    """Smallest bumper-to-bumper gap (m) between any two vehicles in the same lane, the ego included."""
    smallest = math.inf
    for lane in range(4):
        d = np.array([0.0, 0.0, -1.0]) if layout.LANE_YAW[lane] == 0.0 else np.array([0.0, 0.0, 1.0])
        members = [(v.position @ d, v.spec.length_m / 2) for v, l in zip(traffic.vehicles, traffic.lanes,
                                                                           strict=True) if l == lane]
        if abs(ego.position[0] - layout.LANE_CENTRES_X[lane]) < 1.0:
            members.append((ego.position @ d, ego.spec.length_m / 2))
        for i, (si, hi) in enumerate(members):
            for j, (sj, hj) in enumerate(members):
                if i != j:
                    smallest = min(smallest, (sj - si) % PERIOD_M - hi - hj)
    return smallest


def test_traffic_keeps_gaps_and_stays_near_ego():
    ego = EgoCar(position=(layout.LANE_CENTRES_X[0], 0.0, 0.0), speed_m_s=90.0 / 3.6)
    pilot = Autopilot(lane_index=0, target_speed_m_s=90.0 / 3.6, seed=1)
    traffic = Traffic(count=14, seed=2, ego=ego)
    dt = 1.0 / 20.0
    smallest = math.inf
    for _ in range(int(120.0 / dt)):
        throttle, brake, steer = pilot.controls(ego, dt, others=traffic.vehicles)
        ego.step(dt, throttle, brake, steer)
        traffic.step(dt)
        smallest = min(smallest, _lane_gaps(traffic, ego))
        for v in traffic.vehicles:
            assert abs(v.position[2] - ego.position[2]) <= PERIOD_M / 2 + 1e-6
            # A wrap must not turn into a 1200 m sweep of the wheel path.
            assert np.abs(v.wheel_contacts() - v.previous_wheel_contacts).max() < 5.0
    assert smallest > 4.0
    speeds = [v.speed_m_s for v in traffic.vehicles]
    assert np.ptp(speeds) > 3.0  # not all at one speed


def test_traffic_stops_behind_a_stopped_ego():
    ego = EgoCar(position=(layout.LANE_CENTRES_X[1], 0.0, -100.0), speed_m_s=0.0)
    traffic = Traffic(count=1, seed=0, ego=ego)
    car = traffic.vehicles[0]
    traffic.lanes[0] = 1
    traffic.desired_speeds_m_s[0] = 100.0 / 3.6
    car.position = np.array([layout.LANE_CENTRES_X[1], 0.0, 60.0])
    car.yaw, car.speed_m_s = 0.0, 100.0 / 3.6
    for _ in range(600):
        traffic.step(0.05)
    gap = (car.position[2] - ego.position[2]) - (car.spec.length_m + ego.spec.length_m) / 2
    assert car.speed_m_s < 0.1
    assert 2.0 < gap < 10.0


def test_traffic_is_deterministic():
    def run(seed):
        ego = EgoCar(speed_m_s=25.0)
        traffic = Traffic(count=6, seed=seed, ego=ego)
        for _ in range(400):
            ego.step(0.05, 0.5, 0.0, 0.0)
            traffic.step(0.05)
        return np.array([v.position for v in traffic.vehicles])

    np.testing.assert_array_equal(run(11), run(11))
    assert not np.array_equal(run(11), run(12))


def test_lights():
    for spec in (CAR_SPEC, VAN_SPEC, TRUCK_SPEC):
        v = Vehicle(spec, position=(3.0, 0.0, -40.0), yaw=0.4)
        heads = v.headlights()
        assert len(heads) == 2
        for pos, direction in heads:
            assert (pos - v.position) @ v.forward() == pytest.approx(spec.length_m / 2)
            assert np.linalg.norm(direction) == pytest.approx(1.0)
            assert direction @ v.forward() > 0.99 and direction[1] < 0  # aimed ahead, slightly down
            assert 0.4 < pos[1] < 1.5
        tails = v.taillights()
        assert tails.shape == (2, 3)
        np.testing.assert_allclose((tails - v.position) @ v.forward(), -spec.length_m / 2)


def test_spec_validation():
    with pytest.raises(ValueError):
        VehicleSpec("bus", 10, 2.5, 3, 6, 2, 0.5, 0.3, 0.5, 25, 1, 5)
    with pytest.raises(ValueError):
        VehicleSpec("car", 4, 1.8, 1.4, 5.0, 1.5, 0.3, 0.2, 0.5, 50, 3, 9)  # wheelbase longer than the car


def test_pose_caches_follow_every_change_of_the_pose():
    """wheel_contacts and model_matrix are kept while the pose's bits stay: after a step, an in-place move of the
    position (a collision push, the period shift), a new yaw (−0.0 after 0.0 included) or a new spec, each equals
    a fresh computation, bit for bit, and is read-only."""
    from rain_core.vehicles import _contacts_local

    def fresh(car):
        c, s = math.cos(car.yaw), math.sin(car.yaw)
        x, y, z = (float(v) for v in car.position)
        model = np.array([[c, 0.0, s, x], [0.0, 1.0, 0.0, y], [-s, 0.0, c, z], [0.0, 0.0, 0.0, 1.0]])
        return car.to_world(_contacts_local(car.spec)), model

    def check(car):
        contacts, model = fresh(car)
        for _ in range(2):  # made, then kept
            got_c, got_m = car.wheel_contacts(), car.model_matrix()
            assert got_c.tobytes() == contacts.tobytes() and got_m.tobytes() == model.tobytes()
            assert not got_c.flags.writeable and not got_m.flags.writeable

    car = EgoCar(position=(1.75, 0.0, 10.0), speed_m_s=20.0)
    check(car)
    car.step(1 / 30, 0.5, 0.0, 0.3)
    check(car)
    car.position[0] += 0.25  # in place, as a collision pushes
    check(car)
    car._shift_z(-400.0)
    check(car)
    car.yaw = 0.0
    check(car)
    car.yaw = -0.0
    assert car.model_matrix()[0, 2] == 0.0 and math.copysign(1.0, car.model_matrix()[0, 2]) == -1.0
    check(car)
    car.spec = TRUCK_SPEC
    check(car)
    other = Vehicle(position=(5.25, 0.0, 3.0), yaw=math.pi)
    check(other)


def test_autopilot_steering_in_scalars_is_the_array_formula():
    """Autopilot.controls builds the pursuit vector in scalars: over random poses, lanes and times the steering
    equals the array formula's (lane point + d·lookahead + right·lateral − rear axle), bit for bit."""
    from rain_core.traffic import _lane_direction

    rng = np.random.default_rng(9)
    compared = 0
    for _ in range(400):
        lane = int(rng.integers(4))
        pilot = Autopilot(lane_index=lane, target_speed_m_s=20.0, seed=int(rng.integers(100)))
        car = EgoCar(position=(rng.uniform(-9.0, 9.0), 0.0, rng.uniform(-500.0, 500.0)),
                     yaw=rng.uniform(-math.pi, math.pi), speed_m_s=rng.uniform(0.0, 40.0))
        dt = rng.uniform(0.0, 0.1)
        _, _, steer = pilot.controls(car, dt)
        d = _lane_direction(lane)
        lane_right = np.array([-d[2], 0.0, d[0]])
        rear = car.rear_axle()
        lookahead = max(pilot.min_lookahead_m, pilot.lookahead_s * abs(car.speed_m_s))
        target = np.array([layout.LANE_CENTRES_X[lane], 0.0, rear[2]]) + d * lookahead \
            + lane_right * pilot.lateral_target_m()
        w = target - rear
        alpha = math.atan2(float(w @ -car.right()), float(w @ car.forward()))
        delta = math.atan(2.0 * car.spec.wheelbase_m * math.sin(alpha) / max(float(np.linalg.norm(w)), 1e-6))
        want = min(max(delta / car.spec.max_steer_at(car.speed_m_s), -1.0), 1.0)
        if Autopilot(lane_index=lane)._recover(car, car.forward(), alpha) is None:  # not backing off a wall
            assert steer == want
            compared += 1
    assert compared > 100


def test_wheel_contacts_of_a_vehicle_that_keeps_its_yaw_follow_its_moves():
    """The rotated local contacts are kept while the yaw and the spec stay (the traffic's): after moves along the
    lane, in-place pushes, a new yaw and a new spec the contacts equal to_world's, bit for bit."""
    from rain_core.vehicles import _contacts_local

    traffic = Traffic(count=6, seed=4)
    for _ in range(40):
        traffic.step(1 / 30)
        for v in traffic.vehicles:
            assert v.wheel_contacts().tobytes() == v.to_world(_contacts_local(v.spec)).tobytes()
    v = traffic.vehicles[0]
    v.position[0] += 0.125
    v.spec = VAN_SPEC if v.spec is not VAN_SPEC else CAR_SPEC
    assert v.wheel_contacts().tobytes() == v.to_world(_contacts_local(v.spec)).tobytes()
    v.yaw = v.yaw + 0.25
    assert v.wheel_contacts().tobytes() == v.to_world(_contacts_local(v.spec)).tobytes()


def _lane_members(traffic, lane: int, d: np.ndarray) -> list:
    """One lane's members as the traffic made them lane by lane before _all_lane_members (the reference)."""
    from rain_core.traffic import _in_lane

    members = [(v, float(v.position @ d), v.spec.length_m / 2.0, v.speed_m_s)
               for v, l in zip(traffic.vehicles, traffic.lanes, strict=True) if l == lane]
    ego = traffic.ego
    if ego is not None and _in_lane(ego, lane):
        members.append((ego, float(ego.position @ d), ego.spec.length_m / 2.0, float(ego.velocity() @ d)))
    return members


def test_all_lane_members_are_each_lanes_members():
    """Traffic._all_lane_members (one pass) gives what the lane-by-lane formula gives, the ego between two lanes
    included (it is then a member of both)."""
    from rain_core.traffic import _lane_direction

    ego = EgoCar(position=(layout.LANE_CENTRES_X[1], 0.0, 30.0), speed_m_s=15.0)
    traffic = Traffic(count=9, seed=2, ego=ego)
    middle = 0.5 * (layout.LANE_CENTRES_X[0] + layout.LANE_CENTRES_X[1])
    for x, lanes_with_ego in ((layout.LANE_CENTRES_X[1], 1), (middle, 2), (20.0, 0)):
        ego.position[0] = x
        ego.yaw_rate_rad_s = 0.1
        traffic.step(1 / 30)
        want = [_lane_members(traffic, lane, _lane_direction(lane)) for lane in range(len(layout.LANE_CENTRES_X))]
        assert traffic._all_lane_members() == want
        assert sum(any(m[0] is ego for m in lane) for lane in want) == lanes_with_ego


def test_autopilot_wander_in_floats_is_the_arrays():
    """lateral_target_m adds its phases as floats: the array phases' values at any time, also after the phases
    are replaced and for an autopilot made before the floats existed (unpickled: no such attribute)."""
    pilot = Autopilot(seed=5, wander_m=0.3)

    def want(p):
        t = p.time_s
        return p.wander_m * (0.6 * math.sin(math.tau * t / 17.0 + p._phases[0])
                             + 0.4 * math.sin(math.tau * t / 7.3 + p._phases[1]))

    for t in (0.0, 1.0 / 3.0, 17.25, 1234.5):
        pilot.time_s = t
        assert pilot.lateral_target_m() == want(pilot)
    pilot._phases = np.array([0.5, 2.5])
    assert pilot.lateral_target_m() == want(pilot)
    old = Autopilot.__new__(Autopilot)
    old.__dict__.update({k: v for k, v in pilot.__dict__.items() if k != "_phase_floats"})
    assert old.lateral_target_m() == want(pilot)
