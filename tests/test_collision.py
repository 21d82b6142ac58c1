"""The ego car stays in the street: walls where the sidewalks end, posts and trunks solid, the kerb a step that
costs speed; the autopilot backs off a wall and finds its lane; the chase camera never enters a building."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rain_core import layout
from rain_core.collision import WALL_X_M, StreetCollider, box_outline, kerb_speed, street_solids
from rain_core.vehicles import Autopilot, EgoCar
from rain_core.world import build_world


@pytest.fixture(scope="module")
def collider():
    return StreetCollider(street_solids(build_world(seed=1)))


def _car(collider, x=layout.LANE_CENTRES_X[0], z=500.0, yaw=0.0, speed=16.0):
    car = EgoCar(position=np.array([x, 0.0, z]), yaw=yaw, speed_m_s=speed)
    car.collider = collider
    return car


def _max_corner_x(car) -> float:
    h_l, h_w = car.spec.length_m / 2, car.spec.width_m / 2
    f, r = car.forward(), car.right()
    return max(abs(float((car.position + f * a * h_l + r * b * h_w)[0])) for a in (-1, 1) for b in (-1, 1))


@pytest.mark.parametrize("steer", [1.0, -1.0])
@pytest.mark.parametrize("dt", [1 / 60, 1 / 10, 1.0])
def test_full_lock_full_throttle_never_passes_the_facades(collider, steer, dt):
    class Recording(StreetCollider):
        hits = 0

        def resolve(self, car):
            touched = super().resolve(car)
            Recording.hits += touched
            return touched

    car = _car(Recording(collider.solids), z=100.0)  # clear of the forecourt (which opens the +x wall)
    first_hit, speeds = None, []
    t = 0.0
    while t < 20.0:
        before = abs(car.speed_m_s)
        hits = Recording.hits
        car.step(dt, throttle=1.0, brake=0.0, steer=steer)
        t += dt
        assert _max_corner_x(car) <= WALL_X_M + 0.05
        if first_hit is None and Recording.hits > hits:
            first_hit = (t, before)
        speeds.append((t, abs(car.speed_m_s)))
    assert first_hit is not None, "never hit anything"
    after = [v for t, v in speeds if first_hit[0] <= t <= first_hit[0] + 1.0]
    assert min(after) < 0.8 * first_hit[1]  # the impact (a post, a trunk or the wall) costs speed


def test_head_on_into_a_wall_stops_and_bounces_a_little(collider):
    car = _car(collider, x=0.0, yaw=-math.pi / 2, speed=20.0)  # heading +x at 72 km/h
    for _ in range(60):
        car.step(1 / 30, throttle=0.0, brake=0.0, steer=0.0)
    assert _max_corner_x(car) <= WALL_X_M + 0.05 and car.speed_m_s <= 0.5


def test_posts_and_trunks_are_solid(collider):
    world = build_world(seed=1)
    post = world.solid_circles[0]
    x, z = float(post[0]), float(post[1])
    car = _car(collider, x=x, z=z + 15.0, speed=12.0)  # driving −z along the sidewalk, straight at the post
    for _ in range(90):
        car.step(1 / 30, throttle=0.3, brake=0.0, steer=0.0)
        front = float(car.position[2]) - car.spec.length_m / 2
        assert front >= z - post[2] - 0.05 or abs(float(car.position[0]) - x) > car.spec.width_m / 2 + post[2]


def test_kerb_costs_speed():
    assert kerb_speed(20.0, 1, 0) == pytest.approx(20.0 * 0.88)
    assert kerb_speed(20.0, 0, 0) == 20.0


def test_box_outline_has_no_gaps():
    c = box_outline(0.0, 2.0, 0.0, 8.0, 0.3)
    gaps = np.hypot(*np.diff(np.vstack([c, c[:1]])[:, :2], axis=0).T)
    assert gaps.max() <= 0.3 + 1e-9


def _clear_kerb_z(solids, side: float, start: float = 450.0, reach: float = 12.0) -> float:
    """The first z (m) from ``start`` on with no parked car within ``reach`` (m) on ``side``: room to
    recover from a pose across the kerb (a pose inside a parked car is no pose)."""
    boxes = np.asarray(build_world(seed=1).solid_boxes)
    boxes = boxes[np.sign(boxes[:, 0]) == side]
    for z in np.arange(start, start + 600.0, 1.0):
        if not np.any((boxes[:, 3] > z - reach) & (boxes[:, 2] < z + reach)):
            return float(z)
    raise AssertionError("no free stretch of kerb")


@pytest.mark.parametrize("x,yaw", [(7.9, -math.pi / 2), (8.2, -math.pi / 2 - 0.5), (-7.9, math.pi / 2),
                                   (6.0, math.pi)])
def test_autopilot_recovers_without_crossing_a_facade(collider, x, yaw):
    car = _car(collider, x=x, z=_clear_kerb_z(collider.solids, math.copysign(1.0, x)), yaw=yaw, speed=0.0)
    pilot = Autopilot(lane_index=0, target_speed_m_s=14.0, seed=1)
    recovered = None
    for i in range(int(60 / (1 / 30))):
        throttle, brake, steer = pilot.controls(car, 1 / 30)
        car.step(1 / 30, throttle, brake, steer, reverse=pilot.reverse)
        assert _max_corner_x(car) <= WALL_X_M + 0.05
        heading_ok = abs(math.remainder(car.yaw - layout.LANE_YAW[0], math.tau)) < 0.1
        if abs(float(car.position[0]) - layout.LANE_CENTRES_X[0]) < 0.5 and heading_ok and car.speed_m_s > 5.0:
            recovered = i / 30
            break
    assert recovered is not None, f"still off the lane after 60 s at x={car.position[0]:.2f}, yaw={car.yaw:.2f}"


def test_scene_crash_keeps_the_chase_camera_in_the_street_and_r_restores_the_lane(gl_ctx):
    from app.controls import DriveInput, reset_to_lane
    from rain_core.scene import Scene
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = 0.0
    s.camera.mode = "chase"
    scene = Scene(gl_ctx, (64, 36), s, seed=1, gpu_timing=False)
    try:
        for _ in range(300):  # 10 s of full left lock and throttle: into the −x façades and along them
            scene.step(1 / 30, DriveInput(throttle=1.0, steer=1.0))
            cam = scene.camera()
            assert abs(float(cam.position[0])) < scene.collider.wall_x(float(cam.position[0]),
                                                                        float(cam.position[2]))
        reset_to_lane(scene)
        assert scene.ego.position[0] == layout.LANE_CENTRES_X[0] and scene.ego.yaw == layout.LANE_YAW[0]
    finally:
        scene.release()
        gl_ctx.detect_framebuffer(0).use()


def test_parked_cars_are_solid_and_stop_the_car(collider):
    world = build_world(seed=1)
    boxes = world.solid_boxes
    assert len(boxes) > 20
    assert np.all(np.minimum(np.abs(boxes[:, 0]), np.abs(boxes[:, 1])) >= 6.6 - 1e-6)  # traffic lanes stay free
    assert np.all(np.maximum(np.abs(boxes[:, 0]), np.abs(boxes[:, 1])) < WALL_X_M)
    circles = world.solid_circles

    def clear_approach(b):  # nothing else on the 14 m of sidewalk behind this car
        x0, x1, z0, z1 = b
        near_c = (np.abs(circles[:, 0] - (x0 + x1) / 2) < 2.0) & (circles[:, 1] > z1) & (circles[:, 1] < z1 + 14.0)
        near_b = (boxes[:, 2] > z1) & (boxes[:, 2] < z1 + 14.0) & (np.sign(boxes[:, 0]) == 1)
        return x0 > 0 and not near_c.any() and not near_b.any()

    x0, x1, z0, z1 = next(b for b in boxes if clear_approach(b))  # a car on the +x side
    xc = (x0 + x1) / 2
    car = _car(collider, x=xc, z=z1 + 12.0, speed=10.0)  # along the sidewalk, −z, straight at its rear
    speeds = []
    for _ in range(90):
        car.step(1 / 30, throttle=0.5, brake=0.0, steer=0.0)
        f, r = car.forward(), car.right()
        corners = [car.position + f * a * car.spec.length_m / 2 + r * b * car.spec.width_m / 2
                   for a in (-1, 1) for b in (-1, 1)]
        assert min(float(c[2]) for c in corners) >= z1 - 0.05  # never inside the parked car
        speeds.append(car.speed_m_s)
    assert min(speeds[30:]) < 2.0  # it stopped at the parked car
    # Sideways from the lane into it: pushed back, never inside.
    car = _car(collider, x=x0 - 2.3 - 3.0, z=(z0 + z1) / 2, yaw=-math.pi / 2, speed=8.0)  # heading +x
    hit = False
    for _ in range(60):
        car.step(1 / 30, throttle=0.3, brake=0.0, steer=0.0)
        assert float(car.position[0]) + car.spec.length_m / 2 <= x0 + 0.05
        hit |= float(car.position[0]) + car.spec.length_m / 2 > x0 - 0.1
    assert hit and car.speed_m_s < 2.0


def test_sign_posts_are_solid(collider):
    world = build_world(seed=1)
    posts = world.solid_circles[np.isclose(np.abs(world.solid_circles[:, 0]), 7.55)]
    assert len(posts) >= 10
    circles = collider.solids.circles
    for x, z, r in posts[:3]:
        assert np.any(np.all(np.isclose(circles, (x, z, r)), axis=1))


def _deepest_by_nearest_points(collider, car, half_l, half_w):
    """The contact by the footprint's nearest point to every nearby circle (no early-out): the twin of _deepest."""
    fx, fz = -math.sin(car.yaw), -math.cos(car.yaw)
    rx, rz = math.cos(car.yaw), -math.sin(car.yaw)
    px, pz = float(car.position[0]), float(car.position[2])
    best = collider._wall_contact(car, half_l, half_w)
    circles = collider._nearby_circles(pz)
    if len(circles):
        dx, dz = circles[:, 0] - px, circles[:, 1] - pz
        lf = np.clip(dx * fx + dz * fz, -half_l, half_l)
        lr = np.clip(dx * rx + dz * rz, -half_w, half_w)
        ox, oz = px + fx * lf + rx * lr - circles[:, 0], pz + fz * lf + rz * lr - circles[:, 1]
        dist = np.hypot(ox, oz)
        depth = circles[:, 2] - dist
        i = int(depth.argmax())
        if depth[i] > 0.0 and (best is None or depth[i] > best[0]):
            if dist[i] > 1e-9:
                best = (float(depth[i]), (ox[i] / dist[i], oz[i] / dist[i]))
            else:
                sign = math.copysign(1.0, car.speed_m_s or 1.0)
                best = (float(circles[i, 2] + half_w), (-fx * sign, -fz * sign))
    return best


