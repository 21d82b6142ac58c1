"""rain_core.effects.windshield.dynamics / airflow: drops run down parked and climb at speed, trails."""

import numpy as np

from rain_core.effects.windshield import GlassInputs, WindshieldSim, airflow_onset_speed_m_s, drop_mass


def _mean_velocity_up(scatter, speed_kmh: float) -> float:
    sim = WindshieldSim(seed=11)
    scatter(sim, 400, (1.0, 5.0), seed=3)
    inputs = GlassInputs.for_speed(speed_kmh, 0.0)
    for _ in range(15):
        sim.step(1 / 30, inputs)
    return float((sim.mass * sim.vel[:, 1]).sum() / sim.mass.sum())


def test_parked_drops_run_down_and_at_motorway_speed_climb(scatter):
    down = _mean_velocity_up(scatter, 0.0)
    up = _mean_velocity_up(scatter, 120.0)
    assert down < 0.0
    assert up > 0.0
    # Small drops stick, large ones run (parked): pinning ∝ a, weight ∝ a³.
    sim = WindshieldSim(seed=1)
    scatter(sim, 50, (0.5, 1.5))
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
