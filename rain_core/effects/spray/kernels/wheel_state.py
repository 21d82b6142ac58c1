"""Kernels of the wheels: contacts, velocities and launch axes of every wheel of every vehicle
(``wheel_kinematics``) and the water each one meets (``wheel_water``). Twin: ``wheels``. Units: m, m/s, mm."""

from __future__ import annotations

import math

import numpy as np

from rain_core import jit


@jit.kernel
def wheel_kinematics(state, cos_yaw, sin_yaw, local, consts, side, vehicle, wheel, signed):
    """``wheels.gather_wheels``' rigid-body kinematics of every vehicle's wheels (``Vehicle.to_world`` and
    ``_point_velocity``, about the rear axle): from ``state`` (V, 6) x, z (m), yaw, speed (m/s), yaw rate (rad/s),
    y (m), the yaw's cosine and sine (NumPy's, as the twin), the wheels' local contacts (V, 4, 3) m, the fleet's
    constants (V, 4; column 3 the half wheelbase) and the wheels' sides ``side`` (4V,) ±1. Writes the vehicle
    table's position, velocity, right and forward (``vehicle`` (V, 20) columns 0–11) and the wheel table's
    velocity, contact, travel, outward and speed (``wheel`` (4V, 15) columns 0–11 and 14); ``signed`` (4V,) the
    wheels' ground speeds with the sign of travel (m/s)."""
    for vi in range(state.shape[0]):
        px, pz, speed, omega, py = state[vi, 0], state[vi, 1], state[vi, 3], state[vi, 4], state[vi, 5]
        c, s = cos_yaw[vi], sin_yaw[vi]
        fx, fz = -s, -c  # forward (−sin, 0, −cos), right (cos, 0, −sin)
        row = vehicle[vi]
        row[0], row[1], row[2] = px, py, pz
        row[6], row[8] = c, fx
        row[9], row[11] = fx, fz
        hwb = consts[vi, 3]
        ax = px + s * hwb  # the rear axle
        az = pz + c * hwb
        bx, by, bz = fx * speed, row[10] * speed, fz * speed
        row[3] = bx + omega * (pz - az)
        row[5] = bz + omega * (ax - px)
        vx, vy, vz = row[3], row[4], row[5]
        back = -1.0 if speed < 0.0 else 1.0
        for k in range(4):
            w = 4 * vi + k
            lx, ly, lz = local[vi, k, 0], local[vi, k, 1], local[vi, k, 2]
            cx = c * lx + s * lz + px
            cz = c * lz - s * lx + pz
            out = wheel[w]
            out[0], out[1], out[2] = vx, vy, vz
            out[3], out[4], out[5] = cx, ly + py, cz
            wx = bx + omega * (cz - az)
            wz = bz - omega * (cx - ax)
            sp = math.sqrt((wx * wx + wz * wz) + by * by)  # np.einsum's order
            out[14] = sp
            signed[w] = sp * back
            out[6], out[7], out[8] = fx * back, row[10] * back, fz * back
            sg = side[w]
            out[9], out[10], out[11] = c * sg, row[7] * sg, fx * sg


@jit.kernel
def wheel_water(signed, wheel, depth, planing_speed, bands, consts):
    """``water.allocate_water_unchecked`` and ``hydroplaning_risk_unchecked`` at every wheel: its ground speed
    ``signed`` (m/s, either sign), tread width ``wheel[:, 13]`` (m) and the film ``depth`` the road's sampler gave
    (mm: NaN counts as dry, below 0 as 0, capped at MAX_FILM_DEPTH_MM). ``bands`` (4, 4): per mechanism its depth
    band's start and width (mm) and its release ramp's start and span (m/s); ``consts``: ρ_w·1e-3, the tread
    spray ramp's start and span, TREAD_SPRAY_SHARE, 1 − MIST_SHARE, MIST_SHARE, HYDRO_LIFT_ONSET, 1 − onset,
    the drained depth's start and span (mm), MAX_FILM_DEPTH_MM. Returns the depths (mm), M_w, the allocation and
    what is thrown per mechanism (kg/s), the six buckets (kg/s), the hydroplaning risk and whether any wheel
    throws water."""
    n = signed.shape[0]
    depth_out, available, risk = np.empty(n), np.empty(n), np.empty(n)
    allocated, thrown, buckets = np.empty((n, 4)), np.empty((n, 4)), np.empty((n, 6))
    rho_mm, spray_lo, spray_span, tread_share = consts[0], consts[1], consts[2], consts[3]
    keep_share, mist_share, onset, onset_span = consts[4], consts[5], consts[6], consts[7]
    drain_lo, drain_span, max_mm = consts[8], consts[9], consts[10]
    throwing = False
    for i in range(n):
        d = depth[i]
        d = 0.0 if not d > 0.0 else d  # np.fmax(d, 0): NaN and below 0 → 0
        d = min(d, max_mm)
        depth_out[i] = d
        h_mm = (d * 1e-3) * 1e3
        v = abs(signed[i])
        flux = v * wheel[i, 13] * rho_mm
        available[i] = flux * h_mm
        total = 0.0
        for j in range(4):
            a = flux * min(max(h_mm - bands[j, 0], 0.0), bands[j, 1])
            allocated[i, j] = a
            thrown[i, j] = a * min(max((v - bands[j, 2]) / bands[j, 3], 0.0), 1.0)
            total += a
        scale = available[i] / total if total > 0.0 else 1.0
        for j in range(4):
            allocated[i, j] *= scale
            thrown[i, j] *= scale
            if thrown[i, j] > 0.0:
                throwing = True
        share = tread_share * min(max((v - spray_lo) / spray_span, 0.0), 1.0)
        tread_spray = thrown[i, 1] * share
        buckets[i, 0] = thrown[i, 0] * keep_share
        buckets[i, 1] = tread_spray * keep_share
        buckets[i, 2] = thrown[i, 1] - tread_spray
        buckets[i, 3] = thrown[i, 2]
        buckets[i, 4] = thrown[i, 3]
        buckets[i, 5] = (thrown[i, 0] + tread_spray) * mist_share
        lift = v / planing_speed[i]
        lift = lift * lift
        speed_part = min(max((lift - onset) / onset_span, 0.0), 1.0)
        depth_part = min(max(((d * 1e-3) * 1e3 - drain_lo) / drain_span, 0.0), 1.0)
        risk[i] = speed_part * depth_part
    return depth_out, available, allocated, thrown, buckets, risk, throwing
