"""rain_core.effects.windshield.glass / constants: the glass surface against the mesh, and a drop's cap."""

import math

import numpy as np
import pytest

from rain_core.effects.windshield import GlassGeometry, drop_mass, drop_radius


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
