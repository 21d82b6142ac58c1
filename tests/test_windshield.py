"""rain_core.windshield / rain_core.wipers: water bookkeeping, drop physics, merging, wipers, the GPU water
texture against the CPU state, and the effect's skip rule."""

import math

import numpy as np
import pytest

from rain_core import physics
from rain_core.settings import Settings, SettingsError, set_value
from rain_core.windshield import (
    FILM_CELLS,
    RESIDUE_M,
    RHO_W,
    GlassGeometry,
    GlassInputs,
    WindshieldEffect,
    WindshieldSim,
    _grid_pairs,
    airflow_onset_speed_m_s,
    drop_mass,
    drop_radius,
)
from rain_core.wipers import WiperController, tandem_blades


def _scatter(sim: WindshieldSim, n: int, radius_mm: tuple[float, float], seed: int = 0) -> None:
    """Put n resting drops of contact radius uniform in radius_mm (mm) on the glass, away from its edges."""
    rng = np.random.default_rng(seed)
    g = sim.glass
    uv = rng.uniform(0.1, 0.9, (n, 2))
    a = rng.uniform(*radius_mm, n) * 1e-3
    sim._append(g.from_uv(uv), np.zeros((n, 2)), drop_mass(a))
    sim.arrived += float(drop_mass(a).sum())


# --- glass geometry -----------------------------------------------------------------------------------------
def test_glass_matches_the_mesh_frame_and_uv_round_trips():
    from rain_core.car_mesh import windshield_surface

    g = GlassGeometry()
    pos, _, uv, _ = windshield_surface(n_u=9, n_v=7)
    assert np.allclose(g.local_points(g.from_uv(uv)), pos, atol=1e-9)
    st = g.sample_uniform(1000, np.random.default_rng(1))
    assert g.contains(st).all()
    assert np.allclose(g.from_uv(g.to_uv(st)), st)
    # Uniform over the area: as many points in the lower half of the area as in the upper.
    t_half = (
        g.height
        * (math.sqrt(0.5 * (g.width_bottom**2 + g.width_top**2)) - g.width_bottom)
        / (g.width_top - g.width_bottom)
    )
    assert abs(np.mean(st[:, 1] < t_half) - 0.5) < 0.05
    # Gravity along a 60°-raked glass: g·cos(60°) down the glass at the centre line.
    grav = g.gravity(np.array([[0.0, 0.5 * g.height], [0.5, 0.5 * g.height]]))
    assert grav[0] == pytest.approx([0.0, -9.81 * math.cos(g.rake)], abs=1e-9)
    assert grav[1, 0] > 0  # the bulge: off-centre drops are pulled outwards


def test_cap_mass_radius_round_trip():
    a = np.array([1e-4, 1e-3, 5e-3])
    assert np.allclose(drop_radius(drop_mass(a)), a)


# --- arrivals -----------------------------------------------------------------------------------------------
def test_arrivals_follow_the_physics_flux_and_stop_under_a_roof():
    sim = WindshieldSim(seed=3)
    inputs = GlassInputs.for_speed(50.0, 4.0, drop_budget=0)
    rate, _, _ = sim.arrival_rate_per_s(inputs)
    n = sim.glass.normal
    flux = physics.flux_on_surface_per_s(4.0, sim.glass.area_m2, n, (0, 0, -50 / 3.6))
    assert rate == pytest.approx(flux, rel=1e-3)
    parked = GlassInputs.for_speed(0.0, 4.0, wind_m_s=np.array([3.0, 0.0, 5.0]))
    flux = physics.flux_on_surface_per_s(4.0, sim.glass.area_m2, n, (0, 0, 0), (3.0, 0.0, 5.0))
    assert sim.arrival_rate_per_s(parked)[0] == pytest.approx(flux, rel=1e-3)
    for _ in range(60):
        sim.step(1 / 60, inputs)
    expected = rate * 1.0
    assert abs(sim.arrival_count - expected) < 5 * math.sqrt(expected)
    covered = GlassInputs.for_speed(50.0, 4.0, sheltered=True)
    assert sim.arrival_rate_per_s(covered)[0] == 0.0
    assert sim.arrival_rate_per_s(GlassInputs.for_speed(50.0, 0.0))[0] == 0.0


