"""A lorry ahead of the ego car at 100 km/h on a road of uniform water depth: the spray tests' scene."""

import numpy as np
import pytest

from rain_core import layout
from rain_core.effects.spray.water import KMH
from rain_core.vehicles import TRUCK_SPEC, Vehicle


@pytest.fixture
def truck_scene(gl_ctx):
    """Factory: (scene, spray effect) at 96×54, heavy rain, the lorry 20 m ahead in the ego's lane; ``puddle_mm``
    (mm) is the water depth everywhere (None: the road's own film)."""
    from rain_core.effects.spray import SprayEffect
    from rain_core.scene import Scene
    from rain_core.settings import Settings
    from rain_core.traffic import Autopilot

    def make(enabled=True, strength=1.0, hour=12.0, puddle_mm=None):
        s = Settings()
        s.rain.rate_mm_h, s.rain.wetness, s.rain.cracks, s.rain.puddles = 8.0, 1.0, 0.0, 0.0
        s.traffic.count, s.time_of_day.hour = 1, hour
        s.spray.enabled, s.spray.strength, s.spray.budget = enabled, strength, 3000
        effect = SprayEffect(gl_ctx, s, seed=1)
        if puddle_mm is not None:
            effect.emitter.film_depth_fn = lambda x, z: np.full(
                np.broadcast(np.asarray(x), np.asarray(z)).shape, float(puddle_mm))
        scene = Scene(gl_ctx, (96, 54), s, seed=1, effects=[effect])
        v = 100 * KMH
        scene.ego.position[:] = [layout.LANE_CENTRES_X[0], 0.0, 600.0]
        scene.ego.speed_m_s = v
        truck = Vehicle(TRUCK_SPEC, (layout.LANE_CENTRES_X[0], 0.0, 580.0), 0.0, v, (0.75, 0.75, 0.72))
        scene.traffic.vehicles, scene.traffic.lanes, scene.traffic.desired_speeds_m_s = [truck], [0], [v]
        scene.autopilot = Autopilot(lane_index=0, target_speed_m_s=v, seed=1, wander_m=0.0)
        return scene, effect

    return make
