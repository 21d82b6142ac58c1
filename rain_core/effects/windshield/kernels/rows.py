"""Kernels of the drop array's bookkeeping: appending, removing, shedding and sorting rows (``drop_array``'s
twins). Units: m, kg."""

from __future__ import annotations

from rain_core import jit
from rain_core.effects.windshield.constants import (
    M_OBJECT_MIN,
)
from rain_core.effects.windshield.drop_rows import DIRTY as _DIRTY
from rain_core.effects.windshield.drop_rows import KEY, RB, TRAIL, VS, VT, A, M, S, T
from rain_core.effects.windshield.kernels.common import _INF, film_cell, inside
from rain_core.effects.windshield.kernels.motion import place_row


@jit.kernel
def append_at_rest(buf, fresh, n, s, t, picks, mass, radius):
    """``DropArray._append_at_rest``: drops at rest at (s, t) m, of masses ``mass`` (kg) and radii ``radius`` (m),
    as rows [n, n + len(mass)) of ``buf`` (its capacity reserved by the caller): a fresh trail, unplaced (KEY
    DIRTY), to be tested, fresh. Drop j is at point ``picks[j]`` of the columns ``s``, ``t`` (the arrivals'), or
    with ``picks`` empty at point j. One pass instead of a gather and a strided write per column."""
    for j in range(len(mass)):
        q = picks[j] if len(picks) else j
        i = n + j
        buf[i, S] = s[q]
        buf[i, T] = t[q]
        buf[i, VS] = 0.0
        buf[i, VT] = 0.0
        buf[i, M] = mass[j]
        buf[i, TRAIL] = 0.0
        buf[i, A] = radius[j]
        buf[i, KEY] = _DIRTY
        buf[i, RB] = _INF
        fresh[i] = True


@jit.kernel
def compact_rows(buf, fresh, n, drop):
    """``DropArray._keep``: remove the rows [:n] marked in ``drop`` (bool), the others keeping their order (and
    their ``fresh`` flag); returns the new count."""
    k = 0
    for i in range(n):
        if drop[i]:
            continue
        if k != i:
            buf[k] = buf[i]
            fresh[k] = fresh[i]
        k += 1
    return k


@jit.kernel
def shed_rows(buf, fresh, n, test_all, gone, flat, w0, dw, height, drop, shed_m, sensor, s_lo, s_hi, t_lo, t_hi,
              sensor_m):
    """``WindshieldSim._shed_outside``: of rows [:n], those off the glass (every one if ``test_all``, else those
    placed this sub-step: KEY DIRTY) are shed (their masses, kg, in row order into ``shed_m``), those below half
    the object size become film (``flat``, kg per cell) where they are, and the rows ``gone`` (joined into others
    by the merge) go too: one compaction (``compact_rows``'). ``drop``: bool scratch over the rows. On its way over
    the rows kept, the compaction takes what the next steps of the sub-step would read in passes of their own: with
    ``sensor``, the masses of those inside the rain sensor's box (``sensor_masses``' test, bounds in m) in row order
    into ``sensor_m``, and their largest radius (m; 0 when none is kept). Returns (new count, shed, masses in the
    sensor, largest radius)."""
    for i in range(n):
        drop[i] = False
    for g in gone:
        drop[g] = True
    # One pass: each row is shed, turned to film, or kept (the shed masses and the film's additions each in row
    # order, as the twin's separate passes make them).
    n_shed = 0
    k = 0
    n_sensor = 0
    a_max = 0.0
    for i in range(n):
        if drop[i]:
            continue
        if (test_all or buf[i, KEY] == _DIRTY) and not inside(buf[i, S], buf[i, T], w0, dw, height):
            shed_m[n_shed] = buf[i, M]
            n_shed += 1
            continue
        if buf[i, M] < 0.5 * M_OBJECT_MIN:
            flat[film_cell(buf[i, S], buf[i, T], w0, dw, height)] += buf[i, M]
            continue
        if k != i:
            buf[k] = buf[i]
            fresh[k] = fresh[i]
        a = buf[k, A]
        if k == 0 or a > a_max:
            a_max = a
        if sensor:
            s = buf[k, S]
            t = buf[k, T]
            if s >= s_lo and s <= s_hi and t >= t_lo and t <= t_hi:
                sensor_m[n_sensor] = buf[k, M]
                n_sensor += 1
        k += 1
    return k, n_shed, n_sensor, a_max