def test_arrival_sizes_are_flux_weighted_marshall_palmer():
    sim = WindshieldSim(seed=4)
    inputs = GlassInputs.for_speed(0.0, 8.0)
    _, closing, cdf = sim.arrival_rate_per_s(inputs)
    d, _ = sim._sample_arrivals(40000, closing, cdf)
    # Parked, a drop's chance to land grows with its fall speed: the mean is ∫D·N·v / ∫N·v.
    grid = np.linspace(physics.D_MIN_MM, physics.D_MAX_MM, 4001)
    w = physics.marshall_palmer(grid, 8.0) * physics.terminal_velocity(grid)
    assert d.mean() == pytest.approx(np.sum(grid * w) / np.sum(w), rel=0.02)
    assert d.mean() > physics.sample_drop_diameters(8.0, 40000, 5).mean() * 1.2


# --- the balance --------------------------------------------------------------------------------------------
def test_mass_bookkeeping_closes_over_ten_thousand_frames():
    """arrived − wiped − shed − evaporated = on the glass, through speeds 0→120→0 km/h, a roof, wiper
    modes."""
    sim = WindshieldSim(seed=7)
    frames = 10_000
    for k in range(frames):
        x = k / frames
        speed = 120.0 * math.sin(math.pi * x)
        mode = ("auto", "low", "intermittent", "high", "off")[int(x * 5) % 5]
        inputs = GlassInputs.for_speed(
            speed,
            6.0 if x < 0.8 else 0.0,
            sheltered=0.3 < x < 0.35,
            drop_budget=300,
            wiper_mode=mode,
            wiper_interval_s=2.0,
        )
        sim.step(1 / 60, inputs)
        if k % 500 == 0:
            assert sim.glass.contains(sim.pos).all()
    assert sim.arrived > 0 and sim.wiped > 0 and sim.shed > 0 and sim.evaporated > 0
    assert abs(sim.balance_error_kg()) <= 0.01 * sim.arrived
    assert abs(sim.balance_error_kg()) <= 1e-9 * sim.arrived  # in fact exact up to rounding
    assert sim.glass.contains(sim.pos).all()
    assert np.all(sim.mass > 0) and np.all(sim.film >= 0) and np.all(sim.beads >= 0)


def test_drops_leave_the_glass_only_by_shedding():
    sim = WindshieldSim(seed=8)
    _scatter(sim, 300, (3.5, 6.0))  # large drops: they run
    inputs = GlassInputs.for_speed(0.0, 0.0)
    before = sim.mass_on_glass()
    for _ in range(240):
        sim.step(1 / 30, inputs)
        assert sim.glass.contains(sim.pos).all()
    assert sim.shed > 0  # some ran off the lower edge …
    assert sim.mass_on_glass() + sim.shed + sim.evaporated == pytest.approx(
        before, rel=1e-12
    )  # … and nothing else


# --- drops --------------------------------------------------------------------------------------------------
def test_merging_conserves_mass_momentum_and_centre_of_mass():
    sim = WindshieldSim(seed=0)
    a = 1.5e-3
    pos = np.array([[0.0, 0.5], [2.5e-3, 0.5], [4.9e-3, 0.5], [0.2, 0.3]])  # a chain of three, one apart
    vel = np.array([[0.0, 0.1], [0.0, 0.0], [0.02, 0.0], [0.0, 0.0]])
    mass = drop_mass(np.array([a, a, 0.8 * a, a]))
    sim._append(pos, vel, mass)
    p0, m0 = (mass[:, None] * vel).sum(axis=0), mass.sum()
    c0 = (mass[:, None] * pos)[:3].sum(axis=0) / mass[:3].sum()
    sim._merge(sim.pos.copy(), np.zeros_like(sim.pos))
    assert sim.count == 2
    assert sim.mass.sum() == pytest.approx(m0, rel=1e-14)
    assert (sim.mass[:, None] * sim.vel).sum(axis=0) == pytest.approx(p0, rel=1e-12)
    big = int(np.argmax(sim.mass))
    assert sim.mass[big] == pytest.approx(mass[:3].sum())
    assert sim.pos[big] == pytest.approx(c0)


def test_fast_drops_do_not_tunnel_through_others():
    sim = WindshieldSim(seed=0)
    sim._append(np.array([[0.0, 0.55], [0.0, 0.5]]), np.zeros((2, 2)), drop_mass(np.array([1e-3, 1e-3])))
    start = np.array([[0.0, 0.45], [0.0, 0.5]])
    disp = np.array([[0.0, 0.1], [0.0, 0.0]])  # the first jumps right over the second within one step
    sim._merge(start, disp)
    assert sim.count == 1


