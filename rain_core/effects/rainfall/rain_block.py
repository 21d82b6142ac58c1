"""The rainfall's per-frame uniform block, ``RainFrame`` in shaders/rainfall/rain_frame.glsl (std140): the values
that change every frame (the boxes' offsets, the vehicles' poses, the clock, the splash box, the camera's
velocity, the lights that reach the boxes), packed once a frame into one buffer that the streak and splash
programs both read (issue 13: one buffer write instead of a dozen uniform writes into each program)."""

from __future__ import annotations

import struct

import numpy as np

from rain_core.effects.rainfall.constants import LAYER_SCALES, MAX_VEHICLES
from rain_core.lighting import MAX_LIGHTS

LAYERS = len(LAYER_SCALES)
RAIN_FRAME_BINDING = 1  # its uniform-buffer binding point (the frame block has 0: gfx.frame_block.BINDING)
# The block's scalar head, std140: a vec3 array's elements 16 bytes apart; u_wind (vec3) + u_time_whole,
# u_time_frac, u_epoch, 8 bytes to the next vec3; u_splash_lo + u_splash_count, u_splash_off + u_splash_tau,
# u_cam_vel + u_light_count. The three light arrays follow (vec4 each, 16-byte aligned: no padding).
RAIN_FRAME = struct.Struct("=" + "3f4x" * (3 * LAYERS) + f"{4 * MAX_VEHICLES}f" + "3fifI8x" + "3fI" + "3ff" + "3fi")
LIGHT_ARRAY_BYTES = 16 * MAX_LIGHTS  # one of u_light_pos / dir / color: lighting.pack_lights' buffers
RAIN_FRAME_BYTES = RAIN_FRAME.size + 3 * LIGHT_ARRAY_BYTES
_NO_LIGHTS = (bytes(LIGHT_ARRAY_BYTES), bytes(LIGHT_ARRAY_BYTES), bytes(LIGHT_ARRAY_BYTES), 0)


def pack_rain_frame(box_lo: list, box_off: list, box_turb: list, pose: list, wind, time: tuple, splash_lo,
                    splash_count: int, splash_off, splash_tau: float, cam_vel, lights: tuple = _NO_LIGHTS) -> bytes:
    """The block's bytes: box_lo, box_off, box_turb 3·LAYERS floats each, pose 4·MAX_VEHICLES floats, wind and
    the three-vectors 3 floats, time = drops.time_split's (whole, frac, epoch), lights = (pos, dir, color bytes of
    MAX_LIGHTS vec4 each, count), lighting.pack_lights' form (default: none)."""
    pos_b, dir_b, col_b, count = lights
    return b"".join((RAIN_FRAME.pack(*box_lo, *box_off, *box_turb, *pose, *wind, *time, *splash_lo, splash_count,
                                     *splash_off, splash_tau, *cam_vel, count), pos_b, dir_b, col_b))


def rain_frame_from_uniforms(values: dict) -> bytes:
    """The block from ``RainfallEffect.drop_uniforms``' dict (the debug probe's; splash and camera values 0, no
    lights)."""
    def floats(name):
        return np.asarray(values[name], np.float64).ravel().tolist()

    return pack_rain_frame(floats("u_box_lo"), floats("u_box_off"), floats("u_box_turb"), floats("u_veh_pose"),
                           floats("u_wind"), (values["u_time_whole"], values["u_time_frac"], values["u_epoch"]),
                           (0.0, 0.0, 0.0), 0, (0.0, 0.0, 0.0), 0.0, (0.0, 0.0, 0.0))
