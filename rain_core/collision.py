"""The street as the ego car feels it: the kerbs (a step that costs speed), the end of the sidewalks where the
façades stand (a wall), and the posts, tree trunks, parked cars and station parts on the way (solid). GL-free.

Everything solid is a wall along the street (x beyond ``wall_x``, which opens onto the fuel station's forecourt)
or a circle (a lamp post, a sign post, a trunk, a pillar; a box — a parked car, a pump island — is its outline in
circles), so one contact rule serves all:
the car's footprint (its spec's length × width, a rectangle) is pushed out along the contact normal and the part
of its velocity into the obstacle is reversed with restitution ``RESTITUTION`` and Coulomb friction on the rest.
The kinematic car keeps the share of that velocity along its heading, and a glancing hit turns it part of the way
along the wall. The car sub-steps at 0.01 s, so it moves at most 0.7 m per contact check, far less than its own
length: no obstacle can be passed through (the walls are half-planes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rain_core import layout

WALL_X_M = layout.ROAD_HALF_WIDTH_M + layout.KERB_WIDTH_M + layout.SIDEWALK_WIDTH_M  # 10.3 m: the sidewalk ends
FORECOURT_BACK_X_M = 33.5  # m: the fuel station's forecourt opens the +x wall this far
_NEAREST_WALL_X_M = min(WALL_X_M, FORECOURT_BACK_X_M)  # no wall lies nearer the centre line than this
RESTITUTION = 0.1
FRICTION = 0.4  # Coulomb: tangential speed lost per unit of normal speed removed
GLANCE_TURN = 0.5  # share of the angle to the new velocity the heading turns by on a glancing hit
KERB_UP_LOSS = 0.12  # share of the speed a wheel climbing the kerb costs (a 15 cm step)
KERB_DOWN_LOSS = 0.04
REACH_M = 8.0  # circles further than this along z from the car are not tested
CACHE_SLACK_M = 4.0  # m a car may move before its window of nearby circles is made again


@dataclass(frozen=True)
class StreetSolids:
    """Circles (N, 3): x, z (m, z in one tile [0, PERIOD_M)), radius (m); the forecourt's z range (m)."""

    circles: np.ndarray
    forecourt_z: tuple[float, float]


def box_outline(x0: float, x1: float, z0: float, z1: float, radius: float = 0.3) -> np.ndarray:
    """(N, 3) circles of ``radius`` (m) along the outline of the box [x0, x1] × [z0, z1] (m), at most a radius
    apart, so the car's corners cannot slip between them."""
    circles = []
    for (ax, az), (bx, bz) in (((x0, z0), (x1, z0)), ((x1, z0), (x1, z1)), ((x1, z1), (x0, z1)),
                               ((x0, z1), (x0, z0))):
        n = max(1, math.ceil(math.hypot(bx - ax, bz - az) / radius))
        t = np.arange(n) / n
        circles.append(np.stack([ax + (bx - ax) * t, az + (bz - az) * t, np.full(n, radius)], axis=1))
    return np.concatenate(circles)


def inset_box_outline(x0: float, x1: float, z0: float, z1: float, radius: float = 0.3) -> np.ndarray:
    """Circles whose union's outer edge is the box [x0, x1] × [z0, z1] (m) with corners rounded by ``radius``
    (m): the outline of the box shrunk by the radius (a parked car is solid up to its body, not 0.3 m beyond)."""
    r = min(radius, (x1 - x0) / 2, (z1 - z0) / 2)
    return box_outline(x0 + r, x1 - r, z0 + r, z1 - r, r)


