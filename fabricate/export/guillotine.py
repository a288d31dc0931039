"""rectpack's guillotine packer (best short side fit, short axis split), its loops over free sections in numpy.

:class:`GuillotineBssfSas` places every rectangle exactly where
``rectpack.GuillotineBssfSas`` places it: the same free sections in the same
order, the same choice among them (the first of the best fits, unrotated ones
before rotated ones), the same merging of free sections.  What changes is the
cost of the loops over the free sections, which grow into the thousands on
one drawing strip of ten thousand plates: rectpack evaluates the fitness of
each section twice in generator expressions, merges a new section with every
section through ``Rectangle.join`` (three method calls and six property
lookups per pair) and removes the chosen one by ``list.remove`` (a Python
``__eq__`` per section before it).  Here the coordinates of the sections are
mirrored in a numpy array: the best fit is one ``argmin`` over the fitness of
every section unturned, then turned (the first least: rectpack's tie rule), the
sections a new one touches are found at once and only those go through the join rules, in
list order, and the chosen section is removed by its index (equal sections
never coexist: merging drops a section that another contains).  The mirror is
kept only from ``NUMPY_FROM`` sections on (down to half that; rebuilt when the
list grows again): a sheet of a few sections does not pay for it.  The split
(short axis) is rectpack's ``_split``, inlined.

Imported by :func:`fabricate.export.nesting.pack` only (rectpack stays a
lazy import), for fewer than ``nesting.KERNEL_FROM`` rectangles or without
numba: above, the compiled :mod:`fabricate.export._nest_kernel` applies the
same rules (``tests/test_nesting_kernel.py`` checks the two agree);
``tests/test_cutfiles.py`` compares its placements with rectpack's own class.
"""
from __future__ import annotations

import numpy as np
import rectpack
from rectpack.geometry import Rectangle
from rectpack.pack_algo import PackingAlgorithm

NUMPY_FROM = 48
"""From this many free sections on, the loops run in numpy (below, plain loops are faster)."""


def _column(s) -> tuple:
    """A free section's column of :meth:`GuillotineBssfSas._mirror`."""
    return s.y + s.height, -s.y, s.x + s.width, -s.x, s.width, s.height, s.width, s.height


