"""Where the ripple field's water is: the solver's water mask kept on the road's film-depth function as the
window scrolls (only the cells that enter are asked, a band of rows is renewed each frame), and the water
fraction that sizes the raindrop candidates, counted on a lattice of rows.

``WaterFollowing`` is a part of ``RippleField`` (field.py), which holds the state it reads: the solver, the
window's anchor and size, the unknown rows and columns, the rows' water counts."""

from __future__ import annotations

import math

import numpy as np

from rain_core.effects.ripples.scroll import shift_line
from rain_core.effects.ripples.wheels import FilmDepthFn

# The water fraction that sizes the candidates is counted on every RAIN_FRACTION_STRIDE-th row and column.
RAIN_FRACTION_STRIDE = 4


def _runs(index: np.ndarray):
    """(start, stop) of each run of consecutive values in a sorted index array without repeats."""
    if index.size == 0:
        return []
    first, last = int(index[0]), int(index[-1])
    if last - first + 1 == index.size:  # one run (the strip that scrolled in, every column): no scan
        return [(first, last + 1)]
    breaks = (index[1:] - index[:-1] != 1).nonzero()[0] + 1  # array methods: NumPy's wrappers cost more here
    starts = np.concatenate([[0], breaks])
    stops = np.concatenate([breaks, [index.size]])
    return [(int(index[a]), int(index[b - 1]) + 1) for a, b in zip(starts, stops, strict=True)]


def _grid_view(line: np.ndarray, shape: tuple[int, int], axis: int) -> np.ndarray:
    """A read-only (rows, cols) view of ``line`` (fresh, contiguous float64) repeated along the other axis:
    ``np.broadcast_to``'s array (stride 0 across the repeats) without its Python-level checks."""
    strides = (0, line.itemsize) if axis == 1 else (line.itemsize, 0)
    view = np.ndarray(shape, np.float64, line, 0, strides)
    view.flags.writeable = False
    return view


