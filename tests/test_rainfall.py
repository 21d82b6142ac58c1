"""rain_core.rainfall: physics of the spawned drops, the container's density, occlusion, the tilt of the streaks,
the ring buffer, determinism, smooth rate changes, skipping, splashes, and the shader against its NumPy twin."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rain_core import layout, physics
from rain_core.rainfall import (
    SPLASH_D_MIN_MM,
    SPLASH_LIFE_S,
    TYPE_PROMPT,
    DropPool,
    RainfallEffect,
    RainfallSim,
    RainInput,
    StreakCamera,
    drawn_share,
    full_region,
    layer_boxes,
    streak_geometry,
    vehicle_pieces,
    weighted_count,
)

FWD = np.array([0.0, -0.07, -1.0])


def _input(t, pos=(1.75, 1.2, 600.0), vel=(0.0, 0.0, 0.0), rate=8.0, wind=(0.0, 0.0, 0.0), **kw):
    return RainInput(time_s=t, camera_position=np.asarray(pos, float), camera_forward=kw.pop("forward", FWD),
                     camera_velocity=np.asarray(vel, float), rate_mm_h=rate, wind_m_s=np.asarray(wind, float), **kw)


def _drive(sim, seconds, speed=0.0, rate=8.0, wind=(0.0, 0.0, 0.0), t0=0.0, dt=1.0 / 30.0, **kw):
    """Advance a sim with the camera moving along −Z at speed (m/s); returns the last time."""
    t = t0
    for i in range(int(round(seconds / dt)) + 1):
        t = t0 + i * dt
        sim.advance(_input(t, pos=(1.75, 1.2, 600.0 - speed * t), vel=(0.0, 0.0, -speed), rate=rate, wind=wind,
                           **kw))
    return t


@pytest.fixture(scope="module")
def world():
    from rain_core.world import build_world

    return build_world(seed=1)


# --- physics of the spawned drops ----------------------------------------------------------------------------


def test_spawned_diameters_and_speeds_follow_the_physics():
    rate = 8.0
    sim = RainfallSim(40000, seed=2)
    sim.advance(_input(0.0, rate=rate))
    slots = np.flatnonzero(sim.pool.alive)
    d = sim.diameter[slots]
    n = d.size
    assert n > 20000
    # The first fill is the air's population: N(D) (one KS test at the 0.1 % level, seeded).
    assert physics.ks_distance(d, rate) < 1.95 / math.sqrt(n)
    # Fall speeds are the measured terminal velocities of those diameters (no wind: purely vertical).
    v = -sim.vel[slots, 1]
    np.testing.assert_allclose(v, physics.terminal_velocity(d), rtol=1e-12)
    assert np.all(sim.vel[slots][:, [0, 2]] == 0.0)
    # The speed distribution, tested on its own: F_v(v) = F_D(v⁻¹(v)) (v is monotone in D).
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 4001)
    v_sorted = np.sort(v)
    f_v = np.interp(v_sorted, physics.terminal_velocity(grid), physics.drop_diameter_cdf(grid, rate))
    i = np.arange(1, n + 1)
    ks_v = max((i / n - f_v).max(), (f_v - (i - 1) / n).max())
    assert ks_v < 1.95 / math.sqrt(n)
    # With the camera still, every later spawn falls in through a top face: in proportion to N(D)·v(D).
    t = 0.0
    new = []
    for _ in range(20):
        t += 0.5
        upd = sim.advance(_input(t, rate=rate))
        new.append(sim.diameter[upd.spawn_slots])
    df = np.sort(np.concatenate(new))
    weights = physics.marshall_palmer(grid, rate) * physics.terminal_velocity(grid)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (weights[1:] + weights[:-1]) * np.diff(grid))])
    f = np.interp(df, grid, cdf / cdf[-1])
    m = df.size
    j = np.arange(1, m + 1)
    assert m > 2000
    assert max((j / m - f).max(), (f - (j - 1) / m).max()) < 1.95 / math.sqrt(m)
    # …while diameters drawn from N(D) alone would fail the same test.
    f_n = physics.drop_diameter_cdf(df, rate)
    assert max((j / m - f_n).max(), (f_n - (j - 1) / m).max()) > 3.0 / math.sqrt(m)


@pytest.mark.parametrize("speed, wind", [(0.0, (0.0, 0.0, 0.0)), (27.8, (3.0, 0.0, 2.0))])
def test_expected_count_in_a_test_volume_within_5_percent(speed, wind):
    """Weighted drops per m³ in a test box of each layer's full region equal the physical density."""
    rate = 8.0
    sims = [RainfallSim(30000, seed=s) for s in range(2)]
    ratios = []
    for sim in sims:
        t = _drive(sim, 4.0, speed=speed, rate=rate, wind=wind)
        for _ in range(3):  # a few frames a second apart, averaged
            t = _drive(sim, 1.0, speed=speed, rate=rate, wind=wind, t0=t + 1.0 / 30.0)
            for k in range(3):
                lo, hi = full_region(sim.boxes, k)
                w, _ = weighted_count(sim, t, lo, hi)
                ratios.append((k, w / (physics.number_density_per_m3(rate) * np.prod(hi - lo))))
    for k in range(3):
        mean = np.mean([r for kk, r in ratios if kk == k])
        assert abs(mean - 1.0) < 0.05, (k, mean)
    # The drawn count follows the physical density until the budget is full (heavy rain).
    light = RainfallSim(8000, seed=1)
    light.advance(_input(0.0, rate=0.5))
    heavy = RainfallSim(8000, seed=1)
    heavy.advance(_input(0.0, rate=28.0))
    assert light.live == pytest.approx(drawn_share(0.5) * heavy.live, rel=0.1)
    assert drawn_share(0.5) < 0.5 and drawn_share(28.0) == 1.0


