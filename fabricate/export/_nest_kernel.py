"""The numba kernel behind :func:`fabricate.export.nesting.pack` (imported only when numba is installed).

:func:`pack_bins` is :func:`~fabricate.export.nesting.pack`'s loop over the rectangles and the bins
together with :class:`~fabricate.export.guillotine.GuillotineBssfSas` (rectpack's guillotine packer,
best short side fit, short axis split, free sections merged), rule for rule, in one compiled call:

- a bin's free sections are the rows ``(x, y, width, height)`` of an int64 array, in rectpack's list
  order (a removed section closes its gap; a new one is appended after merging);
- the fittest section is the first of least ``min(section w - w, section h - h)`` among those holding
  the rectangle unturned, then among those holding it turned only a strictly smaller one wins
  (rectpack's ``min`` over the chained generators);
- the split is rectpack's short axis split (horizontal when the section is narrower than tall);
- a new section is merged as rectpack's ``_add_section`` does: passes over the list in order, each
  dropping the sections it contains or joins (the section growing as it goes: containing one, or
  sharing a full edge with it), until a pass drops none; then it is appended;
- bins: with ``next_fit`` only the last one is asked; otherwise every open bin in the order they were
  opened, skipping those whose largest free width, height, short and long side cannot hold the
  rectangle (a bin that refuses is left unchanged, so the skip changes nothing); a rectangle no open
  bin takes opens a new bin when it fits an empty one (turned if it must be and may), else stays unplaced.

Everything is integer arithmetic: the placements are exactly those of the Python classes.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _copy(src, a, dst, b, k):
    """``dst[b:b + k] = src[a:a + k]`` (rows; an element loop compiles in a fraction of the slice copy's time)."""
    for t in range(k):
        for j in range(4):
            dst[b + t, j] = src[a + t, j]


@njit(cache=True)
def _fittest(S, s0, n, w, h, rot):
    """Index (from ``s0``) of the fittest of the ``n`` free sections ``S[s0:s0 + n]`` for ``w x h`` (-1: none)
    and whether turned."""
    best, idx, turned = 0, -1, False
    for i in range(n):
        sw, sh = S[s0 + i, 2], S[s0 + i, 3]
        if w <= sw and h <= sh:
            f = min(sw - w, sh - h)
            if idx < 0 or f < best:
                best, idx = f, i
    if rot:
        for i in range(n):
            sw, sh = S[s0 + i, 2], S[s0 + i, 3]
            if h <= sw and w <= sh:
                f = min(sw - h, sh - w)
                if idx < 0 or f < best:
                    best, idx, turned = f, i, True
    return idx, turned


@njit(cache=True)
def _add_section(S, s0, n, x, y, w, h):
    """Merge the free section ``(x, y, w, h)`` into the ``n`` sections ``S[s0:s0 + n]`` and append it; the
    new count.  ``S`` has room for ``n + 1`` rows from ``s0``."""
    before = -1
    while n > 0 and before != n:
        before = n
        k = 0
        for t in range(before):
            ox, oy, ow, oh = S[s0 + t, 0], S[s0 + t, 1], S[s0 + t, 2], S[s0 + t, 3]
            joined = False
            if oy >= y and ox >= x and oy + oh <= y + h and ox + ow <= x + w:
                joined = True                                  # the section contains it
            elif not (y > oy + oh or y + h < oy or x > ox + ow or x + w < ox):   # they touch
                if y >= oy and x >= ox and y + h <= oy + oh and x + w <= ox + ow:
                    x, y, w, h = ox, oy, ow, oh                # it contains the section
                    joined = True
                elif x == ox and w == ow:                      # above or below, same width
                    lo, hi = min(y, oy), max(y + h, oy + oh)
                    y, h = lo, hi - lo
                    joined = True
                elif y == oy and h == oh:                      # left or right, same height
                    lo, hi = min(x, ox), max(x + w, ox + ow)
                    x, w = lo, hi - lo
                    joined = True
            if not joined:
                if k != t:
                    S[s0 + k, 0], S[s0 + k, 1], S[s0 + k, 2], S[s0 + k, 3] = ox, oy, ow, oh
                k += 1
        n = k
    S[s0 + n, 0], S[s0 + n, 1], S[s0 + n, 2], S[s0 + n, 3] = x, y, w, h
    return n + 1


@njit(cache=True)
def _add_rect(S, s0, n, w, h, rot):
    """rectpack's ``add_rect`` on the ``n`` free sections ``S[s0:s0 + n]`` (room for ``n + 1`` rows):
    ``(count, x, y, placed width)``, count -1 when no section holds the rectangle."""
    idx, turned = _fittest(S, s0, n, w, h, rot)
    if idx < 0:
        return -1, 0, 0, 0
    if turned:
        w, h = h, w
    i = s0 + idx
    sx, sy, sw, sh = S[i, 0], S[i, 1], S[i, 2], S[i, 3]
    _copy(S, i + 1, S, i, n - 1 - idx)                         # list.remove: the order kept
    n -= 1
    if sw < sh:                                                # short axis: horizontal split
        if h < sh:
            n = _add_section(S, s0, n, sx, sy + h, sw, sh - h)
        if w < sw:
            n = _add_section(S, s0, n, sx + w, sy, sw - w, h)
    else:                                                      # vertical split
        if h < sh:
            n = _add_section(S, s0, n, sx, sy + h, w, sh - h)
        if w < sw:
            n = _add_section(S, s0, n, sx + w, sy, sw - w, sh)
    return n, sx, sy, w


@njit(cache=True)
def _largest(S, s0, n, big, b):
    """Row ``b`` of ``big (bins, 4)``: the largest width, height, short side, long side of the sections."""
    mw, mh, ml, mu = 0, 0, 0, 0
    for i in range(s0, s0 + n):
        sw, sh = S[i, 2], S[i, 3]
        mw, mh = max(mw, sw), max(mh, sh)
        ml, mu = max(ml, min(sw, sh)), max(mu, max(sw, sh))
    big[b, 0], big[b, 1], big[b, 2], big[b, 3] = mw, mh, ml, mu


@njit(cache=True)
def _room(pool, used, start, room, count, c):
    """Room for two more sections in bin ``c``'s rows ``pool[start[c]:start[c] + room[c]]``: grown in place
    when they are the last rows in use, else moved there doubled; the pool (grown when full) and ``used``."""
    if count[c] + 2 <= room[c]:
        return pool, used
    grow = 2 * room[c]
    last = start[c] + room[c] == used
    need = used + (grow - room[c] if last else grow)
    if need > len(pool):
        bigger = np.empty((max(need, 2 * len(pool)), 4), np.int64)
        _copy(pool, 0, bigger, 0, used)
        pool = bigger
    if not last:
        _copy(pool, start[c], pool, used, count[c])
        start[c] = used
    used = start[c] + grow
    room[c] = grow
    return pool, used


@njit(cache=True)
def pack_bins(w, h, order, bw, bh, rot, next_fit):
    """:func:`fabricate.export.nesting.pack` for the rectangles ``w x h`` ((n,) int64) taken in ``order``.

    The free sections of every open bin are rows of one pool (bin ``b``: ``room[b]`` rows from
    ``start[b]``, the first ``count[b]`` in use); with ``next_fit`` a new bin starts the pool afresh.
    Returns ``sheet, x, y, width`` ((n,) int64, -1 where not placed) and -1, or the index of a rectangle
    that an empty bin refused though it fits it (never: the caller raises)."""
    n = len(w)
    sheet = np.full(n, -1, np.int64)
    px, py, pw = np.full(n, -1, np.int64), np.full(n, -1, np.int64), np.full(n, -1, np.int64)
    pool = np.empty((1024, 4), np.int64)
    used = 0
    start, room, count = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, np.int64)  # a bin per
    big = np.zeros((n, 4), np.int64)                                                       # rectangle at most
    bins = 0
    for i in order:
        wi, hi = w[i], h[i]
        lo, up = min(wi, hi), max(wi, hi)
        b, r, x, y, pwi = -1, -1, 0, 0, 0
        for c in range(bins - 1 if next_fit else 0, bins):
            if not next_fit:                                   # can any free section hold it?
                if big[c, 2] < lo or big[c, 3] < up:
                    continue
                if not ((big[c, 0] >= wi and big[c, 1] >= hi) or (rot and big[c, 0] >= hi and big[c, 1] >= wi)):
                    continue
            pool, used = _room(pool, used, start, room, count, c)
            r, x, y, pwi = _add_rect(pool, start[c], count[c], wi, hi, rot)
            if r >= 0:
                b = c
                break
        if r < 0:
            sw, sh = (hi, wi) if rot and (wi > bw or hi > bh) else (wi, hi)
            if sw > bw or sh > bh:                             # fits no bin: unplaced
                continue
            b = bins
            bins += 1
            if next_fit:                                       # the other bins are never asked again
                used = 0
            if used + 16 > len(pool):
                bigger = np.empty((2 * len(pool), 4), np.int64)
                _copy(pool, 0, bigger, 0, used)
                pool = bigger
            start[b], room[b], count[b] = used, 16, 1
            used += 16
            pool[used - 16, 0], pool[used - 16, 1], pool[used - 16, 2], pool[used - 16, 3] = 0, 0, bw, bh
            r, x, y, pwi = _add_rect(pool, start[b], 1, wi, hi, rot)
            if r < 0:
                return sheet, px, py, pw, i
        count[b] = r
        if not next_fit:
            _largest(pool, start[b], r, big, b)
        sheet[i], px[i], py[i], pw[i] = b, x, y, pwi
    return sheet, px, py, pw, -1
