"""rainfall occlusion: no drawn drop under a roof or inside a vehicle, no streak under the bridge."""

from __future__ import annotations

import math

import numpy as np

from rain_core import layout
from rain_core.effects.rainfall import RainfallSim
from rain_core.effects.rainfall.vehicle_fate import vehicle_pieces

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


def test_no_drawn_drop_is_ever_under_a_roof_or_in_a_vehicle(world, rain):
    """The twin of the vertex shader's culling (the GPU's agrees: test_stateless), driving under the bridge in
    wind with a van alongside: no visible drop under the roof map or inside a vehicle's body, at any frame."""
    from rain_core.vehicles import VAN_SPEC, EgoCar, Vehicle

    sim = RainfallSim(20000, seed=3, world=world)
    ego = EgoCar(position=np.array([layout.LANE_CENTRES_X[0], 0.0, layout.BRIDGE_Z_M + 25.0]), speed_m_s=12.0)
    van = Vehicle(VAN_SPEC, position=np.array([layout.LANE_CENTRES_X[1], 0.0, layout.BRIDGE_Z_M + 10.0]))
    vehicles = (ego, van)
    dt = 1.0 / 30.0
    checked = culled_in_vehicles = 0
    for i in range(120):  # drive under the bridge, in wind
        t = i * dt
        ego.step(dt, 0.0, 0.0, 0.0)
        ego.speed_m_s = 12.0
        cam = ego.position + np.array([-0.37, 1.2, 0.59])
        sim.advance(rain.input(t, pos=cam, vel=ego.velocity(), rate=28.0, wind=(2.5, 0.0, -1.0),
                               vehicles=vehicles, forward=ego.forward()))
        if i % 15 != 14:
            continue
        d = sim.drops()
        p = d["pos"][d["visible"]]
        h = world.occluder_height(p[:, 0], p[:, 2])
        assert not np.any(p[:, 1] < h), "a drop under a roof"
        assert np.all(p[:, 1] >= 0.0)
        for veh in vehicles:
            rel = p - veh.position
            rel[:, 2] -= layout.PERIOD_M * np.round(rel[:, 2] / layout.PERIOD_M)
            cy, sy = math.cos(veh.yaw), math.sin(veh.yaw)
            lx, lz = cy * rel[:, 0] - sy * rel[:, 2], sy * rel[:, 0] + cy * rel[:, 2]
            for poly, half_w in vehicle_pieces(veh.spec):
                assert not _inside_piece(lx, rel[:, 1], lz, poly, half_w).any(), "a drop inside a vehicle"
            # …and the culling did something: drawn drops inside the bodies were removed.
            q = d["pos"][d["drawn"]] - veh.position
            q[:, 2] -= layout.PERIOD_M * np.round(q[:, 2] / layout.PERIOD_M)
            qx, qz = cy * q[:, 0] - sy * q[:, 2], sy * q[:, 0] + cy * q[:, 2]
            for poly, half_w in vehicle_pieces(veh.spec):
                culled_in_vehicles += int(_inside_piece(qx, q[:, 1], qz, poly, half_w, eps=0.02).sum())
        checked += p.shape[0]
    assert checked > 10000 and culled_in_vehicles > 0
    # Under the deck itself there is not a single drop, while the open road beside it has many.
    d = sim.drops()
    p = d["pos"][d["visible"]]
    dz = p[:, 2] - layout.BRIDGE_Z_M
    under = (np.abs(dz) < layout.BRIDGE_DEPTH_M / 2 - 1.0) & (np.abs(p[:, 0]) < 7.0)
    assert not np.any(under & (p[:, 1] < layout.BRIDGE_CLEARANCE_M))
    beside = (np.abs(dz) > layout.BRIDGE_DEPTH_M / 2 + 1.0) & (np.abs(p[:, 0]) < 7.0)
    assert np.count_nonzero(beside & (p[:, 1] < layout.BRIDGE_CLEARANCE_M)) > 200


def test_top_view_under_the_bridge_has_no_streak_pixels(gl_ctx, shaders, rain):
    from rain_core.camera import Camera

    s = rain.settings(rate=80.0, container_m=30.0, budget=20000)
    s.wind.speed_m_s = 3.0
    scene, _ = rain.scene(gl_ctx, shaders, s)
    scene.step(1.0 / 60.0)
    down = dict(forward=np.array([0.0, -1.0, 0.0]), up=np.array([0.0, 0.0, -1.0]), fov_y_deg=40.0)
    under = Camera(position=np.array([0.0, 4.8, layout.BRIDGE_Z_M]), **down)
    light = rain.light(scene, under, s)
    assert np.count_nonzero(light > 0.0) == 0
    # The same view out in the open is full of streaks (so the test can fail).
    scene2, _ = rain.scene(gl_ctx, shaders, s)
    scene2.step(1.0 / 60.0)
    open_air = Camera(position=np.array([0.0, 4.8, layout.BRIDGE_Z_M + 80.0]), **down)
    assert np.count_nonzero(rain.light(scene2, open_air, s) > 1e-4) > 100
