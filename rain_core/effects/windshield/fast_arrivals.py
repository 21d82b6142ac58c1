"""The fast path's arrivals: the arrival law and its table, raindrops sampled and landed on the glass, and a full
glass's surplus given to the drops already there (a mixin of ``sim.WindshieldSim``; the float64 reference's
``arrival_rate_per_s``, ``_arrive`` and film surplus are the truth the fast-path tests compare with).
Units: m, s, kg, mm for drop diameters."""


from __future__ import annotations

import math

import numpy as np

from rain_core import jit, physics
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.arrivals import ArrivalTable
from rain_core.effects.windshield.constants import (
    FILM_CELLS,
    M_OBJECT_MIN,
    MAX_ARRIVALS_PER_SUBSTEP,
    SPLASH_MAX,
    SPLASH_SPEED_M_S,
    drop_radius,
    uniform_index,
)
from rain_core.effects.windshield.drop_rows import CELL as _CELL
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import RB as _RB
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T
from rain_core.effects.windshield.inputs import GlassInputs
from rain_core.effects.windshield.reference import _D_GRID_MM, _V_GRID_M_S
from rain_core.physics import RHO_WATER

_NONE_PLACED = np.zeros(0, bool)


class FastArrivals:
    """Arrivals of ``WindshieldSim`` (its state: the drop array, the film, the random generator)."""

    def _arrival_law(self, inputs: GlassInputs) -> tuple:
        """``arrival_rate_per_s`` and its ``ArrivalTable``, the per-diameter part by ``kernels.arrival_law`` (the
        same operations): (drops per second, closing speeds, CDF, table or None)."""
        if inputs.rate_mm_h <= 0.0 or inputs.sheltered or inputs.drop_scale <= 0.0:
            zeros = np.zeros_like(_D_GRID_MM)
            return 0.0, zeros, zeros, None
        n_world = np.asarray(inputs.car_rotation, float) @ self.glass.normal
        wind = np.asarray(inputs.wind_m_s, float).copy()
        wind[1] = 0.0
        a = float((wind - np.asarray(inputs.car_velocity_m_s, float)) @ n_world)
        if self._n0_cache[0] != inputs.rate_mm_h:
            shape = np.exp(-physics.mp_slope_per_mm(inputs.rate_mm_h) * _D_GRID_MM)
            self._n0_cache = (inputs.rate_mm_h, float(physics.effective_n0(inputs.rate_mm_h)), shape)
        _, n0, shape = self._n0_cache
        k = len(_D_GRID_MM)
        closing, cdf, coef = np.empty(k), np.empty(k), np.empty((k - 1, 5))
        kernels.arrival_law(_D_GRID_MM, _V_GRID_M_S, shape, float(n_world[1]), a, closing, cdf, coef)
        rate = self.glass.area_m2 * n0 * float(cdf[-1]) * inputs.drop_scale
        return rate, closing, cdf, ArrivalTable.from_law(closing, cdf, coef) if rate > 0 else None

    def _arrive_fast(self, h: float, rate_per_s: float, inputs: GlassInputs) -> None:
        """The reference's ``_arrive`` (same random numbers, same outcome)."""
        rng = self.rng
        n_all = int(rng.poisson(rate_per_s * h))
        if n_all == 0:
            return
        n = min(n_all, MAX_ARRIVALS_PER_SUBSTEP)
        # The reference's three draws of n (the size, then sample_uniform's two) in one: the same numbers.
        u = rng.random(3 * n)
        if jit.active():
            m = self._arrive_compiled(u, n)
            if n_all > n:
                self._arrive_as_mist(n_all - n, float(np.add.reduce(m) / n))  # (m.mean())
            return
        d_mm, u_n = self._table.sample(u[:n])
        m = (RHO_WATER * math.pi / 6.0 * 1e-9) * (d_mm * d_mm * d_mm)
        # GlassGeometry.sample_uniform, inlined: its u (across) and x (up) are also the film cell's u and v.
        g = self.glass
        u1, u2 = u[n : 2 * n], u[2 * n :]
        w0, dw, height = self._w0, self._dw * self._height, self._height
        q = u1 * (w0 + 0.5 * dw)
        x = 2.0 * q / (w0 + np.sqrt(w0 * w0 + 2.0 * dw * q)) if dw != 0 else q / w0
        v = np.minimum(np.maximum(x, 0.0), 1.0)
        t = v * height
        s = (u2 - 0.5) * g.width(t)
        self.arrived += float(np.add.reduce(m))
        self.arrival_count += n
        lo, hi = SPLASH_SPEED_M_S
        splash = np.minimum(np.maximum((u_n - lo) / (hi - lo), 0.0), 1.0) * SPLASH_MAX
        keep = m * (1.0 - splash)
        is_obj = keep >= M_OBJECT_MIN
        cells = self._cells(s, t)
        room = max(self._budget - self._n, 0)
        obj = is_obj.nonzero()[0]
        landed = is_obj
        if len(obj) > room:
            # A full glass: the surplus lands on (joins) a drop already in its cell, or else the film.
            over = obj[room:]
            obj = obj[:room]
            landed = is_obj.copy()
            landed[over] = self._give_to_drops(cells[over], keep[over])
        to_film = m - np.where(landed, keep, 0.0)
        self.film.ravel()[:] += np.bincount(cells, weights=to_film, minlength=FILM_CELLS * FILM_CELLS)
        a_obj = drop_radius(keep[obj])
        self._impacts.append((s, t, d_mm, splash, obj, a_obj, to_film))
        if len(obj):
            self._append_at_rest(s[obj], t[obj], keep[obj], a_obj)
        if n_all > n:
            self._arrive_as_mist(n_all - n, float(m.mean()))

    def _arrive_compiled(self, u: np.ndarray, n: int) -> np.ndarray:
        """``_arrive_fast`` after its draws, by ``kernels.sample_arrivals`` and ``land_arrivals`` (the twin's
        operations; its sums and cube roots in NumPy); returns the arrivals' masses (kg)."""
        table = self._table
        imp = np.empty((7, n))
        cells = np.empty(n, np.int64)
        obj = np.empty(n, np.int64)
        n_obj = kernels.sample_arrivals(u, n, table.cdf, table._coef, table.total, self._w0, self._dw, self._height,
                                        imp, cells, obj)
        self.arrived += float(np.add.reduce(imp[4]))
        self.arrival_count += n
        room = max(self._budget - self._n, 0)
        placed = _NONE_PLACED
        if n_obj > room:
            # A full glass: the surplus lands on (joins) a drop already in its cell, or else the film.
            over = obj[room:n_obj]
            placed = self._give_to_drops(cells.take(over), imp[5].take(over))
        kernels.land_arrivals(self.film.ravel(), self._scratch().total, cells, imp, n, obj, n_obj, room, placed)
        obj = obj[: min(n_obj, room)]
        keep = imp[5].take(obj)
        a_obj = drop_radius(keep)
        self._impacts.append((imp[0], imp[1], imp[2], imp[3], obj, a_obj, imp[6]))
        self._append_picked(imp[0], imp[1], obj, keep, a_obj)
        return imp[4]

    def _give_to_drops(self, cells: np.ndarray, mass: np.ndarray) -> np.ndarray:
        """Add each mass (kg) to a random drop of its film cell; returns which ones found a drop."""
        n = self._n
        if n == 0 or len(cells) == 0:
            return np.zeros(len(cells), bool)
        if jit.active():
            ks = self._scratch()
            k = len(cells)
            c, first, c_hit, picks = np.empty((4, k), np.int64)
            pick_m, placed = np.empty(k), np.empty(k, bool)
            n_hit = kernels.drops_in_cells(self._buf, n, self._dirty, self._w0, self._dw, self._height,
                                           cells.astype(np.int64, copy=False), ks.cell_mark, ks.cell_count,
                                           ks.cell_start, ks.hits, ks.members, c, first, placed, c_hit)
            if n_hit:
                # (the twin's draws: one uniform per query whose cell has drops, in order)
                n_p = kernels.give_to_drops(self._buf, self._fresh_buf, ks.members, first, c,
                                            self.rng.random(n_hit), mass, picks, pick_m)
                self._buf[picks[:n_p], _A] = drop_radius(pick_m[:n_p])
            return placed
        d = self._buf[:n]
        # The drops in those cells (a table marks the cells), grouped by cell in index order.
        drop_cells = d[:, _CELL].astype(np.int16)
        if self._dirty:  # only the cell of the drops placed this step is needed: the rest of _placed waits
            dirty = (d[:, _KEY] == _DIRTY).nonzero()[0]
            drop_cells[dirty] = self._cells(d[dirty, _S], d[dirty, _T])
        cells = cells.astype(np.int16)
        mark = self._cell_mark
        mark[cells] = True
        idx = mark[drop_cells].nonzero()[0]
        mark[cells] = False
        dc = drop_cells[idx]
        order = dc.argsort(kind="stable")  # 16-bit keys: a radix sort
        # Where each cell's run starts in the sorted cells, and its length (two binary searches, as a count).
        per_cell = np.bincount(dc, minlength=FILM_CELLS * FILM_CELLS)
        c = per_cell[cells]
        first = per_cell.cumsum()[cells]
        first -= c
        placed = c > 0
        if np.count_nonzero(placed):
            counts = c[placed]
            pick = idx[order[first[placed] + uniform_index(self.rng.random(len(counts)), counts)]]
            np.add.at(d[:, _M], pick, mass[placed])
            d[pick, _A] = drop_radius(d[pick, _M])
            d[pick, _RB] = np.inf  # grown: tested again
            self._fresh_buf[pick] = True
        return placed
