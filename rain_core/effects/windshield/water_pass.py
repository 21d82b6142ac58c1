"""The windshield effect's water textures (a mixin of ``effect.WindshieldEffect``): each frame the film texture
relaxes towards the CPU film and takes the deposits of the step (wet trails, splash speckle), the drops and wiper
beads are splatted into a height texture, and both make the water texture (thickness, film, slopes) the glass pass
refracts through. See ``effect``'s docstring for why the texture is a rendering of the simulation's state."""

from __future__ import annotations

import math
import struct

import moderngl
import numpy as np

from rain_core import jit
from rain_core.effects.windshield import render_kernels
from rain_core.effects.windshield.constants import (
    EVAP_AIR_M_S,
    FILM_CELLS,
    FILM_EVAP_KG_M2_S,
    RESIDUE_M,
)
from rain_core.effects.windshield.splats import half_bits
from rain_core.gfx import units
from rain_core.gfx.targets import float_target
from rain_core.physics import RHO_WATER

FILM_DIFFUSION_M2_S = 5e-6  # visual spreading of thin water in the film texture
FILM_BEAD_RATE_PER_S = 0.15  # a thin film left alone pulls into micro-droplets over several seconds
BEAD_LIFE_S = 15.0  # the densest bead trail a sliding drop leaves evaporates over this time (s)
_UNIT_A, _UNIT_B, _UNIT_C, _UNIT_D = units.WINDSHIELD  # each pass binds its (up to) four textures to these