# --- occlusion ------------------------------------------------------------------------------------------------


def _inside_piece(lx, y, lz, poly, half_w, eps=1e-3):
    """Points (car-local x, y, z) strictly inside a convex side polygon (z, y) extruded ±half_w."""
    z, yy = poly[:, 0], poly[:, 1]
    area = 0.5 * np.sum(z * np.roll(yy, -1) - np.roll(z, -1) * yy)
    if area < 0:
        poly = poly[::-1]
    inside = np.abs(lx) < half_w - eps
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        cross = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (lz - a[0])
        inside &= cross > eps * np.hypot(*(b - a))
    return inside


def test_no_live_drop_is_ever_under_a_roof_or_in_a_vehicle(world):
    """Vehicles hold their speed here: a drop's fate assumes the velocities it saw when it spawned."""
    from rain_core.vehicles import VAN_SPEC, EgoCar, Vehicle

    sim = RainfallSim(6000, seed=3, world=world)
    ego = EgoCar(position=np.array([layout.LANE_CENTRES_X[0], 0.0, layout.BRIDGE_Z_M + 25.0]), speed_m_s=12.0)
    van = Vehicle(VAN_SPEC, position=np.array([layout.LANE_CENTRES_X[1], 0.0, layout.BRIDGE_Z_M + 10.0]))
    vehicles = (ego, van)
    dt = 1.0 / 30.0
    checked = 0
    for i in range(120):  # drive under the bridge, in wind
        t = i * dt
        ego.step(dt, 0.0, 0.0, 0.0)
        ego.speed_m_s = 12.0
        cam = ego.position + np.array([-0.37, 1.2, 0.59])
        sim.advance(_input(t, pos=cam, vel=ego.velocity(), rate=28.0, wind=(2.5, 0.0, -1.0),
                           vehicles=vehicles, forward=ego.forward()))
        if i % 15 != 14:
            continue
        slots = np.flatnonzero(sim.pool.alive)
        for lag in (0.0, 0.2, 0.6):  # now and where they will be (the vehicles keep their velocity)
            tt = t + lag
            live = slots[sim.t_hit[slots] > tt + 1e-6]
            p = sim.positions(live, tt)
            h = world.occluder_height(p[:, 0], p[:, 2])
            # Roofs are sampled every 0.25 m along a path, so a path may clip a roof's corner by < 1 cell.
            assert np.mean(p[:, 1] < h - 1e-6) < 2e-3, "drops under a roof"
            for veh in vehicles:
                rel = p - (veh.position + veh.velocity() * lag)
                rel[:, 2] -= layout.PERIOD_M * np.round(rel[:, 2] / layout.PERIOD_M)
                cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
                lx, lz = cy * rel[:, 0] - sy * rel[:, 2], sy * rel[:, 0] + cy * rel[:, 2]
                for poly, half_w in vehicle_pieces(veh.spec):
                    assert not _inside_piece(lx, rel[:, 1], lz, poly, half_w).any(), "a drop inside a vehicle"
            checked += live.size
    assert checked > 10000
    # Under the deck itself (away from its edges) there is not a single drop.
    slots = np.flatnonzero(sim.pool.alive)
    p = sim.positions(slots, t)
    under = (np.abs(p[:, 2] - layout.BRIDGE_Z_M) < layout.BRIDGE_DEPTH_M / 2 - 1.0) & (np.abs(p[:, 0]) < 7.0)
    assert not np.any(under & (sim.t_hit[slots] > t) & (p[:, 1] < layout.BRIDGE_CLEARANCE_M))