class WaterFollowing:
    """The water-mask upkeep of ``RippleField`` (see the module docstring)."""

    def set_water_mask(self, mask):
        """(n, n) bool, or film depth in mm (> 0: water), indexed [iz, ix] over the window; None: all water.
        Replaces any film-depth function given to ``update``."""
        self._film_fn = None
        self._film_key = None
        self._following = False
        self._set_mask(mask)

    def _set_mask(self, mask):
        self.solver.set_water_mask(mask)
        self._row_water = None
        self._water_fraction_stale = True
        self.version += 1

    def refresh_water_mask(self, film_depth_fn: FilmDepthFn):
        """Evaluate film_depth_fn(x_m, z_m) -> depth in mm (vectorised over arrays of world positions in m) at
        every cell now, hold the cells without water at rest, and keep following the function: after a
        scroll only the cells that enter are asked, and ``update`` re-asks a band of rows each frame so the
        whole window is renewed every ``mask_refresh_s`` (puddles fill and dry over seconds; one full
        evaluation of the road's film depth at 512² costs tens of ms). A function with a hashable
        ``cache_key`` attribute promises that functions with equal keys give equal depths: once every row has
        been asked under the current key, the bands stop until the key changes (only scrolled-in strips are
        asked); without one the bands roll on every frame."""
        self._film_fn = film_depth_fn
        self._film_key = getattr(film_depth_fn, "cache_key", None)
        self._rows_to_renew = 0
        self._following = True
        self._unknown_rows[:] = True
        self._unknown_cols[:] = True
        self._fill_unknown_depths()

    def _ask_depths(self, rows, cols, extra_xz=None) -> tuple[np.ndarray, np.ndarray | None]:
        """(depths of the cells rows × cols, depths at the extra world points (k, 2) m or None), in mm: the cells
        asked as a grid, the extra points (the wheels') by a call of their own; only the cells' depths are checked
        (the wheels clamp theirs)."""
        # Positions from the world lattice index (anchor + cell): a lattice point gets the same coordinates,
        # hence the same depth, whichever window asks about it (so strips asked after scrolls agree exactly
        # with a full evaluation).
        ax, az = self._anchor
        shape = (len(rows), len(cols))
        # meshgrid's values as read-only views of one row of x and one column of z: a film-depth function sees
        # (rows, cols) arrays as before, and the road's sampler spots the grid and samples each row's and each
        # column's part once (water_film._standing_on_grid: the same depths, a third of the cost).
        if cols is self._all_cols:  # the strips along z: every column, whose x changes only with the anchor's
            if self._all_cols_x[0] != ax:
                self._all_cols_x = (ax, (ax + self._all_cols) * self.cell_m)
            x_line = self._all_cols_x[1]
        else:
            x_line = (ax + np.asarray(cols)) * self.cell_m
        xs = _grid_view(x_line, shape, 1)
        zs = _grid_view((az + np.asarray(rows)) * self.cell_m, shape, 0)
        depth = np.asarray(self._film_fn(xs, zs), dtype=np.float64)
        if depth.shape != shape:  # e.g. a constant depth
            depth = np.broadcast_to(depth, shape)
        extra = None
        if extra_xz is not None:
            extra = np.asarray(self._film_fn(extra_xz[:, 0], extra_xz[:, 1]), dtype=np.float64)
            if extra.shape != (len(extra_xz),):
                extra = np.broadcast_to(extra, (len(extra_xz),))
        # Two reductions: a NaN makes min() NaN (not >= 0), +inf is the max, -inf below 0.
        if not depth.min() >= 0.0 or depth.max() == math.inf:
            raise ValueError("film_depth_fn must return finite depths >= 0 mm")
        return depth, extra

    def _fill_unknown_depths(self, extra_rows=None, extra_xz=None) -> np.ndarray | None:
        """Ask the film-depth function about the rows and columns not known yet (after a scroll, whole strips)
        and about extra_rows, in at most two calls, and update the mask over what was asked. ``extra_xz``
        ((k, 2) world m, the wheels' points) rides along with the first call; returns their depths (mm), None
        when nothing was asked."""
        rows = self._unknown_rows.nonzero()[0]
        if extra_rows is not None and len(extra_rows):
            rows = np.union1d(rows, extra_rows)
        cols = self._unknown_cols.nonzero()[0]
        if rows.size == 0 and cols.size == 0:
            return None
        asked = None
        blocks = []
        if rows.size:
            depth, asked = self._ask_depths(rows, self._all_cols, extra_xz)
            if rows.size == self.n and self.solver.water_mask is None:  # the first full evaluation
                self._unknown_rows[:] = False
                self._unknown_cols[:] = False
                self._set_mask(depth > 0.0)
                return asked
            self._changed_blocks(blocks, rows, self._all_cols, depth > 0.0)
        if cols.size:  # the columns' cells outside the rows just asked (all of them when no rows were)
            others = np.ones(self.n, bool)
            others[rows] = False
            others = others.nonzero()[0]
            if others.size:
                depth, extra = self._ask_depths(others, cols, None if rows.size else extra_xz)
                self._changed_blocks(blocks, others, cols, depth > 0.0)
                asked = asked if rows.size else extra
        self._unknown_rows[:] = False
        self._unknown_cols[:] = False
        if blocks:
            self.solver.set_water_mask_blocks(blocks)
            if self._row_water is not None:
                for row0, _, block in blocks:
                    self._count_row_water(row0, row0 + block.shape[0])
            self._water_fraction_stale = True
            self.version += 1
        return asked

    def _changed_blocks(self, blocks: list, rows: np.ndarray, cols: np.ndarray, water: np.ndarray):
        """Append to ``blocks`` the (row0, col0, block) of each run of ``rows`` × run of ``cols`` (sorted cell
        indices; ``water`` (len(rows), len(cols)) bool) where the solver's mask differs: the rest of the mask
        already matches the depths."""
        current = self.solver.water_mask  # exactly 0 or 1: compared with the bools as they are
        row_runs, col_runs = _runs(rows), _runs(cols)
        p = 0
        for r0, r1 in row_runs:
            q = 0
            for c0, c1 in col_runs:
                block = water[p:p + r1 - r0, q:q + c1 - c0]
                if current is None or not (block == current[r0:r1, c0:c1]).all():
                    blocks.append((r0, c0, block))
                q += c1 - c0
            p += r1 - r0

    def _refresh_depth_band(self, dt: float, extra_xz=None) -> tuple[int, np.ndarray | None]:
        """Re-ask the film depth of the next band of rows (the whole window every mask_refresh_s), together
        with any cells that scrolled in (and ``extra_xz``, as ``_fill_unknown_depths``). Returns the rows of the
        band and the extra points' depths."""
        if self.mask_refresh_s == 0.0:
            rows = np.arange(self.n)
        else:
            start = int(self._refresh_row)
            self._refresh_row += self.n * dt / self.mask_refresh_s
            stop = min(int(self._refresh_row), start + self.n)
            rows = np.arange(start, max(stop, start)) % self.n
            self._refresh_row %= self.n
        return rows.size, self._fill_unknown_depths(rows, extra_xz)

    def _count_water(self, stride: int = 1) -> tuple[int, int]:
        """(water cells, cells) among the interior cells on every ``stride``-th row and column (the fixed edges
        take no drops)."""
        mask = self.solver.water_mask
        inner = slice(1, self.n - 1, stride)
        cells = len(range(1, self.n - 1, stride)) ** 2
        if mask is None:
            return cells, cells
        if stride == RAIN_FRACTION_STRIDE:  # the rain's lattice: from the rows' counts
            if self._row_water is None:
                self._row_water = np.zeros(self.n, np.int64)
                self._count_row_water(0, self.n)
            return int(self._row_water[inner].sum()), cells
        view = mask[inner, inner]
        if view.dtype == bool:
            return int(np.count_nonzero(view)), cells
        # The mask holds exactly 0 or 1: a float sum of at most 512² ones is exact (and on a strided float view
        # several times cheaper than count_nonzero).
        return int(view.sum()), cells

    def _scroll_row_water(self, dx: int, dz: int) -> None:
        """Scroll the rows' counts with the mask (``shifted``'s rows; the entering rows are water everywhere, as
        the mask's); a lateral scroll moves the lattice's columns: count afresh."""
        if dx or abs(dz) >= self.n:
            self._row_water = None
        else:  # the entering rows: a row of water on the lattice's columns
            shift_line(self._row_water, dz, len(range(1, self.n - 1, RAIN_FRACTION_STRIDE)))

    def _count_row_water(self, row0: int, row1: int) -> None:
        """Count the water of mask rows row0 … row1 − 1 on the lattice's columns into ``_row_water``."""
        lattice = slice(1, self.n - 1, RAIN_FRACTION_STRIDE)
        # The mask holds exactly 0 or 1 (bool or float): its sums are the water cells (exact, cast to int64).
        self._row_water[row0:row1] = self.solver.water_mask[row0:row1, lattice].sum(axis=1)

    def _rain_water_fraction(self) -> float:
        """The window's water fraction, counted on a lattice of every RAIN_FRACTION_STRIDE-th cell once per frame
        that rains after the mask or the window moved (it only sizes the raindrop candidates); 0 only when no
        interior cell at all holds water."""
        if self._water_fraction_stale:
            self._water_fraction_stale = False
            water, cells = self._count_water(RAIN_FRACTION_STRIDE)
            if water == 0:
                water, cells = self._count_water()
            self._water_fraction = water / cells if cells else 0.0
        return self._water_fraction
