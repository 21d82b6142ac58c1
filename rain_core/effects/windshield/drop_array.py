"""The fast path's drops as one array (``WindshieldSim``'s storage; see ``sim``'s docstring): position,
velocity, mass, trail run, contact radius and the position's cached columns are the columns of one preallocated
array (``drop_rows``). Appending writes rows, removing drops is one compaction of whole rows, sorting one
gather; ``pos``, ``vel``, ``mass``, ``trail`` and ``fresh`` are views of it (assign ``pos`` or ``mass`` whole,
through their setters, to keep the cell and the radius with them).

A mixin: the class that uses it provides ``_placed`` (the position's columns) and the glass's ``_w0``, ``_dw``
and ``_height``.
"""

from __future__ import annotations

import numpy as np

from rain_core import jit
from rain_core.effects.windshield import kernels
from rain_core.effects.windshield.constants import FILM_CELLS, MERGE_CELLS_MAX, drop_radius
from rain_core.effects.windshield.drop_rows import COLS as _COLS
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY as _KEY
from rain_core.effects.windshield.drop_rows import PLACED as _PLACED
from rain_core.effects.windshield.drop_rows import RB as _RB
from rain_core.effects.windshield.drop_rows import ROW as _ROW
from rain_core.effects.windshield.drop_rows import TRAIL as _TRAIL
from rain_core.effects.windshield.drop_rows import VS as _VS
from rain_core.effects.windshield.drop_rows import VT as _VT
from rain_core.effects.windshield.drop_rows import A as _A
from rain_core.effects.windshield.drop_rows import M as _M
from rain_core.effects.windshield.drop_rows import S as _S
from rain_core.effects.windshield.drop_rows import T as _T

_ALL = np.zeros(0, np.int64)  # DropArray._append_picked: no picks, every point


class KernelScratch:
    """Work arrays of the compiled kernels (``kernels``) for a drop array of capacity ``cap``: made once, kept
    (not copied with the simulation), so a step allocates nothing large. The float ones are made zeroed: reused
    memory may hold NaN, which the soak (tests/soak) would report as the effect's state."""

    def __init__(self, cap: int, extra_rows: int = 0):
        self.cap = cap
        self.go = np.empty(cap, np.int64)  # move_drops: the drops that slid, and their motion
        self.gcol = np.zeros((6, cap))
        self.loss = np.zeros(cap)
        self.ridx = np.empty(cap, np.int64)  # run_drops: the running drops, their trails, the new droplets
        self.rcol = np.zeros((5, cap))
        self.wcol = np.zeros((3, 4 * cap))
        self.total = np.zeros(FILM_CELLS * FILM_CELLS)
        self.gidx = np.full(cap, -1, np.int64)  # merge_drops
        self.active = np.empty(cap, bool)
        self.parent = np.full(cap, -1, np.int64)
        self.nodes = np.empty(cap, np.int64)
        self.mark = np.zeros(cap, bool)
        self.sums = np.zeros((7, cap))
        self.count = np.zeros(kernels.NEAR_CELLS, np.int64)
        self.head = np.full(kernels.NEAR_CELLS, -1, np.int64)
        entries = max(MERGE_CELLS_MAX, cap)
        self.nxt = np.empty(entries, np.int64)
        self.owner = np.empty(entries, np.int64)
        self.ekey = np.empty(entries, np.int64)
        self.out = np.empty(cap, np.int64)
        self.mid = np.zeros((3, cap))
        self.gone = np.empty(cap, bool)  # sweep_blades
        self.cell_mark = np.zeros(FILM_CELLS * FILM_CELLS, np.int64)  # drops_in_cells
        self.cell_count = np.zeros(FILM_CELLS * FILM_CELLS, np.int64)
        self.cell_start = np.zeros(FILM_CELLS * FILM_CELLS, np.int64)
        self.members = np.empty(cap, np.int64)
        self.hits = np.empty((2, cap), np.int64)
        self.drop = np.empty(cap, bool)  # shed_rows
        self.shed_m = np.zeros(cap)
        self.sensor_m = np.zeros(cap)
        self.hist = np.empty(512, np.int64)  # sort_rows
        self.order = np.empty(4 * cap, np.int64)
        self.tmp = np.zeros((cap, _COLS))  # (the shapes of the drop array: sort_rows may swap them)
        self.tmp_fresh = np.zeros(cap, bool)
        # The drops' float32 rows the sort's full copy wrote (sort_rows), with room for ``extra_rows`` bead rows
        # after them (splats.DropRows), and the drops' version (DropArray.version) they are of, or -1.
        self.rows32 = np.zeros((cap + extra_rows, 5), np.float32)
        self.rows32_of = -1
        self.film_loss = np.zeros(FILM_CELLS * FILM_CELLS)  # evaporate_film
        self.thick = np.empty(FILM_CELLS * FILM_CELLS, np.int64)