def test_grid_finds_every_touching_pair():
    rng = np.random.default_rng(2)
    for _ in range(10):
        n = int(rng.integers(50, 600))
        p = rng.uniform([-0.7, 0.0], [0.7, 1.1], (n, 2))
        reach = rng.exponential(0.002, n) * rng.choice([1.0, 1.0, 1.0, 12.0], n)
        active = rng.random(n) < 0.3
        i, j = _grid_pairs(p, reach, active)
        found = set(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist(), strict=True))
        d = np.linalg.norm(p[:, None] - p[None], axis=2)
        ii, jj = np.nonzero((d <= reach[:, None] + reach[None]) & np.triu(np.ones((n, n), bool), 1))
        want = {(a, b) for a, b in zip(ii.tolist(), jj.tolist(), strict=True) if active[a] or active[b]}
        assert want <= found


def _mean_velocity_up(speed_kmh: float) -> float:
    sim = WindshieldSim(seed=11)
    _scatter(sim, 400, (1.0, 5.0), seed=3)
    inputs = GlassInputs.for_speed(speed_kmh, 0.0)
    for _ in range(15):
        sim.step(1 / 30, inputs)
    return float((sim.mass * sim.vel[:, 1]).sum() / sim.mass.sum())


def test_parked_drops_run_down_and_at_motorway_speed_climb():
    down = _mean_velocity_up(0.0)
    up = _mean_velocity_up(120.0)
    assert down < 0.0
    assert up > 0.0
    # Small drops stick, large ones run (parked): pinning ∝ a, weight ∝ a³.
    sim = WindshieldSim(seed=1)
    _scatter(sim, 50, (0.5, 1.5))
    sim.step(0.5, GlassInputs.for_speed(0.0, 0.0))
    assert np.all(sim.vel == 0.0)


def test_airflow_onset_is_tens_of_km_h_and_earlier_for_larger_drops():
    onsets = [airflow_onset_speed_m_s(a) * 3.6 for a in (2e-3, 3e-3, 5e-3)]
    assert onsets[0] > onsets[1] > onsets[2]
    assert 40.0 < onsets[2] < 100.0


def test_running_drops_leave_trails():
    sim = WindshieldSim(seed=5)
    sim._append(np.array([[0.0, 1.0]]), np.zeros((1, 2)), drop_mass(np.array([4.5e-3])))
    for _ in range(20):
        sim.step(1 / 30, GlassInputs.for_speed(0.0, 0.0))
    assert 1.0 - sim.pos[np.argmax(sim.mass), 1] > 0.05  # it ran down
    assert sim.count > 3  # droplets behind the runner
    droplets = sim.mass < 0.1 * sim.mass.max()
    assert np.all(np.abs(sim.pos[droplets, 0]) < 0.05)  # along its path
    assert sim.film.sum() > 0  # and a wet line


def test_determinism():
    def run():
        sim = WindshieldSim(seed=21)
        for k in range(200):
            sim.step(1 / 30, GlassInputs.for_speed(k * 0.5, 8.0, wiper_mode="auto", drop_budget=1500))
        return sim

    a, b = run(), run()
    assert np.array_equal(a.pos, b.pos) and np.array_equal(a.mass, b.mass) and np.array_equal(a.film, b.film)
    assert a.wiped == b.wiped and a.wipers.cycle_starts == b.wipers.cycle_starts


# --- wipers -------------------------------------------------------------------------------------------------
def test_wiper_stroke_clears_its_swept_area():
    sim = WindshieldSim(seed=2)
    _scatter(sim, 600, (0.5, 2.0))
    sim.film[:] = RHO_W * 2e-6 * sim.cell_areas  # a 2 µm film everywhere
    sim.arrived += float(sim.film.sum())
    inputs = GlassInputs.for_speed(0.0, 0.0, wiper_mode="low", wiper_low_cpm=45.0)
    for _ in range(int(60 / 45 * 30) + 2):  # one cycle
        sim.step(1 / 30, inputs)
        if sim.wipers.cycles:
            break
    assert sim.wipers.cycles == 1
    residue = RESIDUE_M * (1 + 4 * inputs.blade_wear)
    centres = sim.cell_centres.reshape(-1, 2)
    thickness = sim.film_thickness_m().ravel()
    for blade in sim.blades:
        inner = _in_sector(blade, centres, margin=0.02)
        assert inner.sum() > 100
        assert np.all(thickness[inner] <= residue * 1.001)  # below a small water threshold: the residue
        in_drops = _in_sector(blade, sim.pos, margin=0.02)
        assert not in_drops.any()
    outside = ~(_in_sector(sim.blades[0], centres, -0.02) | _in_sector(sim.blades[1], centres, -0.02))
    # Untouched (but for drying) where no blade went, except the paths of drops shed at the ends of the
    # stroke.
    assert np.mean(np.isclose(thickness[outside], 2e-6, rtol=0.02)) > 0.95
    assert sim.wiped > 0 and abs(sim.balance_error_kg()) < 1e-12


