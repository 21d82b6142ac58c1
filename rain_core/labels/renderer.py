"""The label passes (GL): after ``Scene.render()``, redraw the frame's opaque meshes with a class per vertex into a
float target (ray length, class, road-water region), then let the active effects draw their opacity into a
second texture (rain, spray, glass water), and read both back once.

Nothing here runs unless labels are asked for: the renderer's own passes are untouched, and a frame without
``render_label_images`` costs nothing.

Effects that contribute a mask implement ``render_label(name, rc, target)`` (RainfallEffect "rain", SprayEffect
"spray", WindshieldEffect "glass_water"): they draw their opacity as the fragment alpha into ``target.fbo``
(the mask colour with this pass's depth attached, for depth tests; never written) or, to sample that depth
(``target.depth``), through ``target.color_fbo`` (the colour alone). The caller sets the blending and the
colour mask: every mask channel holds the transmittance T = Π(1 − αᵢ) of what was drawn, so overlapping streaks
and parcels composite as they do on screen; the mask is 1 − T.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import moderngl
import numpy as np

from rain_core import layout
from rain_core.gfx.uniforms import mat4_bytes, set_uniform
from rain_core.gutter import frame_spread_coefficient
from rain_core.labels.classes import CLASS_IDS, cabin_classes, world_classes
from rain_core.labels.images import BLENDED_MASKS, CLEAR_GEOMETRY, LabelImages, check_mask_names, decode


@dataclass
class LabelTarget:
    """Where an effect draws a blended mask: ``fbo`` (mask colour + the label depth, depth-tested, read-only),
    ``color_fbo`` (the mask colour alone, for passes that sample ``depth``), ``color``, ``depth`` (textures)."""

    fbo: moderngl.Framebuffer
    color_fbo: moderngl.Framebuffer
    color: moderngl.Texture
    depth: moderngl.Texture

    @property
    def size(self) -> tuple[int, int]:
        return self.color.size


@dataclass
class _Mesh:
    vbo: moderngl.Buffer
    vao: moderngl.VertexArray
    count: int

    def release(self) -> None:
        self.vao.release()
        self.vbo.release()


class LabelRenderer:
    """Owns the label program, the class-tagged copies of the meshes and the label targets of one renderer.
    ``render(renderer, frame, masks=None)`` → LabelImages (call right after ``renderer.render(frame)``);
    ``release()`` frees its GL objects."""

    def __init__(self, ctx: moderngl.Context, shaders):
        self.ctx = ctx
        defines = {"CLASS_ROAD": CLASS_IDS["road"], "CLASS_MARKING": CLASS_IDS["marking"]}
        self.prog = shaders.program("labels/geometry.vert", "labels/geometry.frag", defines=defines)
        self._world: tuple[object, _Mesh] | None = None
        self._vehicles: dict[int, tuple[object, _Mesh]] = {}  # id(vehicle) → (vehicle, mesh): holds the vehicle
        self._cabin: tuple[object, _Mesh] | None = None
        self._size: tuple[int, int] | None = None
        self._geometry = self._depth = self._geometry_fbo = None
        self._target: LabelTarget | None = None

    # --- meshes -------------------------------------------------------------------------------------------
    def _mesh(self, positions: np.ndarray, classes: np.ndarray) -> _Mesh:
        data = np.empty((len(positions), 4), np.float32)
        data[:, :3] = positions
        data[:, 3] = classes
        vbo = self.ctx.buffer(data.tobytes())
        vao = self.ctx.vertex_array(self.prog, [(vbo, "3f 1f", "in_position", "in_class")])
        return _Mesh(vbo, vao, len(data))

    def _world_mesh(self, world) -> _Mesh:
        if self._world is None or self._world[0] is not world:
            if self._world is not None:
                self._world[1].release()
            self._world = (world, self._mesh(world.vertices["position"], world_classes(world)))
        return self._world[1]

    def _vehicle_mesh(self, vehicle) -> _Mesh:
        entry = self._vehicles.get(id(vehicle))
        if entry is None:
            from rain_core.car_mesh import vehicle_mesh

            vertices = vehicle_mesh(vehicle.spec)  # the class is set per draw (vehicle or ego vehicle)
            entry = self._vehicles[id(vehicle)] = (vehicle, self._mesh(vertices["position"],
                                                                       np.zeros(len(vertices))))
        return entry[1]

    def _cabin_mesh(self, ego) -> _Mesh:
        if self._cabin is None or self._cabin[0] is not ego.spec:
            from rain_core.car_mesh import cabin_mesh

            if self._cabin is not None:
                self._cabin[1].release()
            vertices = cabin_mesh(ego.spec)
            self._cabin = (ego.spec, self._mesh(vertices["position"], cabin_classes(vertices)))
        return self._cabin[1]

    def _forget_vehicles(self, vehicles) -> None:
        present = {id(v) for v in vehicles}
        for key in [k for k in self._vehicles if k not in present]:
            self._vehicles.pop(key)[1].release()

    def draw_list(self, rc, frame):
        """(mesh, model matrix in the wrapped frame, class or −1 for the per-vertex classes): what the scene pass
        draws (rain_core.gfx.scene_draw.SceneDrawer.draw_list), the same tiles, vehicles and cabin."""
        cam_z = float(rc.camera_position[2])
        period = layout.PERIOD_M
        for k in (-1, 0, 1):
            if abs(cam_z - (k * period + period / 2)) > period * 1.5:
                continue
            model = np.eye(4)
            model[2, 3] = k * period
            yield self._world_mesh(frame.world), model, -1.0
        inside = frame.camera.inside_car
        for vehicle in frame.vehicles:
            if inside and vehicle is frame.ego:
                continue
            model = vehicle.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            cls = CLASS_IDS["ego_vehicle"] if vehicle is frame.ego else CLASS_IDS["vehicle"]
            yield self._vehicle_mesh(vehicle), model, float(cls)
        if inside and frame.ego is not None:
            model = frame.ego.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            yield self._cabin_mesh(frame.ego), model, -1.0

    # --- targets ------------------------------------------------------------------------------------------
    def _ensure_targets(self, size: tuple[int, int]) -> None:
        if self._size == size:
            return
        self._release_targets()
        ctx = self.ctx
        self._geometry = ctx.texture(size, 4, dtype="f4")
        self._depth = ctx.depth_texture(size)
        self._geometry_fbo = ctx.framebuffer(color_attachments=[self._geometry], depth_attachment=self._depth)
        blended = ctx.texture(size, 4, dtype="f4")  # f4: a thousand faint streaks must not round to nothing
        self._target = LabelTarget(ctx.framebuffer(color_attachments=[blended], depth_attachment=self._depth),
                                   ctx.framebuffer(color_attachments=[blended]), blended, self._depth)
        self._size = size

    def _release_targets(self) -> None:
        if self._size is None:
            return
        self.ctx.detect_framebuffer(0).use()  # never leave a released framebuffer bound
        t = self._target
        for obj in (t.fbo, t.color_fbo, t.color, self._geometry_fbo, self._geometry, self._depth):
            obj.release()
        self._geometry = self._depth = self._geometry_fbo = self._target = None
        self._size = None

    # --- passes -------------------------------------------------------------------------------------------
    def render_context(self, renderer, frame):
        """The renderer's context for ``frame`` (camera matrices in the wrapped frame) with this frame's active
        effects (their ``active`` is a pure predicate)."""
        rc = renderer.render_context(frame)
        rc.active = tuple(e for e in renderer.effects if e.active(frame))
        return rc

    def _bind_road(self, rc) -> None:
        road = next((e for e in rc.active if e.name == "road" and hasattr(e, "bind_film_uniforms")), None)
        if road is None or getattr(road, "world", None) is None:
            set_uniform(self.prog, "u_label_road", 0.0)
            return
        from rain_core.settings import RoadSection

        settings = rc.frame.settings.road if rc.frame.settings is not None else RoadSection()
        wetness, cracks, puddles = road.levels(rc.frame)
        road.bind_film_uniforms(self.prog, wetness, cracks, puddles, settings.puddle_amount, settings.puddle_seed,
                                frame_spread_coefficient(rc.frame))
        set_uniform(self.prog, "u_label_road", 1.0)

    def _draw_geometry(self, rc) -> None:
        ctx = self.ctx
        self._geometry_fbo.use()
        self._geometry_fbo.clear(*CLEAR_GEOMETRY, depth=1.0)
        ctx.disable(moderngl.BLEND)
        ctx.disable(moderngl.CULL_FACE)  # as the scene pass: meshes are not all consistently wound
        ctx.enable(moderngl.DEPTH_TEST)
        prog = self.prog
        rc.set_frame_uniforms(prog)
        self._bind_road(rc)
        model_u, class_u = prog["u_model"], prog["u_class"]
        for mesh, model, cls in self.draw_list(rc, rc.frame):
            model_u.write(mat4_bytes(model))
            class_u.value = cls
            mesh.vao.render(moderngl.TRIANGLES, vertices=mesh.count)

    def _draw_blended(self, rc, names) -> None:
        ctx = self.ctx
        target = self._target
        target.color_fbo.use()
        target.color_fbo.clear(1.0, 1.0, 1.0, 1.0)  # transmittance 1: nothing in front
        ctx.enable(moderngl.BLEND)
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.blend_func = (moderngl.ZERO, moderngl.ONE_MINUS_SRC_ALPHA)  # T ← T·(1 − α) in every written channel
        try:
            for name in names:
                mask = tuple(i == BLENDED_MASKS.index(name) for i in range(4))
                target.fbo.color_mask = target.color_fbo.color_mask = mask
                for effect in rc.active:
                    draw = getattr(effect, "render_label", None)
                    if draw is not None:
                        draw(name, rc, target)
        finally:
            target.fbo.color_mask = target.color_fbo.color_mask = (True, True, True, True)
            target.color_fbo.use()  # applies the full colour mask again
            ctx.disable(moderngl.BLEND)
            ctx.blend_func = moderngl.DEFAULT_BLENDING
            ctx.enable(moderngl.DEPTH_TEST)

    def render(self, renderer, frame, masks=None) -> LabelImages:
        """Label images of ``frame`` as ``renderer`` drew it last (call right after ``renderer.render(frame)``).
        ``masks``: names from MASK_NAMES (None: all); the depth always comes. Blended masks run only the passes
        asked for, and only for active effects."""
        names = check_mask_names(masks)
        size = tuple(renderer.size)
        self._ensure_targets(size)
        self._forget_vehicles(frame.vehicles)
        rc = self.render_context(renderer, frame)
        self._draw_geometry(rc)
        blended_names = [n for n in BLENDED_MASKS if n in names]
        if blended_names:
            self._draw_blended(rc, blended_names)
        w, h = size
        geometry = np.frombuffer(self._geometry_fbo.read(components=4, dtype="f4", alignment=1),
                                 np.float32).reshape(h, w, 4)
        blended = None
        if blended_names:
            blended = np.frombuffer(self._target.color_fbo.read(components=4, dtype="f4", alignment=1),
                                    np.float32).reshape(h, w, 4)
        self.ctx.detect_framebuffer(0).use()
        return decode(geometry, blended, names)

    def release(self) -> None:
        self._release_targets()
        for _, mesh in [*self._vehicles.values(), *(e for e in (self._world, self._cabin) if e is not None)]:
            mesh.release()
        self._vehicles.clear()
        self._world = self._cabin = None


# One LabelRenderer per Renderer, made at the first label request (labels unused: nothing made).
_LABELLERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def label_renderer(scene) -> LabelRenderer:
    """The LabelRenderer of ``scene``'s renderer (made on first use, with the renderer's shader library)."""
    renderer = scene.renderer
    labeller = _LABELLERS.get(renderer)
    if labeller is None:
        labeller = _LABELLERS[renderer] = LabelRenderer(renderer.ctx, renderer.shaders)
    return labeller


def render_label_images(scene, frame, masks=None) -> LabelImages:
    """Ground truth for ``frame`` as ``scene`` (a rain_core.scene.Scene) just rendered it: call after
    ``frame = scene.render()``. ``masks``: which of MASK_NAMES to make (None: all; unknown → ValueError).
    See LabelImages for units and ids."""
    if frame is None:
        raise ValueError("frame: the Frame that scene.render() returned is required, got None")
    return label_renderer(scene).render(scene.renderer, frame, masks)


def release_labels(scene) -> None:
    """Free the label passes' GL objects of ``scene`` (before ``scene.release()``; no-op if labels never ran)."""
    labeller = _LABELLERS.pop(scene.renderer, None)
    if labeller is not None:
        labeller.release()