class DropArray:
    """The drops of ``WindshieldSim`` as rows of one array (see the module docstring)."""

    version = 0  # (the class's: a simulation pickled before it counted starts from 0)
    # An upper bound on the drops' radii (m) from the last shed's compaction (sim._shed_outside), for the wipers'
    # wedges (fast_wiping): valid until a drop is added or changed from outside (``changed``) or the step's sweeps
    # end (the film step and the next sub-step grow drops); a larger bound only widens the wedges' pre-test.
    _a_bound: float | None = None

    def _init_drops(self) -> None:
        self._n = 0
        self._buf = np.zeros((512, _COLS))
        self._rows = self._buf.view(_ROW).ravel()  # one element a drop: whole-row gathers are ~7× faster
        self._fresh_buf = np.zeros(512, bool)  # born, grown or merged since the last merge test
        self._dirty = False  # some drop's position columns are still to be written (drop_rows.DIRTY)
        self._rest_air = None  # the air (head, cross) of the epoch the drops' RB columns hold for (fast_motion)
        self._step_air = None  # the air (head, cross) of the last step: the drops' EV columns hold for it
        self._shed_all = False  # test every drop against the glass's edges in the next _shed_outside
        self._ks: KernelScratch | None = None
        self.version = 0  # counts changes of the drops (``changed``): what is made from them is made again

    def changed(self) -> None:
        """Note that the drops, beads or wipers changed (a step, drops added or removed, a column assigned): the
        effect's drop rows made from them (``WindshieldEffect.update``) are no longer theirs."""
        self.version += 1
        self._a_bound = None

    def _scratch(self) -> KernelScratch:
        """The compiled kernels' work arrays, for the drop array's capacity."""
        ks = self._ks
        if ks is None or ks.cap < len(self._buf):
            ks = self._ks = KernelScratch(len(self._buf), self.beads.size)
        return ks

    def drop_rows32(self) -> np.ndarray | None:
        """The drops' float32 rows (s, t, vs, vt, contact radius: ``splats.DROP_ROW``) as the last sort wrote them
        while it copied every row, with room for the beads' rows after them; None when the drops changed since
        (``version``), or the last sort moved few rows (it did not copy them all) or ran the NumPy twin."""
        ks = self._ks
        if ks is None or ks.rows32_of != self.version:
            return None
        return ks.rows32

    @property
    def pos(self) -> np.ndarray:
        return self._buf[: self._n, _S : _T + 1]

    @pos.setter
    def pos(self, value) -> None:
        d = self._buf[: self._n]
        d[:, _S : _T + 1] = value
        d[:, _PLACED] = self._placed(d[:, _S], d[:, _T])
        d[:, _RB] = np.inf
        self._shed_all = True
        self.changed()

    @property
    def vel(self) -> np.ndarray:
        return self._buf[: self._n, _VS : _VT + 1]

    @vel.setter
    def vel(self, value) -> None:
        self._buf[: self._n, _VS : _VT + 1] = value
        self._buf[: self._n, _RB] = np.inf
        self.changed()

    @property
    def mass(self) -> np.ndarray:
        return self._buf[: self._n, _M]

    @mass.setter
    def mass(self, value) -> None:
        self._buf[: self._n, _M] = value
        self._buf[: self._n, _A] = drop_radius(self._buf[: self._n, _M])
        self._buf[: self._n, _RB] = np.inf
        self.changed()

    @property
    def trail(self) -> np.ndarray:
        return self._buf[: self._n, _TRAIL]

    @trail.setter
    def trail(self, value) -> None:
        self._buf[: self._n, _TRAIL] = value
        self.changed()

    @property
    def fresh(self) -> np.ndarray:
        return self._fresh_buf[: self._n]

    @fresh.setter
    def fresh(self, value) -> None:
        self._fresh_buf[: self._n] = value
        self.changed()

    @property
    def count(self) -> int:
        return self._n

    def radius(self) -> np.ndarray:
        """Contact radius (m) of each drop."""
        return self._buf[: self._n, _A].copy()

    def _reserve(self, n: int) -> None:
        if n > len(self._buf):
            cap = max(n, 2 * len(self._buf))
            buf = np.zeros((cap, _COLS))
            buf[: self._n] = self._buf[: self._n]
            fresh = np.zeros(cap, bool)
            fresh[: self._n] = self._fresh_buf[: self._n]
            self._buf, self._fresh_buf = buf, fresh
            self._rows = buf.view(_ROW).ravel()

    def _append(self, pos: np.ndarray, vel: np.ndarray, mass: np.ndarray, radius: np.ndarray | None = None) -> None:
        rows = self._new_rows(mass, radius)
        if rows is not None:
            rows[:, _S : _T + 1] = pos
            rows[:, _VS : _VT + 1] = vel

    def _append_at_rest(self, s: np.ndarray, t: np.ndarray, mass: np.ndarray, radius: np.ndarray | None = None) -> None:
        """``_append`` of drops at rest at (s, t) m, given as columns."""
        if jit.active() and len(mass):
            self._append_picked(s, t, _ALL, mass, drop_radius(mass) if radius is None else radius)
            return
        rows = self._new_rows(mass, radius)
        if rows is not None:
            rows[:, _S] = s
            rows[:, _T] = t
            rows[:, _VS : _VT + 1] = 0.0

    def _append_picked(self, s: np.ndarray, t: np.ndarray, picks: np.ndarray, mass: np.ndarray,
                       radius: np.ndarray) -> None:
        """``_append_at_rest`` of the points ``picks`` of the columns ``s``, ``t`` (m), or with ``picks`` empty
        (``_ALL``) of all of them, by ``kernels.append_at_rest`` where the kernels run."""
        k = len(mass)
        if k == 0:
            return
        if not jit.active():
            if len(picks):
                s, t = s.take(picks), t.take(picks)
            self._append_at_rest(s, t, mass, radius)
            return
        n = self._n
        self._reserve(n + k)
        kernels.append_at_rest(self._buf, self._fresh_buf, n, s, t, picks, mass, radius)
        self._dirty = True
        self._n = n + k
        self.changed()

    def _new_rows(self, mass: np.ndarray, radius: np.ndarray | None) -> np.ndarray | None:
        """Rows for len(mass) new drops (mass, radius, a fresh trail, unplaced), their position and velocity
        left to the caller; None when there are none."""
        k = len(mass)
        if k == 0:
            return None
        n = self._n
        self._reserve(n + k)
        rows = self._buf[n : n + k]
        rows[:, _M] = mass
        rows[:, _TRAIL] = 0.0
        rows[:, _A] = drop_radius(mass) if radius is None else radius
        rows[:, _KEY] = _DIRTY  # the position's columns are written before they are read (_flush_placed)
        rows[:, _RB] = np.inf
        self._dirty = True
        self._fresh_buf[n : n + k] = True
        self._n = n + k
        self.changed()
        return rows

    def _bead_drops(self, u: np.ndarray, v: np.ndarray, m: np.ndarray) -> None:
        """film.FilmBeading._bead_drops: GlassGeometry.from_uv on columns (the same operations)."""
        t = v * self._height
        self._append_at_rest((u - 0.5) * (self._w0 + self._dw * t), t, m)

    def _keep(self, keep: np.ndarray) -> None:
        n = self._n
        self.changed()
        if jit.active():
            self._n = kernels.compact_rows(self._buf, self._fresh_buf, n, ~keep)
            return
        first = int(keep.argmin())  # the rows before the first one removed stay where they are
        if keep[first]:
            return
        tail = keep[first:]
        rows = self._rows[first:n][tail]
        fresh = self._fresh_buf[first:n][tail]
        k = first + len(rows)
        self._rows[first:k] = rows
        self._fresh_buf[first:k] = fresh
        self._n = k

    def _flush_placed(self) -> None:
        """Write the position's columns (``_placed``) of the drops placed since they were last written (their KEY
        is drop_rows.DIRTY): the same values, computed once a step for all of them."""
        self._dirty = False
        if jit.active():
            kernels.place_rows(self._buf, self._n, self._w0, self._dw, self._height, self._g_up, self._g_sag)
            return
        d = self._buf[: self._n]
        idx = (d[:, _KEY] == _DIRTY).nonzero()[0]
        if len(idx):
            st = d[idx, _S : _T + 1]
            d[idx, _PLACED] = self._placed(st[:, 0], st[:, 1], st)

    def _sort_drops(self) -> None:
        """Keep the drops in merge-grid cell order (grid.grid_keys), as the reference does."""
        n = self._n
        compiled = jit.active() and n >= 2  # (the kernel places the dirty rows as it reads the keys)
        if self._dirty and not compiled:
            self._flush_placed()
        if self._ks is not None:
            self._ks.rows32_of = -1  # (a later sub-step moves drops without a new version)
        if n < 2:
            return
        if compiled:
            ks = self._scratch()
            place, self._dirty = self._dirty, False
            if kernels.sort_rows(self._buf, self._fresh_buf, n, ks.hist, ks.order, ks.tmp, ks.tmp_fresh,
                                 ks.rows32, place, self._w0, self._dw, self._height, self._g_up,
                                 self._g_sag) == 2:
                # The sorted rows are in the scratch: it becomes the drop array, the old array the scratch.
                self._buf, ks.tmp = ks.tmp, self._buf
                self._fresh_buf, ks.tmp_fresh = ks.tmp_fresh, self._fresh_buf
                self._rows = self._buf.view(_ROW).ravel()
                ks.rows32_of = self.version  # what changes the drops from here on counts a new version
            return
        keys = self._buf[:n, _KEY]
        if not np.count_nonzero(keys[1:] < keys[:-1]):
            return
        order = keys.argsort(kind="stable")
        # Only the span of rows that change places is rewritten.
        moved = (order != np.arange(n)).nonzero()[0]
        lo, hi = int(moved[0]), int(moved[-1]) + 1
        order = order[lo:hi]
        self._rows[lo:hi] = self._rows.take(order)
        self._fresh_buf[lo:hi] = self._fresh_buf.take(order)