def _scene(gl_ctx, shaders, settings, size=(160, 90), seed=1):
    from rain_core.scene import Scene

    effect = RainfallEffect(gl_ctx, shaders=shaders, settings=settings, seed=seed)
    return Scene(gl_ctx, size, settings, seed=1, effects=[effect], gpu_timing=False), effect


def _settings(rate=28.0, hour=12.0, mode="free", budget=6000, **rainfall):
    from rain_core.settings import Settings

    s = Settings()
    s.rain.rate_mm_h = rate
    s.time_of_day.hour = hour
    s.camera.mode = mode
    s.quality.particle_budget = budget
    s.traffic.count = 0
    for key, value in rainfall.items():
        setattr(s.rainfall, key, value)
    return s


def _rain_light(scene, camera, settings):
    """HDR difference between the frame with the rain and without it (the rainfall switched off)."""
    scene.render(camera)
    rain = scene.renderer.hdr_image()
    settings.rainfall.enabled = False
    scene.render(camera)
    dry = scene.renderer.hdr_image()
    settings.rainfall.enabled = True
    return np.abs(rain - dry).sum(axis=2)


def test_top_view_under_the_bridge_has_no_streak_pixels(gl_ctx, shaders):
    from rain_core.camera import Camera

    s = _settings(rate=80.0, container_m=30.0, budget=20000)
    s.wind.speed_m_s = 3.0
    scene, _ = _scene(gl_ctx, shaders, s)
    scene.step(1.0 / 60.0)
    down = dict(forward=np.array([0.0, -1.0, 0.0]), up=np.array([0.0, 0.0, -1.0]), fov_y_deg=40.0)
    under = Camera(position=np.array([0.0, 4.8, layout.BRIDGE_Z_M]), **down)
    light = _rain_light(scene, under, s)
    assert np.count_nonzero(light > 0.0) == 0
    # The same view out in the open is full of streaks (so the test can fail).
    scene2, _ = _scene(gl_ctx, shaders, s)
    scene2.step(1.0 / 60.0)
    open_air = Camera(position=np.array([0.0, 4.8, layout.BRIDGE_Z_M + 80.0]), **down)
    assert np.count_nonzero(_rain_light(scene2, open_air, s) > 1e-4) > 100


# --- what the camera sees ---------------------------------------------------------------------------------------


def test_tilt_equals_atan_of_car_speed_over_fall_speed():
    """For a steady car the streak (the drop's path relative to the camera) leans towards the windshield by
    atan(v_car / v_fall), drop by drop, in the NumPy twin of the vertex shader."""
    v_car = 25.0
    sim = RainfallSim(3000, seed=4)
    t = _drive(sim, 1.0, speed=v_car, rate=8.0)
    slots = np.flatnonzero(sim.pool.alive)
    eye = np.array([1.75, 1.2, 600.0 - v_car * t])
    from rain_core.camera import Camera

    cam = Camera(position=eye, forward=np.array([0.0, 0.0, -1.0]))
    view_proj = cam.projection_matrix(16 / 9) @ cam.view_matrix()
    sc = StreakCamera(view_proj, eye, 0.0, np.array([0.0, 0.0, -v_car]), 1.0 / 60.0, (320, 180))
    g = streak_geometry(sim, slots, t, sc, sim.boxes)
    seg = g["head"] - g["tail"]  # where the drop is now minus where it was relative to the camera
    vis = g["visible"] & (np.linalg.norm(seg, axis=1) > 1e-6)
    tilt = np.degrees(np.arctan2(seg[vis, 2], -seg[vis, 1]))  # from the vertical, towards +Z (the windshield)
    expected = np.degrees(np.arctan(v_car / physics.terminal_velocity(sim.diameter[slots[vis]])))
    assert vis.sum() > 500
    assert np.max(np.abs(tilt - expected)) < 1.0
    assert np.all(np.abs(seg[vis, 0]) < 1e-9)  # no sideways lean without wind
    # Parked: the streaks are vertical; reversing: they lean the other way.
    for speed, sign in ((0.0, 0.0), (-5.0, -1.0)):
        sc2 = dataclasses.replace(sc, velocity=np.array([0.0, 0.0, -speed]))
        s2 = streak_geometry(sim, slots, t, sc2, sim.boxes)
        seg2 = s2["head"] - s2["tail"]
        lean = np.degrees(np.arctan2(seg2[vis, 2], -seg2[vis, 1]))
        want = sign * np.degrees(np.arctan(abs(speed) / physics.terminal_velocity(sim.diameter[slots[vis]])))
        assert np.max(np.abs(lean - want)) < 1.0