def test_contacts_with_the_bounding_circle_early_out_are_the_full_tests(collider):
    """_deepest skips the nearest-point test when no circle reaches the footprint's bounding circle: over random
    poses around the street's posts, trunks and parked cars (touching, grazing and clear), the same contacts."""
    rng = np.random.default_rng(0)
    car = EgoCar()
    half_l, half_w = car.spec.length_m / 2.0, car.spec.width_m / 2.0
    touching = 0
    for _ in range(3000):
        c = collider._circles[rng.integers(len(collider._circles))]
        car.position = np.array([c[0] + rng.uniform(-4.0, 4.0), 0.0, c[1] + rng.uniform(-4.0, 4.0)])
        car.yaw, car.speed_m_s = rng.uniform(-math.pi, math.pi), rng.uniform(-5.0, 30.0)
        want = _deepest_by_nearest_points(collider, car, half_l, half_w)
        assert collider._deepest(car, half_l, half_w) == want
        touching += want is not None
    assert 300 < touching < 2900  # both outcomes are exercised


def test_contacts_with_the_across_x_early_out_are_the_full_tests(collider):
    """_deepest also skips the circles when every nearby one lies further across x than the footprint reaches
    (a car in its lane): over poses across the whole street (lanes, kerbs, sidewalks; along the posts and past the
    window's slack), the same contacts as the full test, with the early-out taken and not taken."""
    rng = np.random.default_rng(4)
    car = EgoCar()
    half_l, half_w = car.spec.length_m / 2.0, car.spec.width_m / 2.0
    bound = math.hypot(half_l, half_w) + 1e-6
    taken = not_taken = 0
    z = float(collider._circles[rng.integers(len(collider._circles))][1])
    for _ in range(3000):
        z += rng.uniform(-0.5, 1.5)  # mostly onwards, so the window of nearby circles is kept and made again
        car.position = np.array([rng.uniform(-11.0, 11.0), 0.0, z])
        car.yaw, car.speed_m_s = rng.uniform(-math.pi, math.pi), rng.uniform(-5.0, 30.0)
        want = _deepest_by_nearest_points(collider, car, half_l, half_w)
        assert collider._deepest(car, half_l, half_w) == want
        circles, inner = collider._nearby(z)
        assert inner == (float((np.abs(circles[:, 0]) - circles[:, 2]).min()) if len(circles) else math.inf)
        if inner - abs(car.position[0]) > bound + 1e-3:
            taken += 1
        else:
            not_taken += 1
    assert taken > 300 and not_taken > 300


