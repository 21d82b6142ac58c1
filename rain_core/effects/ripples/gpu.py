"""The GPU path of the wave solver: the scheme of ``WaveSolver`` in fragment shaders (``shaders/ripples/``)."""

from __future__ import annotations

import moderngl
import numpy as np

from rain_core import jit, physics
from rain_core.effects.ripples import kernels
from rain_core.effects.ripples.constants import MIN_FOOTPRINT_CELLS
from rain_core.effects.ripples.raindrops import DROP_CDF_NODES, DROP_MOMENTUM_NODES, RainBatch, momentum_table
from rain_core.effects.ripples.scroll import RowWindow, shift_in_place
from rain_core.effects.ripples.solver import WaveSolver
from rain_core.gfx import units
from rain_core.gfx.shaders import ShaderLibrary
from rain_core.gfx.targets import PingPong, float_target, fullscreen_triangle
from rain_core.gfx.uniforms import set_uniforms

REDUCE_BLOCK = 8  # cells per side summed by one fragment of the reduction pass

# Program (by GL name) → the constant uniforms last written into it. The shader library caches programs, so two
# solvers may share one; a solver re-writes its constants only when another wrote its own since.
_CONSTANTS_IN: dict[int, dict] = {}
_UNSET = object()


class WaveSolverGPU(WaveSolver):
    """The same solver in fragment shaders (OpenGL 3.3): an RG32F texture (current, previous) ping-ponged
    through ``shaders/ripples/step.frag``. Sources are queued as bumps (centre, radius, peak) and, before the
    next pass, drawn all at once: one buffer write and one instanced draw of ``shaders/ripples/impulse.*`` with
    additive blending — the CPU never evaluates a footprint. Raindrops (``queue_raindrops``) cost no upload:
    the impulse vertex shader makes them from a hash (``shaders/ripples/raindrops.glsl``), the CPU sends their
    count and two uniforms. ``height`` reads the texture back (float32).

    ``WaveSolverGPU(ctx, n, cell_m, speed_m_s, damping_per_s=0.0, shaders=None, **kw)``. Passes bind their
    inputs to the scratch texture units (``units.SCRATCH``) and leave blending disabled and the scissor reset.
    The programs come from the (caching) shader library, which may share them: every pass sets this solver's
    constant uniforms before it draws, unless they are already there."""

    dtype = np.float32
    # The CPU copy of the water mask only scrolls, uploads and answers questions (the shaders hold the cells):
    # bool, a quarter of float32's bytes to move at every scroll.
    mask_dtype = np.bool_

    def __init__(self, ctx, n: int, cell_m: float, speed_m_s: float, damping_per_s: float = 0.0, *,
                 shaders=None, **kwargs):
        self.ctx = ctx
        self._owns_shaders = shaders is None  # a library of our own: ours to release
        self.shaders = shaders if shaders is not None else ShaderLibrary(ctx)
        super().__init__(n, cell_m, speed_m_s, damping_per_s, **kwargs)

    def _alloc(self):
        ctx, n = self.ctx, self.n
        self.state = PingPong(ctx, (n, n), components=2, dtype="f4", filter_linear=False)
        for target in self.state.targets:
            target.fbo.clear(0.0, 0.0, 0.0, 0.0)
        # The water mask (R8, 1 water / 0 held) ping-pongs too: a scroll shifts it on the GPU (no n² upload),
        # and the field then writes only the strips that entered.
        self.mask = PingPong(ctx, (n, n), components=1, dtype="f1", filter_linear=False)
        self.mask.src.color.write(np.full(n * n, 255, np.uint8))
        self._mask_window: RowWindow | None = None  # where the CPU copy of the mask scrolls along z (shift)
        nb = -(-n // REDUCE_BLOCK)
        self.reduce_target = float_target(ctx, (nb, nb), 4, "f4", filter_linear=False)
        prog = self.shaders.program
        self._progs = {
            "step": prog("common/fullscreen.vert", "ripples/step.frag"),
            "retime": prog("common/fullscreen.vert", "ripples/step.frag", defines={"RIPPLES_RETIME": 1}),
            "reduce": prog("common/fullscreen.vert", "ripples/step.frag",
                           defines={"RIPPLES_REDUCE": 1, "RIPPLES_BLOCK": REDUCE_BLOCK}),
            "shift": prog("common/fullscreen.vert", "ripples/step.frag", defines={"RIPPLES_SHIFT": 1}),
            "mask_shift": prog("common/fullscreen.vert", "ripples/step.frag", defines={"RIPPLES_MASK_SHIFT": 1}),
            "impulse": prog("ripples/impulse.vert", "ripples/impulse.frag"),
            "rain": prog("ripples/impulse.vert", "ripples/impulse.frag", defines={"RIPPLES_RAIN": 1}),
        }
        self._vaos = {name: fullscreen_triangle(ctx, p) for name, p in self._progs.items() if name != "impulse"}
        state_unit, mask_unit, law_unit = units.SCRATCH
        self._written: dict[int, dict] = {}  # program (GL name) → per-pass uniforms this solver wrote there last
        self._constants = {"u_state": state_unit, "u_mask": mask_unit, "u_n": n,
                           "u_s2": self.speed_m_s ** 2, "u_inv_h2": 1.0 / self.cell_m ** 2,
                           "u_drop_law": law_unit,
                           "u_drop_range": (physics.D_MIN_MM, physics.D_MAX_MM, MIN_FOOTPRINT_CELLS)}
        # The raindrops' law (R32F): row 0 the CDF of the current rate (written when the rate changes), row 1
        # the momentum table (written once).
        self.drop_law = ctx.texture((DROP_MOMENTUM_NODES, 2), 1, dtype="f4")
        self.drop_law.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.drop_law.write(np.concatenate([np.zeros(DROP_MOMENTUM_NODES), momentum_table()[0]]).astype(np.float32))
        self._law = None  # the DropLaw whose CDF is in drop_law
        self._queued: list[np.ndarray] = []  # (K, 4) float32 bumps (x, z, radius in cells; peak m) not drawn yet
        self._rain: list[RainBatch] = []  # raindrop batches not drawn yet
        self._bump_capacity = 0
        self._bump_buffer = None
        self._bump_vao = None
        self._grow_bumps(1024)
        # A scroll of the state not drawn yet: the field writes the strips of the mask that entered right after
        # a scroll, and one shift pass under the new mask both moves the state and holds its new dry cells.
        self._pending_shift: tuple[int, int] | None = None

    def _grow_bumps(self, count: int) -> None:
        """Room for ``count`` bumps in the instance buffer (doubling, so a growing batch reallocates rarely)."""
        capacity = max(count, 2 * self._bump_capacity)
        for obj in (self._bump_vao, self._bump_buffer):
            if obj is not None:
                obj.release()
        self._bump_buffer = self.ctx.buffer(reserve=capacity * 16, dynamic=True)
        self._bump_vao = self.ctx.vertex_array(self._progs["impulse"], [(self._bump_buffer, "4f/i", "in_bump")])
        self._bump_capacity = capacity

    @property
    def mask_texture(self):
        """The current water-mask texture (R8: 1 water, 0 held), [iz, ix] = row, column."""
        return self.mask.src.color

    def _own(self, prog) -> None:
        """Write this solver's constant uniforms into ``prog`` unless they are already there."""
        if _CONSTANTS_IN.get(prog.glo) is not self._constants:
            set_uniforms(prog, self._constants)
            _CONSTANTS_IN[prog.glo] = self._constants
            self._written.pop(prog.glo, None)  # another solver may have written its own values since

    def _set(self, prog, uniforms: dict) -> None:
        """Write the per-pass uniforms that differ from what this solver last wrote into ``prog`` (call after
        ``_own``): the sub-step's coefficients and a zero shift repeat frame after frame."""
        written = self._written.setdefault(prog.glo, {})
        changed = {k: v for k, v in uniforms.items() if written.get(k, _UNSET) != v}
        if changed:
            set_uniforms(prog, changed)
            written.update(changed)

    def _draw(self, name: str, target, uniforms: dict, bind_state: bool = True, bind_mask: bool = True):
        """One full-grid pass of ``name`` into ``target``; the state (and mask) textures bound unless the caller
        says they need not be (the mask's own pass reads no state; sub-steps after the first find the mask
        still bound)."""
        prog = self._progs[name]
        self._own(prog)
        self._set(prog, uniforms)
        state_unit, mask_unit, _ = units.SCRATCH
        if bind_state:
            self.state.src.color.use(state_unit)
        if bind_mask:
            self.mask_texture.use(mask_unit)
        target.fbo.use()
        self._vaos[name].render(vertices=3)

    def _pass(self, name: str, uniforms: dict, bind_mask: bool = True):
        """Run a full-grid pass from state.src into state.dst and swap."""
        self._draw(name, self.state.dst, uniforms, bind_mask=bind_mask)
        self.state.swap()

    def _shift_state(self) -> bool:
        """Draw the pending scroll of the state, if any. Returns whether it drew (the mask is then bound)."""
        if self._pending_shift is None:
            return False
        shift, self._pending_shift = self._pending_shift, None
        self._pass("shift", {"u_shift": shift})
        return True

    def add_impulses_unchecked(self, xs, zs, radii, amounts):
        """Queue the bumps (see ``WaveSolver.add_impulses_unchecked``); they are drawn together before the next
        pass that reads the state."""
        rows = self._bump_rows(xs, zs, radii, amounts)
        if len(rows) == 0:
            return
        self._queued.append(rows)
        self._sourced = True
        self._asleep = False

    def _bump_rows(self, xs, zs, radii, amounts) -> np.ndarray:
        """(K', 4) float32 instance rows (x, z, radius in cells, peak m) of the bumps that touch the grid
        (``_bumps``)."""
        inv_h = 1.0 / self.cell_m
        if jit.active():  # _bumps and the rows in one loop: a frame's few hundred bumps cost ~20 NumPy calls
            rows = np.empty((xs.size, 4), np.float32)
            f64 = np.float64
            count = kernels.gpu_bump_rows(np.ascontiguousarray(xs, f64), np.ascontiguousarray(zs, f64),
                                          np.ascontiguousarray(radii, f64), np.ascontiguousarray(amounts, f64),
                                          MIN_FOOTPRINT_CELLS * self.cell_m, self.length_m, inv_h, rows)
            return rows[:count]
        xs, zs, r_eff, amounts = self._bumps(xs, zs, radii, amounts)
        rows = np.empty((xs.size, 4), np.float32)  # straight into the instance layout: no float64 (K, 4) first
        np.multiply(xs, inv_h, out=rows[:, 0], casting="same_kind")
        np.multiply(zs, inv_h, out=rows[:, 1], casting="same_kind")
        np.multiply(r_eff, inv_h, out=rows[:, 2], casting="same_kind")
        rows[:, 3] = amounts
        return rows

    def queue_raindrops(self, batch: RainBatch) -> None:
        """Queue a frame's raindrops (``raindrops.RainBatch``, trusted): drawn with the queued bumps, made by the
        impulse vertex shader from the batch's key — one draw of a point per drop, two uniforms, no upload (the
        law's CDF only when the rain rate changed)."""
        if batch.count > 0:
            self._rain.append(batch)
            self._sourced = True
            self._asleep = False

    def _prepare_rain(self, batch: RainBatch):
        """Bind and set what the raindrop program needs for ``batch``; returns the program."""
        prog = self._progs["rain"]
        self._own(prog)
        if batch.law is not self._law:
            cdf = np.asarray(batch.law.cdf, np.float32)
            self.drop_law.write(cdf, viewport=(0, 0, DROP_CDF_NODES, 1))
            self._law = batch.law
        self._set(prog, {"u_rain_key": batch.key, "u_rain_peak": batch.peak_per_momentum,
                         "u_crater_cells": batch.crater_m_per_mm / self.cell_m})
        self.drop_law.use(units.SCRATCH[2])
        return prog

    def raindrop_bumps(self, batch: RainBatch) -> np.ndarray:
        """(count, 4) float32: the bumps the shader makes for ``batch`` (x, z, radius in cells, peak m; peak 0 for
        drops over dry cells), read back by transform feedback — for tests against the NumPy twin."""
        if "rain_feedback" not in self._progs:
            self._progs["rain_feedback"] = self.shaders.program("ripples/impulse.vert", defines={"RIPPLES_RAIN": 1},
                                                                varyings=("v_bump",))
            self._vaos["rain_feedback"] = self.ctx.vertex_array(self._progs["rain_feedback"], [])
        self._flush()
        rain = self._progs["rain"]
        self._progs["rain"] = self._progs["rain_feedback"]  # the same uniforms and textures as a draw
        try:
            self._prepare_rain(batch)
        finally:
            self._progs["rain"] = rain
        self.mask_texture.use(units.SCRATCH[1])
        out = self.ctx.buffer(reserve=max(1, batch.count) * 16)
        try:
            self._vaos["rain_feedback"].transform(out, moderngl.POINTS, vertices=batch.count)
            return np.frombuffer(out.read(), np.float32).reshape(-1, 4)[:batch.count].copy()
        finally:
            out.release()

    def _flush(self) -> bool:
        """Draw the pending scroll, then add the queued bumps to both stored levels: one buffer write and one
        instanced additive draw, and one instanced draw per queued raindrop batch (no upload). Returns whether
        it drew anything (the mask texture is then bound to its unit)."""
        shifted = self._shift_state()
        if not self._queued and not self._rain:
            return shifted
        bumps = None
        if self._queued:
            bumps = self._queued[0] if len(self._queued) == 1 else np.concatenate(self._queued)
            self._queued = []
            if len(bumps) > self._bump_capacity:
                self._grow_bumps(len(bumps))
            self._bump_buffer.write(bumps)
        rain, self._rain = self._rain, []
        if not shifted:  # else the scroll's pass left the mask bound and the new state its framebuffer
            self.mask_texture.use(units.SCRATCH[1])
            self.state.src.fbo.use()
        self.ctx.enable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE if rain else moderngl.BLEND)
        self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        try:
            if bumps is not None:
                self._own(self._progs["impulse"])
                self._bump_vao.render(moderngl.TRIANGLE_STRIP, vertices=4, instances=len(bumps))
            for batch in rain:
                self._prepare_rain(batch)
                self._vaos["rain"].render(moderngl.POINTS, vertices=batch.count)
        finally:
            self.ctx.disable(moderngl.BLEND | moderngl.PROGRAM_POINT_SIZE)
        return True

    def _get_state(self):
        self._flush()
        data = np.frombuffer(self.state.src.color.read(), np.float32).reshape(self.n, self.n, 2)
        return data[..., 0].astype(np.float64), data[..., 1].astype(np.float64)

    def _set_state(self, z, zp):
        self._queued = []
        self._rain = []
        self._pending_shift = None  # the whole state is replaced
        data = np.stack([np.asarray(z, np.float32), np.asarray(zp, np.float32)], axis=-1)
        self.state.src.color.write(np.ascontiguousarray(data).tobytes())

    @property
    def height(self) -> np.ndarray:
        z, _ = self._get_state()
        return z.astype(np.float32)

    @property
    def texture(self):
        """The current state texture (RG32F: R height, G previous height, metres); changes every step."""
        self._flush()
        return self.state.src.color

    def _advance(self, k: int, alpha: float, kc2: float):
        bound = self._flush()
        uniforms = {"u_alpha": alpha, "u_k": kc2}
        for i in range(k):  # the mask stays bound to its unit from the flush or the first sub-step on
            self._pass("step", uniforms, bind_mask=i == 0 and not bound)

    def _sums(self, dt_old, synced=None):
        self._flush()
        self._draw("reduce", self.reduce_target, {"u_dt_old": 0.0 if dt_old is None else dt_old})
        sums = np.frombuffer(self.reduce_target.color.read(), np.float32).reshape(-1, 4).astype(np.float64)
        total = sums.sum(axis=0)
        return float(total[0]), float(total[1]), float(total[2])

    def _retime(self, dt_new: float):
        dt_old = self._dt
        lam = mu = 1.0
        if dt_old is not None and dt_new < dt_old:
            lam, mu = self._guard(dt_old, dt_new, self._sums(dt_old))
        self.retimes += dt_old is not None
        self._flush()
        self._pass("retime", {"u_dt_old": 0.0 if dt_old is None else dt_old, "u_dt_new": dt_new,
                              "u_lambda": lam, "u_mu": mu})
        self._dt = dt_new

    def energy(self) -> float:
        """Discrete energy (m⁴/s²) from GPU block sums: h²·[½Σu² + ½s²Σz·Az − (Δt²s⁴/8)Σ(Az)²], the same
        quantity as the reference's staggered form (equal algebraically, see the module docstring)."""
        k_sum, p_sum, r_sum = self._sums(self._dt)
        dt = self._dt or 0.0
        s2 = self.speed_m_s ** 2
        return self.cell_m ** 2 * (0.5 * k_sum + 0.5 * s2 * p_sum - dt * dt * s2 * s2 / 8.0 * r_sum)

    def _upload_mask(self):
        m = np.ones((self.n, self.n)) if self._mask is None else self._mask
        self.mask_texture.write((np.asarray(m) > 0.5).astype(np.uint8).__mul__(255).tobytes())

    def _apply_mask_to_blocks(self, regions):
        if self._queued or self._rain:  # laid under the old mask (a cell turning wet must not get them)
            self._flush()
        for rows, cols in regions:  # only the blocks travel; one pass then holds their dry cells
            data = np.multiply(self._mask[rows, cols], np.uint8(255), dtype=np.uint8)  # 0 / 255, one pass
            self.mask_texture.write(data, viewport=(cols.start, rows.start, data.shape[1], data.shape[0]),
                                    alignment=1)
        self._hold_under_mask()

    def _apply_mask_to_state(self):
        if self._queued or self._rain:
            self._flush()
        self._upload_mask()
        self._hold_under_mask()

    def _hold_under_mask(self) -> None:
        """Zero the held cells of the mask just written: the pending scroll's pass does it as it moves the state
        (held cells store 0 on either side of a scroll, so scrolling under the new mask is the same as scrolling
        and then applying it), else a pass of zero shift."""
        if self._pending_shift is None:
            self._pending_shift = (0, 0)
        self._shift_state()

    def set_water_mask(self, mask):
        super().set_water_mask(mask)
        if mask is None:
            self._upload_mask()

    def shift(self, dx_cells: int, dz_cells: int):
        dx, dz = int(dx_cells), int(dz_cells)
        if dx == 0 and dz == 0:
            return
        self._flush()
        if self._mask is not None:
            if dx == 0:  # along z: the row window moves, not the rows (scroll.RowWindow: the same values)
                window = self._mask_window
                if window is None or not window.fits(self._mask):
                    window = self._mask_window = RowWindow(self._mask, self.n // 2)
                self._mask = window.scrolled(self._mask, dz, True)
            else:
                shift_in_place(self._mask, dx, dz, 1.0)
            self._draw("mask_shift", self.mask.dst, {"u_shift": (dx, dz)}, bind_state=False)
            self.mask.swap()
        if not self._asleep:  # drawn by the next pass that needs the state: after the new mask's strips
            self._pending_shift = (dx, dz)

    def release(self):
        """Free the GL objects, and the programs when the shader library is our own."""
        for prog in self._progs.values():  # the programs stay with the library; forget our constants in them
            if _CONSTANTS_IN.get(prog.glo) is self._constants:
                del _CONSTANTS_IN[prog.glo]
        self.state.release()
        self.mask.release()
        self.reduce_target.release()
        self.drop_law.release()
        for obj in (self._bump_vao, self._bump_buffer, *self._vaos.values()):
            obj.release()
        if self._owns_shaders:
            self.shaders.release()

