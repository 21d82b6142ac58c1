"""The ego car's door mirrors: the scene behind, reflected by the mirror glass, in a low-resolution view drawn only
when a mirror is in the driver's view and large enough to show something.

A door mirror is a plane mirror, so its picture is the scene reflected about the glass's plane as seen from the
eye: ``Renderer.draw_mirror_view`` draws exactly that (the road's puddle reflection uses it about y = 0) into a
half-resolution target, scissored to the glass's bounding box on screen and clipped to what lies behind the
glass. The scene shader then shows that texture on the glass at its own screen position, times the glass's
reflectance. Outside the car (chase, free), behind the eye, facing away or under ``MIN_PIXELS`` of the frame, the
mirror is skipped and its glass stays dark.
"""

from __future__ import annotations

import dataclasses
import math

import moderngl
import numpy as np

from rain_core.car_mesh import door_mirror_faces
from rain_core.gfx.targets import RenderTarget, float_target

MIN_PIXELS = 150.0  # px² of the frame a mirror's glass must cover to be drawn (a 15×10 px glass)
VIEW_SCALE = 0.5  # resolution of the mirror view relative to the frame
REFLECTANCE = 0.5  # a silvered door mirror (UN ECE R46 asks at least 0.4)
CLIP_OFFSET_M = 0.01  # m behind the glass kept out of its view (its own housing)
AIM_OUTWARD_DEG = 15.0  # deg, where a driver aims a door mirror: this far outward of straight back, level