def test_wall_contacts_with_the_half_diagonal_early_out_are_the_corner_tests(collider):
    """_wall_contact skips the corners (_wall_corners) of a car further inside the nearer wall than its
    half-diagonal: over poses across the street and the forecourt (far inside, grazing within a mm of the bound,
    and beyond), the same contacts as testing every corner, with the early-out taken and not taken."""
    rng = np.random.default_rng(5)
    car = EgoCar()
    half_l, half_w = car.spec.length_m / 2.0, car.spec.width_m / 2.0
    edge = WALL_X_M - math.hypot(half_l, half_w)  # the early-out's bound on |x|, a µm aside
    taken = touching = 0
    for i in range(4000):
        x = edge + rng.uniform(-2e-3, 2e-3) if i % 2 else rng.uniform(-12.0, 12.0)
        car.position = np.array([x * rng.choice((-1.0, 1.0)), 0.0, rng.uniform(-50.0, 2500.0)])
        car.yaw = rng.choice((0.0, math.pi / 2, math.atan2(half_w, half_l), rng.uniform(-math.pi, math.pi)))
        want = collider._wall_corners(car, half_l, half_w)
        assert collider._wall_contact(car, half_l, half_w) == want
        taken += abs(car.position[0]) < edge - 1e-6
        touching += want is not None
    assert taken > 1000 and touching > 300