def street_solids(world) -> StreetSolids:
    """The solids of ``world`` (rain_core.world.World): its lamp posts, sign posts, tree trunks, parked cars
    (``world.solid_boxes``) and station parts."""
    from rain_core.world.street import station_solid_boxes

    circles = [np.asarray(getattr(world, "solid_circles", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)]
    circles += [box_outline(*box) for box in station_solid_boxes()]
    boxes = np.asarray(getattr(world, "solid_boxes", np.zeros((0, 4))), dtype=np.float64).reshape(-1, 4)
    circles += [inset_box_outline(*box) for box in boxes]
    return StreetSolids(np.concatenate(circles), (layout.CANOPY_Z_M - 28.0, layout.CANOPY_Z_M + 48.0))


class StreetCollider:
    """Keeps a car in the street: ``resolve(car)`` after each of its sub-steps; ``keep_inside(x, z)`` clamps a
    point (a chase camera) to the open street."""

    def __init__(self, solids: StreetSolids):
        self.solids = solids
        order = np.argsort(solids.circles[:, 1])
        self._circles = solids.circles[order]
        self._z = self._circles[:, 1]
        # (z m it was made at, circles, their least |x| − radius m) of _nearby
        self._window: tuple[float, np.ndarray, float] | None = None

    def wall_x(self, x: float, z: float) -> float:
        """|x| (m) of the wall on the side of x at z (m, any world z)."""
        zz = z % layout.PERIOD_M
        if x > 0.0 and self.solids.forecourt_z[0] <= zz <= self.solids.forecourt_z[1]:
            return FORECOURT_BACK_X_M
        return WALL_X_M

    def keep_inside(self, x: float, z: float, margin_m: float = 0.4) -> float:
        """x (m) moved inside the walls at z by at least margin_m."""
        limit = self.wall_x(x, z) - margin_m
        return min(max(x, -limit), limit)

    def _nearby_circles(self, z: float) -> np.ndarray:
        """The circles within REACH_M + CACHE_SLACK_M along z of ``z`` (m), in its period. A car's sub-steps ask
        about nearly the same z: the last window is kept while z stays within CACHE_SLACK_M of where it was
        made (a circle further than REACH_M cannot touch a car, so the wider set gives the same contacts)."""
        return self._nearby(z)[0]

    def _nearby(self, z: float) -> tuple[np.ndarray, float]:
        """(``_nearby_circles(z)``, the least |x| − radius (m) among them: how far across x the nearest one's edge
        lies from the street's centre line; inf without circles)."""
        cached = self._window
        if cached is not None and abs(z - cached[0]) <= CACHE_SLACK_M:
            return cached[1], cached[2]
        zz = z % layout.PERIOD_M
        reach = REACH_M + CACHE_SLACK_M
        out = []
        for shift in (-layout.PERIOD_M, 0.0, layout.PERIOD_M):
            a, b = np.searchsorted(self._z, [zz - reach - shift, zz + reach - shift])
            if b > a:
                c = self._circles[a:b].copy()
                c[:, 1] += shift + (z - zz)
                out.append(c)
        circles = np.concatenate(out) if out else np.zeros((0, 3))
        inner = float((np.abs(circles[:, 0]) - circles[:, 2]).min()) if len(circles) else math.inf
        self._window = (z, circles, inner)
        return circles, inner

    def resolve(self, car) -> bool:
        """Push ``car`` (rain_core.vehicles.Vehicle) out of whatever it overlaps and take the speed the contact
        costs; True if it touched something."""
        spec = car.spec
        half_l, half_w = spec.length_m / 2.0, spec.width_m / 2.0
        touched = False
        for _ in range(3):  # a corner can touch a wall and a post at once: a few passes settle it
            contact = self._deepest(car, half_l, half_w)
            if contact is None:
                # Nothing touches at this pose, the walls included (_deepest starts from them): nothing to add.
                return touched
            depth, normal = contact
            car.position[0] += normal[0] * depth
            car.position[2] += normal[1] * depth
            self._respond(car, normal)
            touched = True
        # A car squeezed between a solid and a wall (a parked car beside the façade) may have been pushed over
        # the wall by the last pass: the walls have the last word.
        wall = self._wall_contact(car, half_l, half_w)
        if wall is not None:
            depth, normal = wall
            car.position[0] += normal[0] * depth
            self._respond(car, normal)
            touched = True
        return touched

    def _wall_contact(self, car, half_l: float, half_w: float):
        """(depth m, normal) of the footprint's deepest corner beyond a wall, or None."""
        # Every corner lies within the footprint's half-diagonal of the centre (and a µm of rounding): a car that
        # far inside the nearer wall touches none (a car on the road: every sub-step), without its four corners.
        if abs(float(car.position[0])) + math.hypot(half_l, half_w) + 1e-6 < _NEAREST_WALL_X_M:
            return None
        return self._wall_corners(car, half_l, half_w)

    def _wall_corners(self, car, half_l: float, half_w: float):
        """``_wall_contact`` by testing each of the footprint's four corners."""
        fx, fz = -math.sin(car.yaw), -math.cos(car.yaw)
        rx, rz = math.cos(car.yaw), -math.sin(car.yaw)
        px, pz = float(car.position[0]), float(car.position[2])
        best = None
        for sl, sw in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            cx = px + fx * half_l * sl + rx * half_w * sw
            cz = pz + fz * half_l * sl + rz * half_w * sw
            side = 1.0 if cx > 0.0 else -1.0
            over = abs(cx) - self.wall_x(cx, cz)
            if over > 0.0 and (best is None or over > best[0]):
                best = (over, (-side, 0.0))
        return best

    def _deepest(self, car, half_l: float, half_w: float):
        """(depth m, outward normal (nx, nz)) of the deepest overlap, or None."""
        fx, fz = -math.sin(car.yaw), -math.cos(car.yaw)
        rx, rz = math.cos(car.yaw), -math.sin(car.yaw)
        px, pz = float(car.position[0]), float(car.position[2])
        # Walls: the footprint's corners beyond |x| = wall.
        best = self._wall_contact(car, half_l, half_w)
        # Circles: the nearest point of the footprint (in the car's frame) to each centre.
        circles, inner = self._nearby(pz)
        if len(circles):
            bound = math.hypot(half_l, half_w) + 1e-6
            # Every circle's edge lies further across x than the footprint's bounding circle reaches (by a mm, far
            # beyond rounding): the test below would find none, without its arrays (a car in its lane, posts on
            # the sidewalks: nearly every sub-step).
            if inner - abs(px) > bound + 1e-3:
                return best
            dx, dz = circles[:, 0] - px, circles[:, 1] - pz
            # No circle reaches the footprint's bounding circle (radius hypot(half_l, half_w), with a margin for
            # rounding): no contact, without the footprint's nearest points (most sub-steps, far from posts).
            reach = circles[:, 2] + bound
            if not (dx * dx + dz * dz < reach * reach).any():
                return best
            lf = np.minimum(np.maximum(dx * fx + dz * fz, -half_l), half_l)  # np.clip, without its wrapper
            lr = np.minimum(np.maximum(dx * rx + dz * rz, -half_w), half_w)
            qx, qz = px + fx * lf + rx * lr, pz + fz * lf + rz * lr
            ox, oz = qx - circles[:, 0], qz - circles[:, 1]
            dist = np.hypot(ox, oz)
            depth = circles[:, 2] - dist
            i = int(depth.argmax())
            if depth[i] > 0.0 and (best is None or depth[i] > best[0]):
                if dist[i] > 1e-9:
                    n = (ox[i] / dist[i], oz[i] / dist[i])
                else:  # the centre is inside the footprint: out the way the car came
                    n = (-fx * math.copysign(1.0, car.speed_m_s or 1.0), -fz * math.copysign(1.0, car.speed_m_s or 1.0))
                    depth[i] = circles[i, 2] + half_w
                best = (float(depth[i]), n)
        return best

    @staticmethod
    def _respond(car, normal) -> None:
        fx, fz = -math.sin(car.yaw), -math.cos(car.yaw)
        v = car.speed_m_s
        vx, vz = fx * v, fz * v
        vn = vx * normal[0] + vz * normal[1]
        if vn >= 0.0:
            return  # already leaving
        tx, tz = vx - vn * normal[0], vz - vn * normal[1]
        removed = (1.0 + RESTITUTION) * -vn
        t_speed = math.hypot(tx, tz)
        keep = max(0.0, 1.0 - FRICTION * removed / t_speed) if t_speed > 1e-9 else 0.0
        nx_, nz_ = tx * keep + RESTITUTION * -vn * normal[0], tz * keep + RESTITUTION * -vn * normal[1]
        along = nx_ * fx + nz_ * fz
        speed = math.hypot(nx_, nz_)
        if speed > 0.5 and along * v > 0.0:  # glancing: the heading turns part of the way along the new motion
            heading = math.atan2(-nx_ * math.copysign(1.0, v), -nz_ * math.copysign(1.0, v))
            car.yaw = math.remainder(car.yaw + GLANCE_TURN * math.remainder(heading - car.yaw, math.tau), math.tau)
        car.speed_m_s = along
        car.yaw_rate_rad_s = 0.0


def kerb_crossings(before: np.ndarray, after: np.ndarray) -> tuple[int, int]:
    """(up, down): wheels that climbed onto / came off the kerb between two sets of contacts (4, 3) m."""
    edge = layout.ROAD_HALF_WIDTH_M
    # Four wheels, asked every sub-step: compared as Python floats (the same comparisons, no NumPy calls).
    up = down = 0
    for x0, x1 in zip(before[:, 0].tolist(), after[:, 0].tolist(), strict=True):
        was, now = abs(x0) > edge, abs(x1) > edge
        up += now and not was
        down += was and not now
    return up, down


def kerb_speed(speed_m_s: float, up: int, down: int) -> float:
    """The speed (m/s) left after ``up`` wheels climbed the kerb and ``down`` came off it (each a share lost)."""
    return speed_m_s * (1.0 - KERB_UP_LOSS) ** up * (1.0 - KERB_DOWN_LOSS) ** down