def reflection_about(point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The 4×4 reflection about the plane through ``point`` (m) with unit ``normal``."""
    n = np.asarray(normal, dtype=np.float64)
    m = np.eye(4)
    m[:3, :3] -= 2.0 * np.outer(n, n)
    m[:3, 3] = 2.0 * float(n @ np.asarray(point, dtype=np.float64)) * n
    return m


@dataclasses.dataclass(frozen=True)
class MirrorView:
    """One mirror to draw this frame: its reflection (4×4, wrapped frame), the clip plane keeping what is in front
    of the glass, and its bounding box on the frame (x, y, w, h) in pixels, GL's bottom-left origin."""

    reflection: np.ndarray
    clip_plane: tuple[float, float, float, float]
    box_px: tuple[int, int, int, int]


class DoorMirrors:
    """Plans and draws the ego car's mirror views (``views`` then ``render``); ``texture`` is what the scene
    shader samples, valid for the frame after ``render`` ran."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._faces_key = None
        self._faces = None
        self._corners = None  # the glasses' corners as Python floats (the quick rejection's input)
        self.target: RenderTarget | None = None

    def _local_faces(self, spec) -> np.ndarray:
        if self._faces_key is not spec:
            self._faces_key, self._faces = spec, door_mirror_faces(spec)
            self._corners = tuple(tuple(tuple(float(v) for v in corner) for corner in glass) for glass in self._faces)
        return self._faces

    def views(self, rc) -> list[MirrorView]:
        """The mirrors worth drawing in ``rc``'s view (none outside the car)."""
        frame = rc.frame
        ego = frame.ego
        if ego is None or not frame.camera.inside_car or getattr(ego, "spec", None) is None:
            return []
        faces = self._local_faces(ego.spec)
        if _clearly_out_of_view(self._corners, ego, rc.shift_z, rc.view_proj):
            return []
        model = ego.model_matrix().copy()
        model[2, 3] -= rc.shift_z
        # Every glass's corners projected at once: in the default view both lie beside the frame, and this one
        # product decides it (a per-glass loop of small NumPy calls cost more than the rest of the frame's plan).
        corners = faces @ model[:3, :3].T + model[:3, 3]  # (glasses, 4, 3)
        view_proj = rc.view_proj  # projection @ view, made once per context
        clip = corners @ view_proj[:, :3].T + view_proj[:, 3]  # (glasses, 4, 4)
        w = clip[..., 3]
        in_front = np.all(w > 1e-6, axis=1)  # a corner behind the eye drops the glass
        ndc = clip[..., :2] / np.where(w > 1e-6, w, 1.0)[..., None]
        overlaps = np.all(ndc.max(axis=1) > -1.0, axis=1) & np.all(ndc.min(axis=1) < 1.0, axis=1)
        candidates = np.flatnonzero(in_front & overlaps)
        if candidates.size == 0:
            return []
        width, height = rc.size
        eye = np.asarray(rc.camera_position, dtype=np.float64)
        views = []
        for index in candidates:
            centre = corners[index].mean(axis=0)
            if float(model[:3, 2] @ (eye - centre)) <= 0.0:  # seen from in front of the car: the glass's back
                continue
            x0, y0 = np.clip((ndc[index].min(axis=0) * 0.5 + 0.5) * (width, height), 0, (width, height))
            x1, y1 = np.clip((ndc[index].max(axis=0) * 0.5 + 0.5) * (width, height), 0, (width, height))
            # The glass's area on screen (a convex quad: the shoelace formula), not its box, decides.
            px = (ndc[index] * 0.5 + 0.5) * (width, height)
            area = 0.5 * abs(float(np.dot(px[:, 0], np.roll(px[:, 1], -1)) - np.dot(px[:, 1], np.roll(px[:, 0], -1))))
            if area < MIN_PIXELS or x1 - x0 < 1.0 or y1 - y0 < 1.0:
                continue
            normal = _adjusted_normal(model, centre, eye)
            plane = (*normal, -float(normal @ centre) - CLIP_OFFSET_M)
            box = (int(x0), int(y0), int(np.ceil(x1)) - int(x0), int(np.ceil(y1)) - int(y0))
            views.append(MirrorView(reflection_about(centre, normal), tuple(float(v) for v in plane), box))
        return views

    def render(self, rc, views: list[MirrorView]) -> None:
        """Draw each mirror's view into the half-resolution target, scissored to its glass."""
        width, height = rc.size
        size = (max(1, round(width * VIEW_SCALE)), max(1, round(height * VIEW_SCALE)))
        if self.target is None or self.target.size != size:
            if self.target is not None:
                self.target.release()
            self.target = float_target(self.ctx, size, 4, "f2", depth=True)
        for mirror in views:
            x, y, w, h = mirror.box_px
            sx, sy = size[0] / width, size[1] / height
            x0, y0 = int(x * sx), int(y * sy)
            box = (x0, y0, max(1, int(np.ceil((x + w) * sx)) - x0 + 1), max(1, int(np.ceil((y + h) * sy)) - y0 + 1))
            camera = _mirrored_camera(rc.frame.camera, mirror.reflection, rc.shift_z)
            self.target.fbo.scissor = box
            try:
                rc.renderer.draw_mirror_view(rc, self.target, camera, mirror.reflection, mirror.clip_plane)
            finally:
                self.target.fbo.scissor = None

    @property
    def texture(self) -> moderngl.Texture | None:
        return self.target.color if self.target is not None else None

    def release(self) -> None:
        if self.target is not None:
            self.target.release()
            self.target = None


# The quick rejection's margins: its float64 sums may differ from NumPy's products in the last bits (~1e-12 here),
# so it rejects only with room to spare and leaves anything near an edge to the exact test.
_W_CERTAIN = 1e-3  # every corner at least this far in front of the eye: its NDC is known to ~1e-9
_NDC_MARGIN = 1e-6
_W_MIN = 1e-6  # views()'s own "in front of the eye" threshold


def _clearly_out_of_view(corners, ego, shift_z: float, view_proj: np.ndarray) -> bool:
    """Whether every glass is certainly dropped by views()'s test (a corner behind the eye, or the whole glass
    beyond one side of the frame), in Python floats: in the default driver's view both mirrors lie beside the
    frame, and this answers that for ~1/10 of the NumPy test's cost. False means "not sure": the exact test runs."""
    c, s = math.cos(ego.yaw), math.sin(ego.yaw)  # Vehicle.model_matrix's rotation about +Y
    px, py, pz = (float(v) for v in ego.position)
    pz -= shift_z
    (x0, x1, x2, x3), (y0, y1, y2, y3), _, (w0, w1, w2, w3) = view_proj.tolist()
    for glass in corners:
        xs, ys = [], []
        behind = False
        for lx, ly, lz in glass:
            wx, wy, wz = c * lx + s * lz + px, ly + py, -s * lx + c * lz + pz
            w = w0 * wx + w1 * wy + w2 * wz + w3
            if w < _W_MIN - _NDC_MARGIN:
                behind = True
                break
            if w < _W_CERTAIN:
                return False
            xs.append((x0 * wx + x1 * wy + x2 * wz + x3) / w)
            ys.append((y0 * wx + y1 * wy + y2 * wz + y3) / w)
        if behind:
            continue
        if not (max(xs) < -1.0 - _NDC_MARGIN or min(xs) > 1.0 + _NDC_MARGIN
                or max(ys) < -1.0 - _NDC_MARGIN or min(ys) > 1.0 + _NDC_MARGIN):
            return False
    return True


def _adjusted_normal(model: np.ndarray, centre: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """The glass's normal as a driver sets it (world): halfway between the eye and the view wanted, level and
    ``AIM_OUTWARD_DEG`` outward of straight back, so the road behind sits mid-glass with the car's flank at its
    inner edge. (The glass is drawn square to the car; the tilt of a 14 cm glass is not seen, its picture is.)"""
    rear, right = model[:3, 2], model[:3, 0]  # the car's local +z points rearwards, +x to its right
    outward = np.sign(float(right @ (centre - model[:3, 3]))) * right
    a = np.radians(AIM_OUTWARD_DEG)
    view = rear * np.cos(a) + outward * np.sin(a)
    view[1] = 0.0
    to_eye = (eye - centre) / np.linalg.norm(eye - centre)
    n = to_eye + view / np.linalg.norm(view)
    return n / np.linalg.norm(n)


def _mirrored_camera(camera, reflection: np.ndarray, shift_z: float):
    """The eye's image in the mirror (world m): it lights the reflected view's speculars and fog."""
    shift = np.array([0.0, 0.0, shift_z])
    pos = reflection[:3, :3] @ (np.asarray(camera.position, dtype=np.float64) - shift) + reflection[:3, 3] + shift
    fwd = reflection[:3, :3] @ np.asarray(camera.forward, dtype=np.float64)
    return dataclasses.replace(camera, position=pos, forward=fwd, inside_car=False)
