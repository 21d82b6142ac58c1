"""Drips' GL side: the drip sites of the world (``edges``) in two float textures, the roofs' outflow per site in
a third (a few hundred bytes a frame), one instanced draw per range of sites near the camera (stateless: the
vertex shader places every drop from the time, ``shaders/drips/drip.vert``), and the drops landing in standing
water handed to the ripples (``rc.shared.droplet_impacts``, after the spray's).

Cost: the roofs' water is followed in ``observe`` (a few NumPy operations) from the first rain on; on a dry day
nothing at all happens, and the effect is idle (no draw) once every roof has drained.
"""

from __future__ import annotations

import bisect
import math

import moderngl
import numpy as np

from rain_core import jit, layout, physics
from rain_core.effects.drips import kernels
from rain_core.effects.drips.edges import DripSites, find_drip_sites
from rain_core.effects.drips.flow import (
    MAX_PERIOD_S,
    RoofReservoirs,
    drop_diameters_mm,
    landing_counts,
    landing_terms,
)
from rain_core.gfx import units
from rain_core.gfx.effect import Effect
from rain_core.gfx.frame import Frame, RenderContext
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.uniforms import owned_uniforms
from rain_core.settings import DripsSection

SLOTS = 12  # drops drawn per site: the hanging one and the last 11 released
# (id(world), seed) → (world, its sites): found once per world and seed. The seed is part of the key: scenes
# share their world, and a scene's sites must not depend on which seed an earlier scene of the process used.
_SITES: dict[tuple[int, int], tuple[object, DripSites]] = {}
MIN_OUTFLOW_M3_S = 1e-9  # total: below this every roof has drained


def drip_sites_of(world, seed: int = 0) -> DripSites:
    """The world's drip sites for ``seed``, found once per world object and seed (~0.06 s on the default world's
    occluder map)."""
    key = (id(world), int(seed))
    entry = _SITES.get(key)
    if entry is None or entry[0] is not world:
        m = world.occluder_map
        if len(_SITES) > 4:
            _SITES.clear()
        entry = _SITES[key] = (world, find_drip_sites(m.grid, m.x0_m, m.cell_m, seed))
    return entry[1]