def test_kerb_crossings_count_wheels_that_changed_side():
    from rain_core.collision import kerb_crossings

    edge = layout.ROAD_HALF_WIDTH_M
    rng = np.random.default_rng(1)
    for _ in range(200):
        before, after = np.zeros((4, 3)), np.zeros((4, 3))
        before[:, 0] = rng.choice([-edge - 0.1, -edge, edge, edge + 0.1, 0.0], 4) + rng.normal(0.0, 0.05, 4)
        after[:, 0] = rng.choice([-edge - 0.1, -edge, edge, edge + 0.1, 0.0], 4) + rng.normal(0.0, 0.05, 4)
        was, now = np.abs(before[:, 0]) > edge, np.abs(after[:, 0]) > edge
        assert kerb_crossings(before, after) == (int((now & ~was).sum()), int((was & ~now).sum()))


def test_sub_steps_without_contacts_far_from_the_kerbs_are_the_full_steps(collider):
    """EgoCar.step makes a sub-step's wheel contacts only where a wheel may reach a kerb line: over drives across
    the kerbs, along them and into the walls, every step ends where the loop that made them all ends, bit for bit,
    with the same kerb losses."""
    from rain_core.collision import kerb_crossings

    def reference_step(car, dt, throttle, brake, steer):  # EgoCar.step's loop with every sub-step's contacts
        car.previous_wheel_contacts = car.wheel_contacts()
        n = max(1, math.ceil(dt / 0.01 - 1e-9))
        contacts = car.previous_wheel_contacts
        for _ in range(n):
            before = contacts
            car._substep(dt / n, throttle, brake, steer, False)
            contacts = car.wheel_contacts()
            up, down = kerb_crossings(before, contacts)
            if up or down:
                car.speed_m_s = kerb_speed(car.speed_m_s, up, down)
            if car.collider.resolve(car):
                contacts = car.wheel_contacts()

    rng = np.random.default_rng(17)
    crossings = 0
    for x, yaw in ((layout.LANE_CENTRES_X[1], 0.0), (5.4, 0.12), (-5.3, -0.2), (6.2, 0.0), (1.75, 0.6)):
        fast, slow = _car(collider, x=x, yaw=yaw, speed=14.0), _car(collider, x=x, yaw=yaw, speed=14.0)
        for _ in range(150):
            controls = (rng.uniform(0.0, 1.0), rng.uniform(0.0, 0.2), rng.uniform(-1.0, 1.0))
            dt = float(rng.choice([1 / 30, 1 / 60, 0.1]))
            fast.step(dt, *controls)
            reference_step(slow, dt, *controls)
            assert fast.position.tobytes() == slow.position.tobytes()
            assert (fast.yaw, fast.speed_m_s, fast.steer_rad) == (slow.yaw, slow.speed_m_s, slow.steer_rad)
            crossings += sum(kerb_crossings(slow.previous_wheel_contacts, slow.wheel_contacts()))
    assert crossings > 5
