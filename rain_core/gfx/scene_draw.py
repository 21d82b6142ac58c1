"""Drawing the opaque scene: sky, world tiles (periodic along Z), vehicles and, inside the car, the cabin.

The renderer draws it for the main view and, through ``Renderer.draw_mirror_view``, for auxiliary views such
as the road's planar reflection.
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from rain_core import layout
from rain_core.gfx import units
from rain_core.gfx.frame import RenderContext
from rain_core.gfx.light_grid import LightGrid
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import mat4_bytes, owned_uniforms, rows_bytes
from rain_core.mesh import VERTEX_ATTRIBUTES, VERTEX_FORMAT

# Share of direct sun/lamp light that reaches the cabin interior (the roof and pillars shade most of it).
CABIN_DIRECT_LIGHT = 0.2

GL_CLIP_DISTANCE0 = 0x3000  # not in moderngl's enable flags: toggled with ctx.enable_direct


def _tile_model(k: int) -> np.ndarray:
    m = np.eye(4)
    m[2, 3] = k * layout.PERIOD_M
    m.flags.writeable = False  # shared by every frame
    return m


_TILE_MODELS = tuple(_tile_model(k) for k in (-1, 0, 1))  # the world tile one period behind, here, ahead
_TILE_BYTES = {k: mat4_bytes(m) for k, m in zip((-1, 0, 1), _TILE_MODELS, strict=True)}
_TILE_SHIFTS = tuple(k * layout.PERIOD_M for k in (-1, 0, 1))  # m along z, the tiles' boxes


def frustum_planes(view_proj) -> list[tuple[float, float, float, float, float]]:
    """The six clip planes of ``view_proj`` (Gribb–Hartmann: clip-space −w ≤ x, y, z ≤ w) as (a, b, c, d, margin):
    a·x + b·y + c·z + d ≥ 0 inside, world m; margin is the rounding allowance the box test keeps. In floats: a
    handful per view, cheaper than NumPy's call overhead."""
    rows = view_proj.tolist()
    w = rows[3]
    planes = []
    for row in rows[:3]:
        for sign in (1.0, -1.0):
            plane = [w[j] + sign * row[j] for j in range(4)]
            planes.append((*plane, 1e-6 * (abs(plane[0]) + abs(plane[1]) + abs(plane[2]) + abs(plane[3]))))
    return planes


def box_outside(planes, lo, hi) -> bool:
    """Whether the axis-aligned box [lo, hi] (world m) lies wholly outside one of ``planes`` (``frustum_planes``).
    Conservative: a box that touches or straddles a plane is kept, so a skipped draw is one that had no
    fragments."""
    return boxes_outside(planes, lo, hi, (0.0,))[0]


def boxes_outside(planes, lo, hi, z_shifts) -> list[bool]:
    """``box_outside`` of the box [lo, hi] moved by each of ``z_shifts`` (m) along z, in one pass over the planes
    (the boxes share their x and y terms): the world tile's copies one period behind and ahead."""
    lows = [lo[2] + s for s in z_shifts]
    highs = [hi[2] + s for s in z_shifts]
    outside = [False] * len(z_shifts)
    for a, b, c, d, margin in planes:
        # the box's corner farthest along the plane's normal: if even it is outside, the whole box is
        xy = (a * (hi[0] if a >= 0.0 else lo[0])) + (b * (hi[1] if b >= 0.0 else lo[1]))
        for i, z in enumerate(highs if c >= 0.0 else lows):
            if xy + c * z + d < -margin:
                outside[i] = True
    return outside


def box_outside_frustum(view_proj, lo, hi) -> bool:
    """``box_outside`` against the clip planes of ``view_proj`` (a 4×4 matrix, world → clip)."""
    return box_outside(frustum_planes(view_proj), lo, hi)


