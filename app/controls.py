"""Keyboard driving: held keys → smoothed throttle, brake and steering (the car model takes [0,1] and [-1,1])."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import layout

# Every key of the window, in the order the help overlay (F1), ``--help`` and the README list them.
KEY_HELP = (
    ("W / Up", "throttle (the autopilot drives until you touch a driving key)"),
    ("S / Down", "brake, then reverse once stopped"),
    ("A / Left, D / Right", "steer"),
    ("R", "reset: the car back on its lane at cruise speed"),
    ("C", "camera: driver's seat -> chase -> free-fly (free: WASD/arrows fly, drag the mouse to look)"),
    ("G", "close-up of the windshield from the driver's eye (G again: back to the seat)"),
    ("Tab", "hide / show the Rain Manager"),
    ("F1", "this list of keys"),
    ("F12", "screenshot to screenshots/"),
    ("Esc", "quit"),
)


def keys_help_text(indent: str = "  ") -> str:
    """KEY_HELP as aligned plain-text lines (for ``--help``)."""
    width = max(len(k) for k, _ in KEY_HELP)
    return "\n".join(f"{indent}{k:<{width}}  {action}" for k, action in KEY_HELP)


def reset_to_lane(scene) -> None:
    """Put the ego car back on the autopilot's lane, wheels straight, facing along the lane at the autopilot's
    cruise speed (m/s), where it was along the street (z kept): the R key and the Rain Manager's button."""
    ego, lane = scene.ego, scene.autopilot.lane_index
    ego.position = np.array([layout.LANE_CENTRES_X[lane], 0.0, float(ego.position[2])])
    ego.yaw = float(layout.LANE_YAW[lane])
    ego.speed_m_s = float(scene.autopilot.target_speed_m_s)
    ego.steer_rad = 0.0
    ego.yaw_rate_rad_s = 0.0
    ego.previous_wheel_contacts = ego.wheel_contacts()  # no swept wheel path across the jump
    scene.chase.reset()


@dataclass
class DriveInput:
    throttle: float = 0.0  # [0, 1]
    brake: float = 0.0  # [0, 1]
    steer: float = 0.0  # [-1, 1], +1 = left
    reverse: bool = False


class KeyboardDriver:
    """Tracks held keys by name ("up", "down", "left", "right") and eases the steering so a tap is not a jerk."""

    STEER_RATE_PER_S = 2.5  # full lock in 0.4 s
    RETURN_RATE_PER_S = 4.0

    def __init__(self):
        self._keys: dict[object, str] = {}  # physical key → action ("up", …): W and ↑ both mean "up"
        self.state = DriveInput()
        self.autopilot = True  # until the user touches a driving key

    @property
    def held(self) -> set[str]:
        return set(self._keys.values())

    def press(self, name: str, key: object = None):
        self._keys[name if key is None else key] = name
        self.autopilot = False

    def release(self, name: str, key: object = None):
        self._keys.pop(name if key is None else key, None)

    def center(self):
        """Wheels straight and no drive input held over (after a reset)."""
        self.state = DriveInput()

    def update(self, dt_s: float, speed_m_s: float) -> DriveInput:
        dt_s = min(max(dt_s, 0.0), 0.1) if math.isfinite(dt_s) else 0.0
        forward, back = "up" in self.held, "down" in self.held
        s = self.state
        # "down" brakes while moving forward and reverses once stopped, as in most driving games.
        if back and speed_m_s <= 0.5:
            s.reverse, s.throttle, s.brake = True, 1.0, 0.0
        else:
            s.reverse = False if forward else s.reverse and back
            s.throttle = 1.0 if forward else 0.0
            s.brake = 1.0 if back else 0.0
        target = (1.0 if "left" in self.held else 0.0) - (1.0 if "right" in self.held else 0.0)
        rate = self.STEER_RATE_PER_S if target != 0.0 else self.RETURN_RATE_PER_S
        delta = target - s.steer
        s.steer += max(-rate * dt_s, min(rate * dt_s, delta))
        return DriveInput(s.throttle, s.brake, s.steer, s.reverse)
