"""The spray's simulation imports and runs where moderngl is absent."""

import subprocess
import sys

CODE = """
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] == 'moderngl': raise ImportError('moderngl blocked')
sys.meta_path.insert(0, Block())
from types import SimpleNamespace
import numpy as np
from rain_core import layout
from rain_core.effects.spray import KMH, SprayEmitter, line_of_sight_optical_depth
from rain_core.vehicles import TRUCK_SPEC, Vehicle
from rain_core.weather import WeatherState
truck = Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 500.0), 0.0, 100 * KMH)
em = SprayEmitter(seed=1, budget=500, film_depth_fn=lambda x, z: np.full(np.shape(x), 3.0))
for i in range(10):
    truck.position = truck.position + truck.forward() * truck.speed_m_s / 30
    em.emit(SimpleNamespace(time_s=i / 30, vehicles=[truck], weather=WeatherState(wetness=1.0), settings=None,
                            world=None))
assert em.stats.parcels > 0 and em.landed_impacts().shape[1] == 3
assert line_of_sight_optical_depth(em, 9 / 30, (1.75, 1.0, 520.0), (1.75, 1.0, 490.0)) >= 0.0
assert 'moderngl' not in sys.modules
"""


def test_simulation_runs_without_gl():
    subprocess.run([sys.executable, "-c", CODE], check=True)