class GuillotineBssfSas(rectpack.GuillotineBssfSas):
    """``rectpack.GuillotineBssfSas`` over a numpy mirror ``_xywh (8, n)`` of its free sections (same placements)."""

    def reset(self):
        PackingAlgorithm.reset(self)
        self._xywh = np.zeros((8, 64))
        self._synced = False
        self._sections = []
        self._add_section(Rectangle(0, 0, self.width, self.height))

    def _mirror(self) -> np.ndarray:
        """``_xywh[:, :n]``, (8, n) of the n free sections: top y, -y, right x, -x (a box touches the
        sections whose four are >= its y, -top, x, -right), width, height, width, height (those a
        rectangle fits, unturned and turned); rebuilt from them when it was not kept (below
        ``NUMPY_FROM // 2`` sections it is not: the plain loops do not read it)."""
        n = len(self._sections)
        if not self._synced:
            if n > self._xywh.shape[1]:
                self._xywh = np.zeros((8, 2 * n))
            if n:
                self._xywh[:, :n] = np.array([_column(s) for s in self._sections]).T
            self._synced = True
        return self._xywh[:, :n]

    def free_sizes(self) -> np.ndarray:
        """(n, 2) width and height of the n free sections, in list order."""
        if self._synced:
            return self._xywh[4:6, :len(self._sections)].T
        return np.array([(s.width, s.height) for s in self._sections], dtype=float).reshape(-1, 2)

    def _push(self, s) -> None:
        if self._synced:
            n = len(self._sections)
            if n == self._xywh.shape[1]:
                self._xywh = np.concatenate([self._xywh, np.zeros_like(self._xywh)], axis=1)
            self._xywh[:, n] = _column(s)
        self._sections.append(s)

    def _drop(self, idx: list[int]) -> None:
        """Remove the sections at the increasing indices ``idx``."""
        if self._synced:
            n = len(self._sections)
            if n - len(idx) < NUMPY_FROM // 2:
                self._synced = False
            elif len(idx) == 1:
                i = idx[0]
                self._xywh[:, i:n - 1] = self._xywh[:, i + 1:n]
            else:
                keep = np.ones(n, bool)
                keep[idx] = False
                self._xywh[:, :n - len(idx)] = self._xywh[:, :n][:, keep]
        for i in reversed(idx):
            del self._sections[i]

    def _fittest(self, w, h) -> tuple[int | None, bool]:
        """Index of the free section of least fitness ``min(section w - w, section h - h)``, the first such
        in list order, unrotated fits before rotated ones (rectpack's ``min`` over the chained fits).
        A section holds the rectangle exactly where that fitness is >= 0."""
        secs = self._sections
        best, idx, rot = None, None, False
        if len(secs) < NUMPY_FROM:                       # a few sections: a plain loop is faster
            for i, s in enumerate(secs):
                sw, sh = s.width, s.height
                if w <= sw and h <= sh:
                    f = min(sw - w, sh - h)
                    if best is None or f < best:
                        best, idx = f, i
            if self.rot:
                for i, s in enumerate(secs):
                    sw, sh = s.width, s.height
                    if h <= sw and w <= sh:
                        f = min(sw - h, sh - w)
                        if best is None or f < best:
                            best, idx, rot = f, i, True
            return idx, rot
        n = len(secs)
        turns = 2 if self.rot else 1                      # rows: fitness unturned, turned
        D = self._mirror()[4:4 + 2 * turns] - np.array([w, h, h, w][:2 * turns], dtype=float)[:, None]
        F = np.minimum(D[0::2], D[1::2])                  # (turns, n): the first least is rectpack's
        F[F < 0] = np.inf
        j = int(F.argmin())
        if F.flat[j] == np.inf:
            return None, False
        return j % n, j >= n

    def _select_fittest_section(self, w, h):
        idx, rot = self._fittest(w, h)
        return (None, None) if idx is None else (self._sections[idx], rot)

    def add_rect(self, width, height, rid=None):
        assert width > 0 and height > 0
        idx, rotated = self._fittest(width, height)
        if idx is None:
            return None
        if rotated:
            width, height = height, width
        section = self._sections[idx]
        self._drop([idx])
        sx, sy, sw, sh = section.x, section.y, section.width, section.height
        if sw < sh:                                        # rectpack's _split: short axis, horizontal
            if height < sh:
                self._add_section(Rectangle(sx, sy + height, sw, sh - height))
            if width < sw:
                self._add_section(Rectangle(sx + width, sy, sw - width, height))
        else:                                              # vertical
            if height < sh:
                self._add_section(Rectangle(sx, sy + height, width, sh - height))
            if width < sw:
                self._add_section(Rectangle(sx + width, sy, sw - width, sh))
        rect = Rectangle(section.x, section.y, width, height, rid)
        self.rectangles.append(rect)
        return rect

    def _add_section(self, section):
        """Merge ``section`` with the free sections as rectpack does (passes over the list in order until
        one changes nothing; a section it contains is dropped, one containing it or sharing a full edge
        with it is joined into it), then append it.  Only sections touching the current box can join:
        those are found with numpy and go through ``Rectangle.join``'s rules one by one."""
        section.rid = 0
        if self._merge and self._sections:
            x, y, w, h = section.x, section.y, section.width, section.height
            before = -1
            while self._sections and before != len(self._sections):
                before = len(self._sections)
                drop: list[int] = []
                pos = 0
                while pos < before:
                    if before - pos < NUMPY_FROM:              # a few sections: every one through the rules
                        near = range(pos, before)
                    else:
                        box = np.array([y, -(y + h), x, -(x + w)], dtype=float)[:, None]
                        touch = (self._mirror()[:4, pos:] >= box).all(axis=0)
                        near = (touch.nonzero()[0] + pos).tolist()
                    grown = False
                    for t in near:
                        s = self._sections[t]
                        ox, oy, ow, oh = s.x, s.y, s.width, s.height
                        if oy >= y and ox >= x and oy + oh <= y + h and ox + ow <= x + w:
                            drop.append(t)                         # section contains s
                            continue
                        if y > oy + oh or y + h < oy or x > ox + ow or x + w < ox:
                            continue                               # apart, not even touching: kept
                        if y >= oy and x >= ox and y + h <= oy + oh and x + w <= ox + ow:
                            x, y, w, h = ox, oy, ow, oh            # s contains section
                        elif x == ox and w == ow:                  # above or below, same width
                            lo, hi = min(y, oy), max(y + h, oy + oh)
                            y, h = lo, hi - lo
                        elif y == oy and h == oh:                  # left or right, same height
                            lo, hi = min(x, ox), max(x + w, ox + ow)
                            x, w = lo, hi - lo
                        else:
                            continue                               # touching: kept
                        drop.append(t)
                        grown = True                               # the box changed: look again after t
                        pos = t + 1
                        break
                    if not grown:
                        break
                if drop:
                    self._drop(drop)
            section.x, section.y, section.width, section.height = x, y, w, h
        self._push(section)