@dataclass
class GpuMesh:
    """A VERTEX_DTYPE mesh on the GPU with a VAO for each program that draws it: the lit scene shader, the shadow
    depth pass, the mirror views' scene shader and the depth pre-passes (positions only)."""

    vao: moderngl.VertexArray
    depth_vao: moderngl.VertexArray
    count: int
    vbo: moderngl.Buffer
    mirror_vao: moderngl.VertexArray  # for SceneDrawer's mirror-view program
    prepass_vaos: dict  # depth pre-pass program's glo → its VAO

    def release(self) -> None:
        for obj in (self.vao, self.depth_vao, self.vbo, self.mirror_vao, *self.prepass_vaos.values()):
            obj.release()


class SceneDrawer:
    """Owns the scene and sky programs and the meshes of the world, the vehicles and the cabin."""

    def __init__(self, ctx: moderngl.Context, shaders: ShaderLibrary, world, shadow_program: moderngl.Program):
        self.ctx = ctx
        self.scene_prog = shaders.program("core/scene.vert", "core/scene.frag")
        # The same shader compiled once more (the define is unused: the same code) for the mirror views (the road's
        # reflection, the door mirrors): each program then keeps its view's values (clip plane, the road's mirror
        # flags, no ripples, no cabin) from frame to frame, and OwnedUniforms skips them instead of the main
        # and the mirror view rewriting them in turn.
        self.mirror_prog = shaders.program("core/scene.vert", "core/scene.frag", defines={"SCENE_MIRROR_VIEW": 1})
        self.sky_prog = shaders.program("common/fullscreen.vert", "core/sky.frag")
        # Which lights reach each tile of a view, built after its pre-pass when its context asks (light_grid_px).
        self.light_grid = LightGrid(ctx, shaders)
        self.light_grid.read_by(self.scene_prog, self.mirror_prog)
        # Depth pre-pass: the scene's depths first, so the lit shader runs once per visible pixel instead of once
        # per layer of the city, the cabin and the cars in front of each other (2–4 layers from the driver's seat).
        self._prepass_progs = {False: shaders.program("core/scene.vert", "core/scene_depth.frag"),
                               True: shaders.program("core/scene.vert", "core/scene_depth.frag",
                                                     defines={"SCENE_MIRROR_VIEW": 1})}
        self._shadow_prog = shadow_program
        self._sky_vao = ctx.vertex_array(self.sky_prog, [])
        self._world = self._mesh(world.vertices)
        positions = world.vertices["position"]
        # the tile's box in its own frame (tile k is this box moved k periods along z), for culling
        self._world_box = (positions.min(axis=0).tolist(), positions.max(axis=0).tolist())
        # id(vehicle) → (vehicle, mesh): holding the vehicle keeps its id from being reused by a new one.
        self._vehicles: dict[int, tuple[object, GpuMesh]] = {}
        self._cabin: list[tuple[GpuMesh, float]] | None = None
        self._mirror_glass: GpuMesh | None = None  # the cabin's door mirror glass (one of self._cabin's meshes)
        self._items: dict | None = None  # the frame's draw items while the renderer draws a frame
        self._models: dict | None = None  # and its vehicles' model bytes
        self._asked: dict | None = None  # and the items each (context, cabin, cull) was given

    # --- geometry -------------------------------------------------------------------------------------------
    def _mesh(self, vertices: np.ndarray) -> GpuMesh:
        """The mesh with all its VAOs made now: a mesh is made in the frame's plan, before its first draw, and a VAO
        made once draws are queued waits for llvmpipe's driver thread (4-25 ms each, ~0.16 s of the first frame
        when the mirror and pre-pass VAOs were made at their first draw; ~10 µs each here)."""
        ctx = self.ctx
        vbo = ctx.buffer(np.ascontiguousarray(vertices).tobytes())
        lit = [(vbo, VERTEX_FORMAT, *VERTEX_ATTRIBUTES)]
        positions = [(vbo, "3f 36x", "in_position")]
        return GpuMesh(ctx.vertex_array(self.scene_prog, lit), ctx.vertex_array(self._shadow_prog, positions),
                       len(vertices), vbo, ctx.vertex_array(self.mirror_prog, lit),
                       {prog.glo: ctx.vertex_array(prog, positions) for prog in self._prepass_progs.values()})

    def _depth_prepass(self, rc: RenderContext, items, prog: moderngl.Program, plane) -> None:
        """Depths of the large occluders, the world tiles and the cabin (from the driver's seat the hood and the
        dashboard hide much of the road). The cars are left out: each hides little, and a draw of its own costs
        more CPU than its hidden pixels cost the GPU; they are still lit only where in front."""
        self.ctx.enable(moderngl.DEPTH_TEST)
        rc.set_frame_uniforms(prog)
        owned_uniforms(prog).set("u_clip_plane", plane)
        model_u = prog["u_model"]
        cabin = self._cabin or ()
        for mesh, model, _share in items:
            if mesh is self._world or any(mesh is part for part, _ in cabin):
                model_u.write(model)
                mesh.prepass_vaos[prog.glo].render(moderngl.TRIANGLES, vertices=mesh.count)

    def _vehicle_mesh(self, vehicle) -> GpuMesh:
        key = id(vehicle)
        if key not in self._vehicles:
            from rain_core.car_mesh import vehicle_mesh

            color = getattr(vehicle, "color", (0.5, 0.05, 0.04))
            self._vehicles[key] = (vehicle, self._mesh(vehicle_mesh(vehicle.spec, np.asarray(color, np.float32))))
        return self._vehicles[key][1]

    def forget_vehicles(self, vehicles) -> None:
        """Release the meshes of vehicles that left the scene (e.g. the traffic count changed)."""
        present = {id(v) for v in vehicles}
        for key in [k for k in self._vehicles if k not in present]:
            self._vehicles.pop(key)[1].release()

    def _cabin_meshes(self, ego):
        """The cabin as (mesh, direct-light share): painted outside parts (hood, mirror housings) get full direct
        light, the interior the share its roof lets in; the mirror glass is a mesh of its own (it shows the
        mirror view when one was drawn)."""
        if self._cabin is None:
            from rain_core.car_mesh import cabin_mesh, mirror_glass_mask
            from rain_core.mesh import MAT_CAR_PAINT

            vertices = cabin_mesh(ego.spec)
            outside = np.round(vertices["params"][:, 2]) == MAT_CAR_PAINT
            glass = mirror_glass_mask(vertices)
            parts = ((vertices[outside], 1.0), (vertices[~outside & ~glass], CABIN_DIRECT_LIGHT),
                     (vertices[glass], CABIN_DIRECT_LIGHT))
            self._cabin = [(self._mesh(part), share) for part, share in parts if len(part)]
            self._mirror_glass = self._cabin[-1][0] if glass.any() else None
        return self._cabin

    def draw_list(self, rc: RenderContext, include_cabin: bool):
        """(mesh, model matrix in the wrapped frame, direct-light share) of everything opaque in the frame."""
        frame = rc.frame
        cam_z = rc.camera_position[2]
        for k, model in zip((-1, 0, 1), _TILE_MODELS, strict=True):
            if abs(cam_z - (k * layout.PERIOD_M + layout.PERIOD_M / 2)) > layout.PERIOD_M * 1.5:
                continue
            yield self._world, model, 1.0
        inside = frame.camera.inside_car
        for vehicle in frame.vehicles:
            if inside and include_cabin and vehicle is frame.ego:
                continue
            model = vehicle.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            yield self._vehicle_mesh(vehicle), model, 1.0
        if inside and include_cabin and frame.ego is not None:
            model = frame.ego.model_matrix().copy()
            model[2, 3] -= rc.shift_z
            for mesh, share in self._cabin_meshes(frame.ego):
                yield mesh, model, share

    def begin_frame(self) -> None:
        """From now until ``end_frame`` the frame's draw items are kept: the shadow pass, the scene and the road's
        mirror view draw the same vehicles, so each model matrix is built and packed once per frame."""
        self._items = {}
        self._models = {}
        self._asked = {}

    def end_frame(self) -> None:
        self._items = None
        self._models = None
        self._asked = None

    @property
    def in_frame(self) -> bool:
        """Between ``begin_frame`` and ``end_frame``."""
        return self._items is not None

    def _model_bytes(self, vehicle, shift_z: float) -> bytes:
        """The vehicle's model matrix in the wrapped frame as ``u_model`` bytes (kept for the frame)."""
        models = self._models
        if models is not None:
            hit = models.get(id(vehicle))
            if hit is not None and hit[0] is vehicle and hit[1] == shift_z:
                return hit[2]
        rows = vehicle.model_matrix().tolist()
        rows[2][3] -= shift_z  # the float64 subtraction of model[2, 3] -= shift_z, without copying the array
        data = rows_bytes(rows)
        if models is not None:
            models[id(vehicle)] = (vehicle, shift_z, data)
        return data

    def _tiles_in_view(self, view_proj) -> tuple[bool, bool, bool]:
        """Whether each world tile (one period behind, here, ahead) may touch the view of ``view_proj``."""
        lo, hi = self._world_box
        return tuple(not out for out in boxes_outside(frustum_planes(view_proj), lo, hi, _TILE_SHIFTS))

    def draw_items(self, rc: RenderContext, include_cabin: bool, cull=False) -> list:
        """``draw_list`` with each model matrix as the bytes ``u_model`` takes; between ``begin_frame`` and
        ``end_frame`` computed once per (vehicles, camera tile, cabin or not). ``cull``: leave out the world tiles
        wholly outside a view: True for ``rc``'s own, or a view-projection (4×4, wrapped frame) such as the sun's
        (the shadow's casters may lie outside the camera's view, not outside the light's)."""
        asked = self._asked
        ask = (id(rc), include_cabin, cull if type(cull) is bool else id(cull))
        if asked is not None:  # the same view asked again in this frame (planned before the passes, drawn in them)
            hit = asked.get(ask)
            if hit is not None and hit[0] is rc and (type(cull) is bool or hit[1] is cull):
                return hit[2]
        frame = rc.frame
        cabin = bool(include_cabin and frame.camera.inside_car)
        cam_z = float(rc.camera_position[2])
        tiles = tuple(abs(cam_z - (k * layout.PERIOD_M + layout.PERIOD_M / 2)) <= layout.PERIOD_M * 1.5
                      for k in (-1, 0, 1))
        if cull is not False:
            view_proj = rc.view_proj if cull is True else cull
            tiles = tuple(near and seen for near, seen in zip(tiles, self._tiles_in_view(view_proj), strict=True))
        key = (cabin, rc.shift_z, tiles)
        cache = self._items
        if cache is not None:
            hit = cache.get(key)
            # the cached entry holds the vehicle list and ego it was built from: compared by identity
            if hit is not None and hit[0] is frame.vehicles and hit[1] is frame.ego:
                if asked is not None:
                    asked[ask] = (rc, cull, hit[2])  # holding rc and the matrix keeps their ids from being reused
                return hit[2]
        items = [(self._world, _TILE_BYTES[k], 1.0) for k, on in zip((-1, 0, 1), tiles, strict=True) if on]
        for vehicle in frame.vehicles:
            if cabin and vehicle is frame.ego:
                continue
            items.append((self._vehicle_mesh(vehicle), self._model_bytes(vehicle, rc.shift_z), 1.0))
        if cabin and frame.ego is not None:
            model = self._model_bytes(frame.ego, rc.shift_z)
            items += [(mesh, model, share) for mesh, share in self._cabin_meshes(frame.ego)]
        if cache is not None:
            cache[key] = (frame.vehicles, frame.ego, items)
            asked[ask] = (rc, cull, items)
        return items

    # --- drawing --------------------------------------------------------------------------------------------
    def draw(self, rc: RenderContext, effects, include_sky: bool = True,
             clip_plane: tuple[float, float, float, float] | None = None,
             mirror_view: moderngl.Texture | None = None) -> None:
        """Sky, world tiles, vehicles and (inside the car) the cabin, into the bound framebuffer. ``effects``: all
        of the renderer's; the active ones (``rc.active``) bind their scene inputs, the rest their neutral ones.
        ``mirror_view``: the door mirrors' view of this frame (rain_core.gfx.mirrors), shown on their glass.
        With ``rc.light_grid_px`` the view's light grid is built after the depth pre-pass, from ``rc.hdr``'s depth
        (the target being drawn)."""
        ctx = self.ctx
        ctx.disable(moderngl.BLEND)
        if include_sky:
            ctx.disable(moderngl.DEPTH_TEST)
            rc.set_frame_uniforms(self.sky_prog)
            self.sky_prog["u_inv_view_proj"].write(mat4_bytes(rc.inv_view_proj))
            self._sky_vao.render(moderngl.TRIANGLES, vertices=3)
        ctx.enable(moderngl.DEPTH_TEST)
        mirrored = clip_plane is not None
        # builds the cabin meshes, the mirror glass among them; a world tile out of this view has no fragments
        items = self.draw_items(rc, include_cabin=True, cull=True)
        plane = (0.0, 0.0, 0.0, 1.0) if clip_plane is None else tuple(map(float, clip_plane))
        if clip_plane is not None:  # after the sky, whose vertex shader writes no clip distance
            ctx.enable_direct(GL_CLIP_DISTANCE0)
        # The pre-pass leaves an undefined colour where its meshes are; the lit pass overwrites every such pixel
        # (the same meshes at the same depths pass "<=").
        self._depth_prepass(rc, items, self._prepass_progs[mirrored], plane)
        if rc.light_grid_px:
            if clip_plane is not None:  # the grid's full-screen triangle writes no clip distance
                ctx.disable_direct(GL_CLIP_DISTANCE0)
            self.light_grid.build(rc, rc.hdr.depth)
            if clip_plane is not None:
                ctx.enable_direct(GL_CLIP_DISTANCE0)
            rc.hdr.fbo.use()
        ctx.depth_func = "<="  # the pre-pass's own depths pass: each pixel is lit once, by what is in front
        prog = self.mirror_prog if mirrored else self.scene_prog
        rc.set_frame_uniforms(prog)
        # Clip plane (reflection passes): keep dot((x, y, z, 1), plane) >= 0, wrapped-frame world positions.
        # The scene drawer alone writes u_clip_plane and u_direct_scale in this program: owned_uniforms skips
        # unchanged values (the main and the mirror view alternate the plane; only the cabin changes the scale).
        owned = owned_uniforms(prog)
        owned.set("u_clip_plane", plane)
        for effect in effects:
            if effect in rc.active:
                effect.bind_scene(prog, rc)
            else:
                effect.unbind_scene(prog, rc)
        live_glass = self._mirror_glass if mirror_view is not None else None
        if live_glass is not None:
            mirror_view.use(units.DOOR_MIRROR)
            prog["u_mirror_view"].value = units.DOOR_MIRROR
            prog["u_mirror_uv_scale"].value = (1.0 / rc.size[0], 1.0 / rc.size[1])
        model_u, set_owned = prog["u_model"], owned.set
        last_share = last_live = None  # what the previous item set: OwnedUniforms is asked only on a change
        for mesh, model, share in items:
            model_u.write(model)
            if share != last_share:
                set_owned("u_direct_scale", share)
                last_share = share
            live = mesh is live_glass
            if live is not last_live:
                set_owned("u_mirror_live", live)
                last_live = live
            (mesh.mirror_vao if mirrored else mesh.vao).render(moderngl.TRIANGLES, vertices=mesh.count)
        ctx.depth_func = "<"
        if clip_plane is not None:
            ctx.disable_direct(GL_CLIP_DISTANCE0)

    def release(self) -> None:
        for mesh in [self._world, *(m for _, m in self._vehicles.values()), *(m for m, _ in (self._cabin or []))]:
            mesh.release()
        self._vehicles.clear()
        self._cabin = None
        self._sky_vao.release()
        self.light_grid.release()
