"""Every simulation imports and steps with moderngl and the GL side (rain_core.gfx, the renderer) impossible to
import: they can be run, tested and timed without a GL context (issue 12, DESIGN §1)."""

import subprocess
import sys

BLOCK = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] == 'moderngl' or name.startswith('rain_core.gfx') or name == 'rain_core.renderer':
            raise ImportError('blocked: ' + name)
sys.meta_path.insert(0, Block())
import numpy as np
from types import SimpleNamespace
from rain_core import layout
"""

STEPS = {
    "weather": """
from rain_core.settings import Settings
from rain_core.weather import Weather
w = Weather.from_settings(Settings())
for _ in range(30):
    state = w.step(1 / 30, 8.0)
assert 0.0 < state.wetness <= 1.0
""",
    "vehicles": """
from rain_core.vehicles import Autopilot, EgoCar, Traffic
ego = EgoCar(position=np.array([1.75, 0.0, 600.0]), speed_m_s=16.0)
pilot, traffic = Autopilot(lane_index=0, target_speed_m_s=22.0, seed=1), Traffic(count=3, seed=1, ego=ego)
for _ in range(30):
    ego.step(1 / 30, *pilot.controls(ego, 1 / 30, others=traffic.vehicles))
    traffic.step(1 / 30)
assert ego.position[2] < 600.0
""",
    "rainfall": """
from rain_core.effects.rainfall import RainfallSim, RainInput
sim = RainfallSim(capacity=4000, seed=1)
for i in range(10):
    update = sim.advance(RainInput(time_s=i / 30, camera_position=np.array([1.75, 1.2, 600.0 - i]),
                                   camera_forward=np.array([0.0, 0.0, -1.0]),
                                   camera_velocity=np.array([0.0, 0.0, -30.0]), rate_mm_h=8.0))
assert update.drawn_expected > 0 and sim.drops()["visible"].sum() > 0 and sim.splashes()["pos"].shape[1] == 3
""",
    "spray": """
from rain_core.effects.spray import KMH, SprayEmitter
from rain_core.vehicles import TRUCK_SPEC, Vehicle
from rain_core.weather import WeatherState
for reference in (False, True):  # the fast path and its float64 reference
    truck = Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 500.0), 0.0, 100 * KMH)
    em = SprayEmitter(seed=1, budget=500, film_depth_fn=lambda x, z: np.full(np.shape(x), 3.0),
                      reference=reference)
    for i in range(10):
        truck.position = truck.position + truck.forward() * truck.speed_m_s / 30
        em.emit(SimpleNamespace(time_s=i / 30, vehicles=[truck], weather=WeatherState(wetness=1.0), settings=None,
                                world=None))
    assert em.stats.parcels > 0 and em.landed_impacts().shape[1] == 3
""",
    "ripples": """
from rain_core.effects.ripples import RippleField, WaveSolver, WaveSolverF32
field = RippleField(n=32, extent_m=3.1, seed=1)
report = field.update(1 / 60, center_xz=(0.0, 0.0), rate_mm_h=5.0,
                      film_depth_fn=lambda x, z: np.full(np.shape(x), 3.0),
                      wheels=[((-1.0, 0.0), (1.0, 0.0), 10.0, None, 0.2)], impacts=np.array([[0.1, 0.2, 1e-4]]))
assert report['substeps'] >= 1 and report['wake_bumps'] > 0 and np.isfinite(field.height).all()
for cls in (WaveSolver, WaveSolverF32):
    solver = cls(16, 0.05, 0.35)
    solver.add_impulse(0.4, 0.4, 0.1, 1e-3)
    assert solver.step(1 / 60) >= 1
""",
    "windshield": """
from rain_core.effects.windshield import GlassInputs, WindshieldSim, WindshieldSimReference
from rain_core.effects.windshield.splats import drop_splats, film_splats
for cls in (WindshieldSim, WindshieldSimReference):
    sim = cls(seed=1)
    for _ in range(30):
        sim.step(1 / 30, GlassInputs.for_speed(60.0, 8.0, wiper_mode='high'))
    assert sim.count > 0 and len(drop_splats(sim, 0.003)) and len(film_splats(sim, 0.003))
""",
    "rainbow": """
from rain_core.effects.rainbow import ShowerTracker, bow_lut
t = ShowerTracker()
t.observe(0.0, 4.0)
assert t.column(0.0, 4.0, 10.0, 3000.0) is not None and bow_lut(4.0, 64).max() > 0.0
""",
    "lightning": """
from rain_core.effects.lightning.storm import Storm
from rain_core.settings import Settings
s = Settings()
s.lightning.flashes_per_min = 30.0
storm = Storm(seed=1)
views = [storm.frame_view(s, i / 30, 1 / 30, np.zeros(3), 20.0) for i in range(30 * 20)]
assert any(v is not None for v in views)
""",
    "drips": """
from rain_core.effects.drips import RoofReservoirs, find_drip_sites, landings
grid = np.full((40, 60), -np.inf, np.float32)
grid[10:20, 20:40] = 5.0
sites = find_drip_sites(grid, -7.5, 0.25, street_half_x_m=100.0)
roofs = RoofReservoirs(sites.area_m2, sites.drain_s)
for _ in range(30):
    roofs.step(1 / 30, 8.0)
assert len(sites) and roofs.outflow_m3_s.sum() > 0.0
""",
    "water film": """
from rain_core.water_film import film_depth_mm
assert np.all(np.asarray(film_depth_mm(np.zeros(4), np.arange(4.0), 1.0, 1.0, wetness=1.0)) >= 0.0)
""",
}


def test_every_simulation_steps_without_gl():
    code = BLOCK + "\n".join(STEPS.values()) + "\nassert 'moderngl' not in sys.modules\n"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-3000:]


def test_the_block_really_blocks():
    result = subprocess.run([sys.executable, "-c", BLOCK + "import moderngl"], capture_output=True, text=True)
    assert result.returncode != 0 and "blocked: moderngl" in result.stderr