class WaterPass:
    """The water textures of ``WindshieldEffect`` (its programs, buffers, builders and simulation): ``_upload_water``
    is its "upload" stage, ``_draw_water`` its "prepare" stage."""

    def _ensure_textures(self, resolution: int) -> None:
        if resolution == self.resolution:
            return
        self._release_textures()
        n = int(resolution)
        size = (n, n)
        self._film = [float_target(self.ctx, size, 2, "f2") for _ in range(2)]  # film µm, bead-trail density
        for target in self._film:
            target.color.build_mipmaps()
            target.color.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            target.fbo.clear(0.0, 0.0, 0.0, 0.0)
            target.color.build_mipmaps()
        self._drops = float_target(self.ctx, size, 1, "f2")
        self._water = float_target(self.ctx, size, 4, "f2")
        self.resolution = n

    def _release_textures(self) -> None:
        for target in [*self._film, getattr(self, "_drops", None), getattr(self, "_water", None)]:
            if target is not None:
                target.release()
        self._film = []
        self._drops = self._water = None
        self.resolution = 0

    # --- the water textures ---------------------------------------------------------------------------------
    def _texel_m(self) -> float:
        return max(self.glass.width_bottom, self.glass.height) / self.resolution

    def _coarse_bits(self) -> np.ndarray:
        """The CPU film's mean thickness per cell (µm, at most 6e4: half floats end at 65504) as float16 bits
        (NumPy's float16 cast is slow), (FILM_CELLS, FILM_CELLS) uint16: ``film_thickness_m`` × 1e6, in arrays kept
        from frame to frame."""
        sim = self.sim
        shape = sim.film.shape
        if self._coarse_scratch is None or self._coarse_scratch[0].shape != shape:
            f32 = np.zeros(shape, np.float32)
            # + the flat views the kernel writes: f32, its bits, the result's
            self._coarse_scratch = (np.zeros(shape), f32, np.empty(shape, np.uint16), f32.ravel(),
                                    f32.view(np.uint32).ravel())
        f64, f32, bits16, f32_flat, u32_flat = self._coarse_scratch
        if jit.active():  # all of it in one pass
            render_kernels.coarse_half_bits(sim.film.ravel(), sim.cell_areas.ravel(), RHO_WATER, f32_flat, u32_flat,
                                            bits16.ravel())
            return bits16
        sim.film_thickness_m(out=f64)
        f64 *= 1e6
        np.minimum(f64, 6e4, out=f64)
        f32[...] = f64
        bits = half_bits(f32, out=f32.view(np.uint32))
        np.copyto(bits16, bits, casting="unsafe")
        return bits16

    def _resolution_of(self, settings) -> int:
        """The water textures' resolution the settings ask for."""
        return int(settings.quality.windshield_resolution) if settings is not None else 512

    def _make_rows_early(self, rc) -> None:
        """The water pass's rows (drops, film deposits) and coarse film bits, made by ``update`` right after the
        step, while it has left the drop array and the film in the cache: by the prepare pass the other effects'
        updates have evicted them and the same copies read them from memory (~0.2 ms more at 5,700 drops). Kept
        for this render context while the simulation stays as it is (its version) and the resolution too."""
        sim = self.sim
        version = getattr(sim, "version", None)
        if version is None:  # (a simulation without one: the reference) made in the water pass
            return
        n = self._resolution_of(self._settings(rc.frame))
        texel_m = max(self.glass.width_bottom, self.glass.height) / n  # _texel_m at that resolution
        self._early = (rc, sim, version, n, self._drop_builder.rows(sim), self._film_builder.rows(sim, texel_m),
                       self._coarse_bits())

    def _take_early(self, rc) -> tuple | None:
        """(drop rows, film rows, coarse bits) that ``update`` made for this render context and the simulation
        as it is now at this resolution, or None (then the water pass makes them)."""
        early, self._early = self._early, None
        sim = self.sim
        if (early is not None and early[0] is rc and early[1] is sim and early[2] == getattr(sim, "version", None)
                and early[3] == self.resolution):
            return early[4:]
        return None

    def _write_splats(self, which: int, splats: np.ndarray) -> int:
        """Write splat rows into their buffer (``which``: 0 the film deposits, 1 the drops and beads, each in its
        own); returns how many (``_draw_splats`` draws them)."""
        if not len(splats):
            return 0
        data = splats if which else np.ascontiguousarray(splats, dtype=np.float32)  # drops: splats.DROP_ROW
        buf = self._splat_bufs[which]
        if data.nbytes > buf.size:
            buf.orphan(int(data.nbytes * 1.5))
        buf.write(data)
        self.upload_bytes += data.nbytes
        return len(data)

    def _draw_splats(self, which: int, count: int) -> None:
        """The ``count`` splats ``_write_splats`` wrote into the bound target with one instanced draw, blended as
        set by the caller."""
        if count:
            self.splat_draws += 1
            self._splat_vaos[which].render(moderngl.TRIANGLES, vertices=6, instances=count)

    def _upload_water(self, rc) -> None:
        """The "upload" stage: the water pass's writes (the CPU film as float16 bits per cell, the film deposits'
        and the drops' splat rows), before the frame's first draw (gfx/effect.py: each of them makes Mesa's
        driver thread wait); ``_draw_water`` draws them."""
        self._ensure_textures(self._resolution_of(self._settings(rc.frame)))
        early = self._take_early(rc)
        sim = self.sim
        # The CPU film now, as mean thickness (µm) per cell, as float16 bits (half floats end at 65504; NumPy's
        # float16 cast is slow), into the coarse texture the pass does not read as last frame's.
        coarse = self._coarse_bits() if early is None else early[2]
        self._coarse[1 - self._coarse_index].write(coarse)
        self.upload_bytes = coarse.nbytes
        film = self._write_splats(0, self._film_builder.rows(sim, self._texel_m()) if early is None else early[1])
        drops = self._write_splats(1, self._drop_builder.rows(sim) if early is None else early[0])
        self._drop_rows = drops
        self._uploaded = (rc, film, drops)

    def _draw_water(self, rc) -> None:
        ctx = self.ctx
        uploaded = self._uploaded
        if uploaded is None or uploaded[0] is not rc:  # prepare asked alone (a benchmark, a test): upload here
            self._upload_water(rc)
            uploaded = self._uploaded
        self._uploaded = None
        _, film_splats, drop_splats = uploaded
        sim = self.sim
        n = self.resolution
        lod = math.log2(n / FILM_CELLS)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)  # one call: each costs
        cur = 1 - self._coarse_index  # the film the upload wrote
        self.splat_draws = 0
        prev = self._coarse[self._coarse_index]
        src, dst = self._film[self._film_index], self._film[1 - self._film_index]
        # 1. relax last frame's film (rescaled to the CPU film it showed) and wipe what the blades swept.
        src.color.use(_UNIT_A)
        prev.use(_UNIT_B)
        dt = self._dt
        inputs = self._inputs
        if self._head_memo[0] is not inputs:  # the same inputs while parked (inputs_for)
            # The step's air of these inputs (its _prepare made it: the same product), else made here.
            air = sim._air_local if getattr(sim, "_inputs_seen", None) is inputs else inputs.relative_air_local()
            self._head_memo = (inputs, max(float(air[2]), 0.0) * 0.65)
        head = self._head_memo[1]
        residue_um = RESIDUE_M * (1.0 + 4.0 * inputs.blade_wear) * 1e6
        sweeps = []
        for sweep in sim.frame_sweeps():
            sweeps += (sweep[0], sweep[1], 1.0, residue_um) if sweep else (0.0, 0.0, 0.0, 0.0)
        blades = self._blades_bytes()
        texel_m = self._texel_m()
        # Our programs' own uniforms go through owned_uniforms: a value that did not change is not written again;
        # those that change only with the resolution are not even looked at in between (update_for).
        film_u = self._film_u
        film_u.update_for("static", (self._token, n, blades), lambda: dict(
            u_film=_UNIT_A,
            u_coarse=_UNIT_B,
            u_coarse_lod=lod,
            u_texel=(1.0 / n, 1.0 / n),
            u_blade=blades,
            u_seed=self.seed % 100000,
        ))
        # Those of the frame's step: made again only when the step's length or the head wind changes.
        film_u.update_for("step", (self._token, n, dt, head), lambda: dict(
            u_diffusion=min(FILM_DIFFUSION_M2_S * dt / texel_m ** 2, 0.2),
            u_dry_um=FILM_EVAP_KG_M2_S * (1.0 + head / EVAP_AIR_M_S) * dt / RHO_WATER * 1e6,
            u_bead_mix=1.0 - math.exp(-FILM_BEAD_RATE_PER_S * dt),
            u_bead_dry=dt / BEAD_LIFE_S,
        ))
        film_u.set("u_sweep", struct.pack(f"{len(sweeps)}f", *sweeps))  # float32 as NumPy's cast rounds
        dst.fbo.use()
        self._film_vao.render(moderngl.TRIANGLES, vertices=3)
        # 2. deposits: wet trails and splash speckle, added (the blending the splats of 2 and 3 share, set once).
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = (moderngl.ONE, moderngl.ONE)
        ctx.blend_equation = moderngl.FUNC_ADD
        self._draw_splats(0, film_splats)
        dst.color.build_mipmaps()
        # 3. drops and beads: heights (mm), overlapping splats keep the highest.
        self._drops.fbo.use()
        self._drops.fbo.clear(0.0, 0.0, 0.0, 0.0)
        self._splat_u.update_for("static", (self._token, n), lambda: dict(u_min_radius=0.75 * texel_m))
        ctx.blend_equation = moderngl.MAX
        self._draw_splats(1, drop_splats)
        ctx.blend_equation = moderngl.FUNC_ADD
        ctx.disable(moderngl.BLEND)
        # 4. the water texture: thickness, film, slopes.
        self._drops.color.use(_UNIT_A)
        dst.color.use(_UNIT_B)
        self._coarse[cur].use(_UNIT_C)
        self._normals_u.update_for("static", (self._token, n), lambda: dict(
            u_drops=_UNIT_A,
            u_film=_UNIT_B,
            u_coarse=_UNIT_C,
            u_coarse_lod=lod,
            u_texel=(1.0 / n, 1.0 / n),
        ))
        self._water.fbo.use()
        self._normals_vao.render(moderngl.TRIANGLES, vertices=3)
        self._film_index = 1 - self._film_index
        self._coarse_index = cur