def _in_sector(blade, pts, margin):
    rel = pts - np.asarray(blade.pivot)
    r = np.hypot(rel[:, 0], rel[:, 1])
    phi = np.arctan2(rel[:, 1], rel[:, 0])
    return (
        (r > blade.r_inner_m + margin)
        & (r < blade.r_outer_m - margin)
        & (phi > blade.park_rad + margin / np.maximum(r, 1e-3))
        & (phi < blade.top_rad - margin / np.maximum(r, 1e-3))
    )


def test_wiper_modes_and_their_rates():
    c = WiperController()
    assert c.advance(10.0, "off") == [] and not c.running
    segs = c.advance(60.001, "high", high_cpm=70.0)
    assert c.cycles == 70 and segs[0].p_start == 0.0
    assert [s.event for s in segs if s.event][:4] == ["top", "park", "top", "park"]
    c = WiperController()
    c.advance(60.001, "low", low_cpm=45.0)
    assert c.cycles == 45
    c = WiperController()
    for _ in range(601):
        c.advance(0.1, "intermittent", interval_s=5.0, low_cpm=60.0)
    # 60 s of 1 s cycles + 5 s pauses, the first at once: a cycle every 6 s.
    assert c.cycles == 10
    assert np.allclose(np.diff(c.cycle_starts), 6.0)
    # off in mid-stroke: the blade returns to park, then rests.
    c = WiperController()
    c.advance(0.3, "low", low_cpm=60.0)
    assert c.running
    c.advance(5.0, "off")
    assert not c.running and c.progress == 0.0 and c.cycles == 1
    blades = tandem_blades(1.54, 1.21, 1.1)
    assert blades[0].angle(0.0) == pytest.approx(blades[0].park_rad)
    assert blades[0].angle(1.0) == pytest.approx(blades[0].top_rad)
    with pytest.raises(ValueError):
        c.advance(1.0, "fast")


def _auto_cycles(rate_mm_h: float) -> int:
    sim = WindshieldSim(seed=6)
    inputs = GlassInputs.for_speed(50.0, rate_mm_h, wiper_mode="auto", drop_budget=800)
    for _ in range(20 * 30):
        sim.step(1 / 30, inputs)
    return sim.wipers.cycles


def test_auto_wipes_more_often_in_heavier_rain():
    light, heavy = _auto_cycles(0.5), _auto_cycles(8.0)
    assert heavy > light >= 1


def test_heavy_rain_overwhelms_a_slow_wiper_more_than_a_fast_one():
    def water_in_view(mode: str) -> float:
        """Mean water (kg/m²) in the driver's blade's sweep, over 6 s after the first 2."""
        sim = WindshieldSim(seed=9)
        blade = sim.blades[0]
        cells = _in_sector(blade, sim.cell_centres.reshape(-1, 2), 0.0)
        area = sim.cell_areas.ravel()[cells].sum()
        inputs = GlassInputs.for_speed(60.0, 8.0, wiper_mode=mode, drop_budget=1500)
        samples = []
        for k in range(8 * 30):
            sim.step(1 / 30, inputs)
            if k > 60:
                drops = sim.mass[_in_sector(blade, sim.pos, 0.0)].sum()
                samples.append((drops + sim.film.ravel()[cells].sum() + sim.beads[0].sum()) / area)
        return float(np.mean(samples))

    assert water_in_view("low") > 1.5 * water_in_view("high")


# --- settings -----------------------------------------------------------------------------------------------
def test_settings_have_wiper_and_windshield_options():
    s = Settings()
    assert s.wipers.mode in ("off", "intermittent", "low", "high", "auto")
    assert s.wipers.low_cycles_per_min < s.wipers.high_cycles_per_min
    set_value(s, "wipers.interval_s", 8.0)
    set_value(s, "windshield.drop_budget", 2000)
    with pytest.raises(SettingsError):
        set_value(s, "windshield.drop_budget", -1)
    with pytest.raises(SettingsError):
        set_value(s, "wipers.mode", "turbo")
    assert 64 <= s.quality.windshield_resolution <= 2048