def test_shader_draws_the_twins_streaks(gl_ctx, shaders):
    """Every pixel the streak pass lights lies on a streak of the NumPy twin, and the light it adds (with the
    radiance switched to a constant) matches the twin's light budget."""
    from rain_core.camera import Camera

    s = _settings(rate=8.0, mode="driver", budget=300, container_m=16.0, splashes=False)
    s.wind.speed_m_s = 0.0
    scene, effect = _scene(gl_ctx, shaders, s, size=(240, 135))
    scene.ego.speed_m_s = 15.0
    scene.step(1.0 / 60.0)
    eye = scene.camera().position + np.array([1.6, 0.3, 0.0])  # beside the car, looking right
    cam = Camera(position=eye, forward=np.array([1.0, 0.0, 0.0]), fov_y_deg=60.0)
    frame = scene.render(cam)
    rain = scene.renderer.hdr_image()
    slots = np.flatnonzero(effect.sim.pool.alive)
    g = streak_geometry(effect.sim, slots, frame.time_s, effect.streak_camera(scene.renderer.render_context(frame)),
                        effect.sim.boxes)
    s.rainfall.enabled = False
    scene.render(cam)
    light = np.abs(rain - scene.renderer.hdr_image()).sum(axis=2)
    w, h = scene.renderer.size
    ys, xs = np.nonzero(light > 1e-5)
    assert xs.size > 200
    px = np.stack([xs + 0.5 - w / 2, h / 2 - (ys + 0.5)], axis=1)
    vis = g["visible"]
    a, b, width = g["head_px"][vis], g["tail_px"][vis], g["width_px"][vis]
    ab = b - a
    t = np.clip(((px[:, None] - a[None]) * ab[None]).sum(2) / np.maximum((ab**2).sum(1), 1e-9)[None], 0, 1)
    dist = np.linalg.norm(px[:, None] - (a[None] + t[..., None] * ab[None]), axis=2) - 0.5 * width[None]
    assert dist.min(axis=1).max() < 1.5  # within the 0.5 px antialiasing margin and the pixel's half-diagonal
    # The car's speed tilts the streaks: seen from the side they are almost horizontal.
    ok = vis & (np.linalg.norm(g["head_px"] - g["tail_px"], axis=1) > 3)
    d = g["tail_px"][ok] - g["head_px"][ok]
    from_horizontal = np.abs(np.degrees(np.arctan(d[:, 1] / np.where(d[:, 0] == 0, 1e-9, d[:, 0]))))
    assert np.median(from_horizontal) < 30.0