class DripsEffect(Effect):
    """Water dripping from the edges of low roofs: during the rain and, while the roofs drain, after it.

    ``DripsEffect(ctx, settings=None, *, seed=0, shaders=None)``: settings from ``frame.settings.drips``.
    """

    name = "drips"
    stages = ("transparent",)

    def __init__(self, ctx: moderngl.Context, settings=None, *, seed: int = 0, shaders: ShaderLibrary | None = None):
        self.ctx = ctx
        self.settings = settings
        self.seed = int(seed)
        self._shaders = shaders
        self.sites: DripSites | None = None
        self.roofs: RoofReservoirs | None = None
        self._world = None
        self._diam: np.ndarray | None = None
        self._drop_m3 = self._t_fall = self._momentum = self._ground = None  # per site, made with the sites
        self._flux_key: tuple | None = None  # (storage, drain, kernel args, texture) the flux was made for
        self._kernel_args = None  # the kernels' contiguous per-site and per-roof arrays and outputs, made with them
        self._tex: dict[str, moderngl.Texture] = {}
        self._prog: moderngl.Program | None = None
        self._vao: moderngl.VertexArray | None = None
        self._ranges: list[tuple[int, int, float]] = []
        self._sites_z: tuple | None = None  # (sites, their z as a list) for _visible_ranges
        self.landed = 0  # drops that reached standing-water-capable ground in the last update
        self._seen_s = 0.0  # time of the last frame observed (s)

    def _section(self, frame) -> DripsSection:
        settings = getattr(frame, "settings", None) or self.settings
        return getattr(settings, "drips", None) or DripsSection()

    # --- per frame ------------------------------------------------------------------------------------------
    def observe(self, frame: Frame) -> None:
        rate = frame.rain_rate_mm_h * self._section(frame).strength
        if self.roofs is None or self._world is not frame.world:
            if rate <= 0.0 or getattr(frame.world, "occluder_map", None) is None:
                return  # never rained here: no roof holds water, nothing to find
            self._world = frame.world
            self.sites = drip_sites_of(frame.world, self.seed)
            self._diam = drop_diameters_mm(self.sites.phase)
            # What the landings need per site besides the clock and the roof's flux: fixed with the sites.
            self._drop_m3 = math.pi / 6.0 * (self._diam * 1e-3) ** 3
            self._t_fall, self._momentum = landing_terms(self.sites.edge_y - self.sites.land_y, self._diam)
            self._ground = self.sites.land_y < 0.5
            self.roofs = RoofReservoirs(self.sites.area_m2, self.sites.drain_s)
            self.roofs.settle(rate)  # a scene that starts in rain starts dripping
            self._kernel_args = None
            self._release_textures()
            self._seen_s = frame.time_s
            return
        # All the time since the last frame seen (steps that drew no frame included), at today's rate.
        self.roofs.step(max(frame.time_s - self._seen_s, 0.0), rate)
        self._seen_s = frame.time_s

    def active(self, frame) -> bool:
        return (self._section(frame).enabled and self.roofs is not None and len(self.sites) > 0
                and self.roofs.total_outflow_m3_s() > MIN_OUTFLOW_M3_S)

    def describe(self) -> str:
        if self.roofs is None:
            return "dry roofs"
        return f"{len(self.sites)} drip sites, roofs shed {self.roofs.outflow_m3_s.sum() * 6e4:.2f} L/min"

    def _visible_ranges(self, camera_z: float, reach_m: float) -> list[tuple[int, int, float]]:
        """(first, count, world z offset of the tile) of the sites within reach_m (m) of camera_z along z."""
        sites_z = self._sites_z
        if sites_z is None or sites_z[0] is not self.sites:
            sites_z = self._sites_z = (self.sites, self.sites.z.tolist())
        z = sites_z[1]  # sorted: bisect gives np.searchsorted's indices without its array conversions
        period = layout.PERIOD_M
        base = math.floor(camera_z / period) * period
        offsets = (-period, 0.0, period)
        bounds = []
        for offset in offsets:
            bounds += (camera_z - reach_m - base - offset, camera_z + reach_m - base - offset)
        ends = [bisect.bisect_left(z, b) for b in bounds]
        out = []
        for k, offset in enumerate(offsets):
            a, b = ends[2 * k], ends[2 * k + 1]
            if b > a:
                out.append((a, b - a, base + offset))
        return out

    def update(self, frame: Frame, rc: RenderContext) -> None:
        sec = self._section(frame)
        self._ranges = self._visible_ranges(float(frame.camera.position[2]), sec.reach_m)
        if jit.active():
            self._update_compiled(frame, rc)
            return
        flux = self.roofs.outflow_m3_s / np.maximum(self.sites.edges, 1)
        self._upload(flux)
        # Drops landing now on the ground: the ripples ring where it stands in water.
        impacts = []
        s = self.sites
        for first, count, z_base in self._ranges:
            sl = slice(first, first + count)
            ground = self._ground[sl]
            if not ground.any():
                continue
            period = np.minimum(self._drop_m3[sl] / np.maximum(flux[s.roof[sl]], 1e-300), MAX_PERIOD_S)
            n = landing_counts(frame.time_s - frame.dt_s, frame.time_s, period, s.phase[sl], self._t_fall[sl])
            momentum = self._momentum[sl]
            hit = ground & (n > 0)
            if hit.any():
                impacts.append(np.stack([s.x[sl][hit], s.z[sl][hit] + z_base, momentum[hit] * n[hit]], axis=1))
        self.landed = int(sum(len(i) for i in impacts))
        if impacts:
            mine = np.concatenate(impacts)
            prev = rc.shared.droplet_impacts
            rc.shared.droplet_impacts = mine if prev is None or len(prev) == 0 else np.concatenate([prev, mine])

    def _update_compiled(self, frame: Frame, rc: RenderContext) -> None:
        """``update``'s flux, upload and landings by the compiled kernels (kernels.roof_flux, landing_impacts)."""
        args = self._kernel_args
        if args is None:
            s = self.sites
            per_site = [np.ascontiguousarray(a, np.float64) for a in (self._drop_m3, s.phase, self._t_fall, s.x, s.z,
                                                                          self._momentum)]
            roofs = len(s.area_m2)
            args = self._kernel_args = (
                np.ascontiguousarray(self._ground, np.bool_), np.ascontiguousarray(s.roof, np.int64), per_site,
                np.ascontiguousarray(s.edges, np.int64), np.empty(roofs), np.empty(roofs, np.float32),
                np.empty((3 * len(s), 3)))  # the landings: each site at most once a tile, three tiles
        ground, roof, (drop_m3, phase, t_fall, x, z, momentum), edges, flux, flux32, out = args
        roofs = self.roofs
        # The flux (and its texture) change only with the roofs' storage: the same arrays, the same flux.
        key = self._flux_key
        if (key is None or key[0] is not roofs.storage_m3 or key[1] is not roofs.drain_s or key[2] is not args
                or key[3] is not self._tex.get("flux")):
            kernels.roof_flux(roofs.storage_m3, roofs.drain_s, edges, flux, flux32)
            self._upload(flux32)
            self._flux_key = (roofs.storage_m3, roofs.drain_s, args, self._tex.get("flux"))
        ranges = np.array(self._ranges, np.float64).reshape(-1, 3)
        t0, t1 = float(frame.time_s - frame.dt_s), float(frame.time_s)  # (as Python floats: one signature)
        k = kernels.landing_impacts(ranges, t0, t1, float(MAX_PERIOD_S), ground, drop_m3, flux, roof, phase, t_fall, x,
                                    z, momentum, out)
        self.landed = k
        if k:
            mine = out[:k].copy()  # the ripples' (the kept array is rewritten next frame)
            prev = rc.shared.droplet_impacts
            rc.shared.droplet_impacts = mine if prev is None or len(prev) == 0 else np.concatenate([prev, mine])

    # --- GL -------------------------------------------------------------------------------------------------
    def _upload(self, flux: np.ndarray) -> None:
        if not self._tex:
            s = self.sites
            n = len(s)
            rows = max(1, -(-n // 1024))
            a = np.zeros((rows * 1024, 4), np.float32)
            b = np.zeros((rows * 1024, 4), np.float32)
            a[:n] = np.stack([s.x, s.z, s.edge_y, s.land_y], axis=1)
            b[:n] = np.stack([s.phase, s.roof, physics.terminal_velocity(self._diam), self._diam], axis=1)
            for name, data in (("a", a), ("b", b)):
                tex = self.ctx.texture((1024, rows), 4, data.tobytes(), dtype="f4")
                tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
                self._tex[name] = tex
            self._tex["flux"] = self.ctx.texture((len(flux), 1), 1, dtype="f4")
            self._tex["flux"].filter = (moderngl.NEAREST, moderngl.NEAREST)
        self._tex["flux"].write(np.asarray(flux, np.float32).tobytes())

    def render(self, stage: str, rc: RenderContext) -> None:
        if stage != "transparent" or not self._ranges:
            return
        if self._prog is None:
            self._prog = (self._shaders or rc.shaders).program("drips/drip.vert", "drips/drip.frag")
            self._vao = self.ctx.vertex_array(self._prog, [])
        prog = self._prog
        rc.set_frame_uniforms(prog)
        settings = rc.frame.settings
        shutter = settings.camera.exposure_s if settings is not None else 1.0 / 60.0
        fov_y_deg = rc.frame.camera.fov_y_deg
        for i, name in enumerate(("a", "b", "flux")):
            self._tex[name].use(units.DRIPS[i])
        # Made and compared only when the shutter, the lens or the frame's height changes.
        owned_uniforms(prog).update_for("static", (shutter, fov_y_deg, rc.size[1]), lambda: {
            "u_sites_a": units.DRIPS[0], "u_sites_b": units.DRIPS[1], "u_roof_flux": units.DRIPS[2],
            "u_slots": SLOTS, "u_shutter_s": float(shutter), "u_max_period_s": float(MAX_PERIOD_S),
            "u_pixel_rad": 2.0 * math.tan(math.radians(fov_y_deg) / 2.0) / rc.size[1]})
        ctx = self.ctx
        ctx.enable(moderngl.DEPTH_TEST | moderngl.BLEND)  # one call for both flags
        rc.hdr.fbo.depth_mask = False  # test against the scene's depth, never write it
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        owned = owned_uniforms(prog)
        for first, count, z_base in self._ranges:  # written where they differ from the last draw's (one range: rarely)
            owned.set("u_first", first)
            owned.set("u_z_offset", float(z_base - rc.shift_z))
            self._vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=count * SLOTS)
        ctx.blend_func = moderngl.DEFAULT_BLENDING
        ctx.disable(moderngl.BLEND)
        rc.hdr.fbo.depth_mask = True

    def _release_textures(self) -> None:
        for tex in self._tex.values():
            tex.release()
        self._tex.clear()

    def release(self) -> None:
        self._release_textures()
        if self._vao is not None:
            self._vao.release()
            self._vao = None
        self._prog = None  # owned by the (shared, caching) ShaderLibrary