# --- GPU ----------------------------------------------------------------------------------------------------
def _scene(gl_ctx, settings, effect, size=(160, 90)):
    from rain_core.scene import Scene

    scene = Scene(gl_ctx, size, settings, seed=1, effects=[effect], gpu_timing=False)
    scene.ego.speed_m_s = 0.0
    return scene


class _Brake:
    throttle, brake, steer, reverse = 0.0, 1.0, 0.0, False


def test_dry_glass_costs_nothing_and_outside_camera_skips(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 0.0
    s.wipers.mode = "auto"
    effect = WindshieldEffect(gl_ctx, shaders, s, seed=1)
    scene = _scene(gl_ctx, s, effect)
    scene.step(1 / 30, _Brake)
    scene.render()

    def ran():
        return {name: done for name, done, *_ in scene.renderer.pass_table()}

    assert ran()["windshield"] is False and "windshield.overlay" not in ran()
    s.rain.rate_mm_h = 4.0
    scene.step(1 / 30, _Brake)
    scene.render(scene.camera("chase"))
    assert ran()["windshield"] is False  # outside the car
    scene.render()
    assert ran()["windshield.prepare"] and ran()["windshield.overlay"]
    scene.release()


def test_gpu_water_texture_agrees_with_the_cpu_state(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 8.0
    s.wipers.mode = "off"
    s.quality.windshield_resolution = 256
    effect = WindshieldEffect(gl_ctx, shaders, s, seed=2)
    scene = _scene(gl_ctx, s, effect)
    for _ in range(12):
        scene.step(1 / 30, _Brake)
        scene.render()
    n = effect.resolution
    water = np.frombuffer(effect._water.color.read(), np.float16).reshape(n, n, 4).astype(np.float64)
    assert np.all(np.isfinite(water))
    # The film channel, averaged over each CPU cell, is the CPU film (the rescaling keeps them together).
    k = n // FILM_CELLS
    gpu_cells = water[..., 1].reshape(FILM_CELLS, k, FILM_CELLS, k).mean(axis=(1, 3))
    cpu_cells = effect.sim.film_thickness_m() * 1e6
    wet = cpu_cells > 0.05
    assert wet.sum() > 100
    ratio = np.median(gpu_cells[wet] / cpu_cells[wet])
    assert 0.8 < ratio < 1.25
    # Every drop is a bump in the thickness texture where the CPU has it.
    uv = effect.glass.to_uv(effect.sim.pos)
    texel = np.clip((uv * n).astype(int), 0, n - 1)
    big = effect.sim.radius() > 1e-3
    assert np.mean(water[texel[big, 1], texel[big, 0], 0] > 0.05) > 0.9
    dry = water[..., 0] < 1e-4
    assert dry.mean() > 0.2
    scene.release()


def test_wet_glass_changes_the_view_and_stays_finite(gl_ctx, shaders):
    s = Settings()
    s.rain.rate_mm_h = 16.0
    s.wipers.mode = "off"
    effect = WindshieldEffect(gl_ctx, shaders, s, seed=3)
    scene = _scene(gl_ctx, s, effect)
    scene.step(1 / 30, _Brake)
    scene.render()
    dry = scene.renderer.hdr_image()
    for _ in range(40):
        scene.step(1 / 30, _Brake)
        effect.sim.step(1 / 30, effect.inputs_for(scene.frame()))  # the water builds faster than we draw
    effect._last_time = scene.time_s
    scene.step(1 / 30, _Brake)
    scene.render()
    wet = scene.renderer.hdr_image()
    assert np.all(np.isfinite(wet))
    assert np.mean(np.abs(wet - dry)) > 0.01 * np.mean(dry)
    scene.release()


def test_rendering_is_deterministic(gl_ctx, shaders):
    def frame():
        s = Settings()
        s.rain.rate_mm_h = 8.0
        s.wipers.mode = "high"
        effect = WindshieldEffect(gl_ctx, shaders, s, seed=4)
        scene = _scene(gl_ctx, s, effect)
        for _ in range(8):
            scene.step(1 / 30, _Brake)
            scene.render()
        image = scene.image()
        scene.release()
        return image

    assert np.array_equal(frame(), frame())