@jit.kernel
def _counts_to_starts(hist):
    """A histogram's counts → each bin's first position (exclusive prefix sums, in place)."""
    at = 0
    for b in range(hist.shape[0]):
        c = hist[b]
        hist[b] = at
        at += c


@jit.kernel
def sort_rows(buf, fresh, n, hist, order, tmp, tmp_fresh, rows32, place, w0, dw, height, g_up, g_sag):
    """``DropArray._sort_drops`` (after the position columns are written): rows [:n] in stable order of their
    merge-grid KEY (integers below 2^18: two 9-bit passes of a radix sort), only the span of rows that change
    places rewritten. ``hist``: int64 scratch of 512, ``order`` int64 scratch of 4n, ``tmp`` (rows) and
    ``tmp_fresh`` scratch of the shapes of ``buf`` and ``fresh``. Returns 0 (in order already), 1 (sorted in
    place) or 2 (most rows move: the sorted rows [:n] are in ``tmp`` and ``tmp_fresh``, for the caller to swap
    with ``buf`` and ``fresh``: one pass over the rows instead of two; that pass also writes the sorted drops'
    float32 rows s, t, vs, vt, radius into ``rows32``, (≥ n, 5): ``splats.DropRows`` reads them instead of the
    array, whose rows are cold in the cache by the time the effect asks). With ``place``, the rows whose KEY is
    DIRTY are placed first (``place_row``; the glass's ``w0`` … ``g_sag`` as ``place_rows`` takes them), in the
    pass that reads the keys: ``_flush_placed``'s pass folded into this one."""
    keys = order[2 * n : 3 * n]
    keys2 = order[3 * n : 4 * n]
    src = order[:n]
    dst = order[n : 2 * n]
    ordered = True
    for i in range(n):
        if place and buf[i, KEY] == _DIRTY:
            place_row(buf, i, w0, dw, height, g_up, g_sag)
        keys[i] = int(buf[i, KEY])
        if i and keys[i] < keys[i - 1]:
            ordered = False
    if ordered:
        return 0
    # Pass 1: by the low 9 bits, from row order (stable).
    hist[:] = 0
    for i in range(n):
        hist[keys[i] & 511] += 1
    _counts_to_starts(hist)
    for i in range(n):
        b = keys[i] & 511
        dst[hist[b]] = i
        keys2[hist[b]] = keys[i]
        hist[b] += 1
    # Pass 2: by the high bits, keeping pass 1's order within each.
    hist[:] = 0
    for i in range(n):
        hist[keys2[i] >> 9] += 1
    _counts_to_starts(hist)
    for i in range(n):
        b = keys2[i] >> 9
        src[hist[b]] = dst[i]
        hist[b] += 1
    lo = 0
    while src[lo] == lo:
        lo += 1
    hi = n
    while src[hi - 1] == hi - 1:
        hi -= 1
    cols = buf.shape[1]
    # Most rows move: all of them are written in order into tmp once, and the caller swaps the arrays.
    if 2 * (hi - lo) > n:
        for j in range(n):
            r = src[j]
            for c in range(cols):
                tmp[j, c] = buf[r, c]
            tmp_fresh[j] = fresh[r]
            for c in range(4):  # S … VT: adjacent columns (drop_rows)
                rows32[j, c] = buf[r, S + c]
            rows32[j, 4] = buf[r, A]
        return 2
    for j in range(lo, hi):
        r = src[j]
        for c in range(cols):
            tmp[j, c] = buf[r, c]
        tmp_fresh[j] = fresh[r]
    for j in range(lo, hi):
        for c in range(cols):
            buf[j, c] = tmp[j, c]
        fresh[j] = tmp_fresh[j]
    return 1