def test_drops_in_a_headlight_beam_glow(gl_ctx, shaders):
    from rain_core.camera import Camera

    s = _settings(rate=8.0, hour=23.0, mode="driver", budget=8000, splashes=False)
    s.wind.speed_m_s = 0.0
    scene, effect = _scene(gl_ctx, shaders, s)
    scene.ego.speed_m_s = 0.0
    scene.step(1.0 / 60.0)
    ego = scene.ego
    # A camera on the kerb side, looking across the road through the beams in front of the car.
    target = ego.position + ego.forward() * 6.0 + np.array([0.0, 0.8, 0.0])
    eye = target + ego.right() * 6.0 + np.array([0.0, 0.2, 0.0])
    cam = Camera(position=eye, forward=(target - eye) / np.linalg.norm(target - eye), fov_y_deg=50.0)
    lit = []
    for on in (True, False):
        frame = dataclasses.replace(scene.frame(cam), headlights_on=on)
        scene.renderer.render(frame)
        rain = scene.renderer.hdr_image()
        s.rainfall.enabled = False
        scene.renderer.render(frame)
        dry = scene.renderer.hdr_image()
        s.rainfall.enabled = True
        h, w = rain.shape[:2]
        centre = (rain - dry)[h // 4: 3 * h // 4, w // 4: 3 * w // 4]  # the beam, away from the street lamps
        lit.append(float(np.clip(centre, 0, None).sum()))
    assert lit[0] > 3.0 * lit[1] and lit[0] > 0.0


# --- the ring buffer, determinism, rate changes, skipping ---------------------------------------------------------


def test_ring_buffer_never_leaks_or_overflows_in_1e5_frames():
    """The pool's free list and calendar under 10⁵ frames of spawning, expiring and rescheduling."""
    rng = np.random.default_rng(7)
    pool = DropPool(512)
    t, dt = 0.0, 1.0 / 60.0
    peak = 0
    for frame in range(100_000):
        t += dt * (0.5 + rng.random())  # jittered frame times
        due = pool.pop_due(t)
        if due.size:
            dead = due[rng.random(due.size) < 0.7]
            pool.release(dead)
            alive = np.setdiff1d(due, dead)
            pool.schedule(alive, t + rng.exponential(0.5, alive.size), t)
        want = int(rng.poisson(8 if (frame // 5000) % 2 else 3))
        slots = pool.allocate(want)
        assert slots.size == min(want, slots.size) and slots.size <= pool.capacity
        pool.schedule(slots, t + rng.exponential(1.5, slots.size), t)
        peak = max(peak, pool.live)
        if frame % 10_000 == 0:
            pool.check()
    pool.check()
    assert 0 < peak <= pool.capacity and pool.high_water <= pool.capacity
    # Drain: every slot comes back.
    t += 200.0
    for _ in range(3):
        t += 1.0
        pool.release(pool.pop_due(t))
    pool.check()
    assert pool.live == 0 and pool.n_free == pool.capacity


def test_simulation_keeps_its_budget_over_many_frames():
    sim = RainfallSim(1500, seed=5)
    t, rate = 0.0, 8.0
    rng = np.random.default_rng(1)
    heading = 0.0
    pos = np.array([1.75, 1.2, 600.0])
    spawned = 0
    for frame in range(3000):
        dt = 1.0 / 60.0 * (0.5 + rng.random())
        t += dt
        if frame % 300 == 0:
            rate = float(rng.choice([0.0, 0.5, 8.0, 80.0]))
        heading += 0.3 * dt
        fwd = np.array([-math.sin(heading), -0.05, -math.cos(heading)])
        vel = 20.0 * fwd * np.array([1.0, 0.0, 1.0])
        pos = pos + vel * dt
        upd = sim.advance(_input(t, pos=pos, vel=vel, rate=rate, wind=(2.0, 0.0, 0.0), forward=fwd))
        spawned += upd.spawn_slots.size
        assert sim.live <= sim.capacity
        if frame % 1000 == 0:
            sim.pool.check()
    sim.pool.check()
    assert spawned > 10 * sim.capacity
    assert sim.pool.overflow < 0.01 * spawned


def test_same_seed_same_frame(gl_ctx, shaders):
    images = []
    for seed in (11, 11, 12):
        s = _settings(rate=8.0, mode="driver", budget=4000)
        scene, _ = _scene(gl_ctx, shaders, s, seed=seed)
        for _ in range(3):
            scene.step(1.0 / 30.0)
        scene.render()
        images.append(scene.image())
    assert np.array_equal(images[0], images[1])
    assert not np.array_equal(images[0], images[2])


def test_a_rate_change_takes_effect_smoothly():
    """R steps from 2 to 28 mm/h and back to 0: the weighted density moves a little each frame, no pop."""
    sim = RainfallSim(6000, seed=6)
    dt = 1.0 / 30.0
    t = _drive(sim, 3.0, rate=2.0, dt=dt)
    lo, hi = full_region(sim.boxes, 2)
    volume = float(np.prod(hi - lo))
    series = []
    for rate, seconds in ((28.0, 12.0), (0.0, 30.0)):
        for _ in range(int(seconds / dt)):
            t += dt
            sim.advance(_input(t, rate=rate))
            series.append(weighted_count(sim, t, lo, hi)[0] / volume)
    series = np.array(series)
    n2, n28 = physics.number_density_per_m3(2.0), physics.number_density_per_m3(28.0)
    steps = np.abs(np.diff(series))
    assert steps.max() < 0.05 * (n28 - n2)  # never more than 5 % of the change in one frame
    assert series[0] < n2 + 0.1 * (n28 - n2)  # the first frame after the change still looks like before
    rise = series[: int(12.0 / dt)]
    assert rise[-1] > n2 + 0.6 * (n28 - n2)  # most of the way there within 12 s
    fall = series[int(12.0 / dt):]
    assert series[-1] < 0.3 * n28  # the air empties after the rain stops (the smallest drops take a minute)
    assert np.all(np.diff(fall[int(5.0 / dt):]) <= 0.01 * n28)  # … steadily
    assert sim.rate_eff == 0.0


def test_no_rain_no_pass(gl_ctx, shaders):
    s = _settings(rate=0.0, mode="driver")
    scene, effect = _scene(gl_ctx, shaders, s)
    scene.step(1.0 / 60.0)
    scene.render()
    stats = {st.name: st.ran for st in scene.renderer.stats}
    assert stats["rainfall"] is False and "rainfall.transparent" not in stats
    assert effect.sim is None
    # Rain starts, then stops: the pass runs while drops are still in the air, then stops by itself.
    s.rain.rate_mm_h = 8.0
    scene.step(1.0 / 60.0)
    scene.render()
    assert "rainfall.transparent" in {st.name for st in scene.renderer.stats}
    s.rain.rate_mm_h = 0.0
    for _ in range(600):  # the slowest drops need a minute to reach the ground
        scene.step(0.25)
        frame = scene.frame()
        if not effect.active(frame):
            break
        effect.update(frame, scene.renderer.render_context(frame))
    assert not effect.active(scene.frame()) and effect.sim.live == 0
    # Switched off: skipped at once.
    s.rain.rate_mm_h = 8.0
    s.rainfall.enabled = False
    assert not effect.active(scene.frame())


# --- splashes -------------------------------------------------------------------------------------------------


def test_splashes_follow_the_rate_and_never_fall_under_a_roof(world):
    counts = {}
    for rate in (0.5, 8.0):
        sim = RainfallSim(20000, seed=8, world=world)
        spawned = []
        t = 0.0
        for i in range(60):
            t = i / 30.0
            upd = sim.advance(_input(t, pos=(1.75, 1.2, layout.BRIDGE_Z_M + 12.0), rate=rate, wetness=1.0,
                                     puddles=0.5))
            spawned.append(upd.splash_slots)
        slots = np.concatenate(spawned)
        counts[rate] = slots.size
        if rate == 8.0:
            p = sim.splash_pos[np.unique(slots)]
            assert np.all(~np.isfinite(world.occluder_height(p[:, 0], p[:, 2]))), "a splash under a roof"
            life = sim.splash_life[slots]
            assert life.min() >= SPLASH_LIFE_S[0] - 1e-9 and life.max() <= SPLASH_LIFE_S[1] + 1e-9
    assert counts[8.0] > 20 * max(counts[0.5], 1)  # hardly any in light rain
    assert counts[8.0] > 200
    # A dry road gives prompt splashes, a wet one crowns; the drops that splash are the big ones.
    sim = RainfallSim(20000, seed=9)
    upd = sim.advance(_input(0.0, rate=8.0, wetness=0.0, puddles=0.0))
    kinds = np.floor(upd.splash_data[:, 6]).astype(int)
    assert np.all(kinds == TYPE_PROMPT)
    assert np.all(upd.splash_data[:, 4] >= SPLASH_D_MIN_MM)


def test_container_follows_the_camera_and_looks_ahead():
    boxes = layer_boxes([0.0, 1.2, 100.0], [0.0, 0.0, -1.0], 40.0)
    lo, hi = boxes.lo, boxes.hi
    assert np.all(lo[:, 2] < 100.0) and np.all(hi[:, 2] > 100.0)  # the camera is inside every box
    assert np.all(100.0 - lo[:, 2] > 3.0 * (hi[:, 2] - 100.0))  # most of each box is in front
    assert np.all(np.diff(hi[:, 0] - lo[:, 0]) > 0)  # nested, growing
    down = layer_boxes([0.0, 5.0, 100.0], [0.0, -1.0, 0.0], 40.0)
    np.testing.assert_allclose(0.5 * (down.lo[:, 2] + down.hi[:, 2]), 100.0)  # looking down: centred
