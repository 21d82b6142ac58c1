"""rainfall's per-frame CPU paths (issue 13): the cached and packed forms equal what they replace."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from rain_core import layout
from rain_core.effects.rainfall.boxes import layer_boxes, wrap_near
from rain_core.effects.rainfall.constants import MAX_VEHICLES
from rain_core.effects.rainfall.effect import RainfallEffect
from rain_core.effects.rainfall.vehicle_fate import (
    PIECES_PER_VEHICLE,
    PLANES_PER_PIECE,
    cull_vehicles,
    piece_volumes,
    vehicle_uniforms,
)
from rain_core.vehicles import CAR_SPEC, TRUCK_SPEC, VAN_SPEC, Vehicle


def _fleet(rng, n=9):
    specs = (CAR_SPEC, VAN_SPEC, TRUCK_SPEC)
    return [Vehicle(specs[i % 3], position=(rng.uniform(-8, 8), 0.0, rng.uniform(-3000, 3000)),
                    yaw=rng.uniform(-3, 3)) for i in range(n)]


def test_vehicle_uniforms_equal_the_pieces_of_each_vehicle_in_order():
    rng = np.random.default_rng(4)
    for trial in range(4):
        vehicles = _fleet(rng, n=3 + 2 * trial)
        got = vehicle_uniforms(vehicles, shift_z=1200.0, around_z=40.0)
        n, m = PIECES_PER_VEHICLE, PIECES_PER_VEHICLE * PLANES_PER_PIECE
        assert got["u_veh_count"] == min(len(vehicles), MAX_VEHICLES)
        for i in range(MAX_VEHICLES):
            if i < len(vehicles):
                v = vehicles[i]
                plo, phi, pp = piece_volumes(v.spec)
                z = float(wrap_near(v.position[2] - 1200.0, 40.0))
                np.testing.assert_array_equal(got["u_veh_pose"][i], (v.position[0], v.position[1], z, v.yaw))
            else:
                plo = phi = np.zeros((n, 3))
                pp = np.zeros((m, 4))
                np.testing.assert_array_equal(got["u_veh_pose"][i], 0.0)
            np.testing.assert_array_equal(got["u_veh_lo"][i * n:(i + 1) * n, :3], plo)
            np.testing.assert_array_equal(got["u_veh_hi"][i * n:(i + 1) * n, :3], phi)
            np.testing.assert_array_equal(got["u_veh_plane"][i * m:(i + 1) * m], pp.reshape(-1, 4))
        # The pieces are shared and read-only: a caller cannot corrupt the next frame's.
        assert not got["u_veh_lo"].flags.writeable and not got["u_veh_plane"].flags.writeable


def test_cull_vehicles_keeps_the_nearest_within_reach_with_the_period_wrapped():
    rng = np.random.default_rng(7)
    vehicles = _fleet(rng, n=40)
    centre = np.array([1.0, 2500.0])
    reach = 80.0
    got = cull_vehicles(vehicles, centre, reach)
    dist = [float(np.hypot(v.position[0] - centre[0], wrap_near(v.position[2] - centre[1], 0.0))) for v in vehicles]
    want = sorted((d, i) for i, (d, v) in enumerate(zip(dist, vehicles, strict=True))
                  if d <= reach + 0.5 * v.spec.length_m)[:MAX_VEHICLES]
    assert [id(v) for v in got] == [id(vehicles[i]) for _, i in want]
    # A real test: some of the vehicles kept are near only through the period's wrap.
    assert any(abs(v.position[2] - centre[1]) > layout.PERIOD_M / 2 for v in got)


def test_lights_are_packed_as_each_buffer_alone():
    """_lights packs the three light buffers in one pass: the bytes equal packing each buffer by itself."""
    rng = np.random.default_rng(2)
    count, slots = 9, 16
    pos = np.zeros((slots, 4), np.float32)
    pos[:count, :3] = rng.uniform(-80, 80, (count, 3))
    pos[:count, 3] = rng.uniform(-40, 40, count)  # w < 0: a low beam (its |w| is the range)
    dirs = rng.standard_normal((slots, 4)).astype(np.float32)
    cols = rng.uniform(0, 5, (slots, 4)).astype(np.float32)
    boxes = layer_boxes(np.array([0.0, 1.2, 30.0]), np.array([0.0, 0.0, -1.0]), 40.0)
    rc = SimpleNamespace(lights=(pos.tobytes(), dirs.tobytes(), cols.tobytes(), count), shift_z=5.0)
    got = RainfallEffect._lights(None, rc, boxes)
    lo = boxes.lo[-1] - [0.0, 0.0, 5.0]
    hi = boxes.hi[-1] - [0.0, 0.0, 5.0]
    gap = np.maximum(np.maximum(lo - pos[:count, :3], pos[:count, :3] - hi), 0.0)
    keep = np.flatnonzero(np.linalg.norm(gap, axis=1) < np.abs(pos[:count, 3]))
    assert 0 < keep.size < count  # a real test: some lights reach the rain, some do not
    for arr, data in zip((pos, dirs, cols), got[:3], strict=True):
        packed = np.zeros_like(arr)
        packed[:keep.size] = arr[keep]
        assert data == packed.tobytes()
    assert got[3] == keep.size


class _Uniform:
    def __init__(self, log, name):
        self.log, self.name = log, name

    def write(self, data):
        self.log.append((self.name, data))

    @property
    def value(self):
        raise AttributeError

    @value.setter
    def value(self, v):
        self.log.append((self.name, v))


class _Program(dict):
    __hash__ = object.__hash__  # a program is its own key in owned_uniforms' weak table
    __eq__ = object.__eq__

    def __init__(self, names):
        self.log = []
        super().__init__({n: _Uniform(self.log, n) for n in names})


def test_set_skips_only_values_equal_to_the_last_written():
    """The effect's uniform cache: an unchanged value (or the same read-only array) is not written again; a
    changed value, a writeable array edited in place, or another value in between is."""
    effect = RainfallEffect.__new__(RainfallEffect)
    prog = _Program(["u_box_lo", "u_veh_lo", "u_light_count"])
    frozen = np.arange(8.0)
    frozen.flags.writeable = False
    live = np.arange(3.0)
    effect._set(prog, {"u_veh_lo": frozen, "u_box_lo": live})
    effect._set(prog, {"u_veh_lo": frozen, "u_box_lo": live})
    assert [n for n, _ in prog.log] == ["u_veh_lo", "u_box_lo"]
    live[1] = 7.0  # edited in place: written again
    effect._set(prog, {"u_box_lo": live})
    assert prog.log[-1] == ("u_box_lo", live.astype(np.float32).tobytes())
    other = np.zeros(8)
    effect._set(prog, {"u_veh_lo": other})
    effect._set(prog, {"u_veh_lo": frozen})  # back to the frozen array after another value: written
    assert [n for n, _ in prog.log] == ["u_veh_lo", "u_box_lo", "u_box_lo", "u_veh_lo", "u_veh_lo"]
    assert prog.log[-1][1] == frozen.astype(np.float32).tobytes()
    # Another effect drawing with the same program shares its cache; a name others may also write (the frame's
    # light count) is written every time.
    second = RainfallEffect.__new__(RainfallEffect)
    second._set(prog, {"u_veh_lo": frozen, "u_light_count": 3})
    effect._set(prog, {"u_light_count": 3})
    assert [n for n, _ in prog.log[5:]] == ["u_light_count", "u_light_count"]
