"""Vehicle bodies stop the drops they meet (rain_core.effects.spray.body)."""

import numpy as np

from rain_core.effects.spray.body import BodyBox, body_hit_time
from rain_core.effects.spray.flight import flight_position, ground_time
from rain_core.vehicles import CAR_SPEC, Vehicle


def test_body_hit_stops_drops_at_the_body_and_lets_the_rest_pass():
    car = Vehicle(CAR_SPEC, (0.0, 0.0, 0.0), 0.0, 20.0)
    box = BodyBox.of(CAR_SPEC)
    fl = car.wheel_contacts()[0]
    # Thrown straight up from the front-left tyre's inner half: meets the wheel arch above the well.
    p0 = np.array([fl + [0.05, 0.3, 0.0], fl + [0.0, 0.05, 0.0]])
    v0 = np.array([[0.0, 15.0, -20.0], [-12.0, 0.5, -20.0]])  # second: sideways out of the well, low
    u = np.array([[0.0, -1.0, 0.0], [0.0, -1.0, 0.0]])
    tau = np.array([0.05, 0.05])
    t_ground = ground_time(p0, v0, u, tau)
    t = body_hit_time(p0, v0, u, tau, t_ground, np.zeros((2, 3)), np.tile(car.velocity(), (2, 1)),
                      np.tile(car.right(), (2, 1)), np.tile(car.forward(), (2, 1)), [box], np.zeros(2, int))
    assert t[0] < 0.5 * t_ground[0]
    top = flight_position(p0[0], v0[0], u[0], tau[0], t[0])
    assert box.well_top - 0.05 < top[1] < box.well_top + 0.2  # stopped at the arch
    assert t[1] == t_ground[1]
