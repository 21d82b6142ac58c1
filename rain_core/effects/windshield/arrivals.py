"""Sampling raindrop arrivals on the glass without a search (the fast path, ``sim.WindshieldSim``): the
flux-weighted size law of one rain rate and glass motion as a bucket table over its cumulative distribution, so a
sample is a gather instead of ``np.interp``'s binary search; only the far tail searches. The bucket table is built
only when it repays itself: for a large sample, or when the same law is sampled again (a steady speed). The law
changes nearly every frame while the car accelerates, and one frame's sample of ~2,000 searches the 512-point CDF
about as fast as the table is built and then used."""

from __future__ import annotations

import numpy as np

from rain_core.effects.windshield.reference import _D_GRID_MM

_CDF_BUCKETS = 2048  # (4096 samples no faster and take ~30 % longer to build)
_TABLE_FROM = 4096  # samples at least this large use the bucket table; smaller ones search (the same intervals)


class ArrivalTable:
    """The flux-weighted size law of one rain rate and glass motion, ready to sample without a search: the
    reference's (closing speed, CDF) over the diameter grid, the slopes ``np.interp`` would use, and for each of
    _CDF_BUCKETS equal slices of the CDF the first grid interval it meets (built on the first large sample)."""

    def __init__(self, closing: np.ndarray, cdf: np.ndarray):
        self.total = float(cdf[-1])
        self.cdf = cdf
        with np.errstate(divide="ignore", invalid="ignore"):
            self.d_slope = np.diff(_D_GRID_MM) / np.diff(cdf)  # inf on flat stretches: never selected
        self.c_slope = np.diff(closing) / np.diff(_D_GRID_MM)
        self.closing = closing
        # What _interpolate reads of interval j, as one row: one gather instead of six.
        self._coef = np.stack([self.d_slope, cdf[:-1], _D_GRID_MM[:-1], self.c_slope, closing[:-1]], axis=1)
        self.first = None
        self._searched = False  # a sample searched already: the next one builds the table

    @classmethod
    def from_law(cls, closing: np.ndarray, cdf: np.ndarray, coef: np.ndarray) -> ArrivalTable:
        """The table of (closing, cdf) whose interpolation rows ``coef`` (``_coef``'s) were made elsewhere (the
        windshield's ``kernels.arrival_law``, the same operations as ``__init__``)."""
        table = cls.__new__(cls)
        table.total = float(cdf[-1])
        table.cdf = cdf
        table.d_slope = coef[:, 0]
        table.c_slope = coef[:, 3]
        table.closing = closing
        table._coef = coef
        table.first = None
        table._searched = False
        return table

    def _build_buckets(self) -> None:
        cdf = self.cdf
        edges = np.arange(_CDF_BUCKETS + 1) * (self.total / _CDF_BUCKETS)
        # np.searchsorted(cdf, edges, "right") - 1, counted from the other side: the CDF's few hundred points are
        # searched among the edges (cdf ≤ edge k ⟺ the first edge ≥ that point is at most k).
        at = np.searchsorted(edges, cdf, "left")
        j = np.cumsum(np.bincount(at, minlength=_CDF_BUCKETS + 2)[: _CDF_BUCKETS + 1]) - 1
        self.first = np.minimum(np.maximum(j[:-1] - 1, 0), len(cdf) - 2)  # one interval of slack for rounding
        self.span = j[1:] - self.first  # intervals a bucket may need to step over
        self.steps = int(min(self.span.max(), 3))
        self.cdf_next = np.append(cdf[1:], np.inf)

    def sample(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Diameters (mm) at the CDF quantiles ``u`` ∈ [0, 1) (as np.interp on the CDF gives them), and their
        closing speeds (m/s)."""
        x = u * self.total
        if self.first is None:
            if len(u) < _TABLE_FROM and not self._searched:
                self._searched = True
                j = self.cdf.searchsorted(x, "right") - 1  # the interval the bucket walk below finds
                return self._interpolate(j, x)
            self._build_buckets()
        k = np.minimum((u * _CDF_BUCKETS).astype(np.int64), _CDF_BUCKETS - 1)
        j = self.first[k]
        for _ in range(self.steps):
            j += x >= self.cdf_next[j]
        wide = self.span[k] > self.steps
        if np.count_nonzero(wide):  # the far tail of the law, where one bucket spans many grid intervals
            j[wide] = self.cdf.searchsorted(x[wide], "right") - 1
        return self._interpolate(j, x)

    def _interpolate(self, j: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        np.minimum(j, len(self.cdf) - 2, out=j)
        r = self._coef.take(j, axis=0)  # d_slope, cdf, D, c_slope, closing of each sample's interval
        d_j = r[:, 2]
        d = x - r[:, 1]
        d *= r[:, 0]
        d += d_j
        closing = d - d_j
        closing *= r[:, 3]
        closing += r[:, 4]
        return d, closing
