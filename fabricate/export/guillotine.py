"""rectpack's guillotine packer (best short side fit, short axis split), its two inner loops made faster.

:class:`GuillotineBssfSas` places every rectangle exactly where
``rectpack.GuillotineBssfSas`` places it: the same free sections, the same
choice among them (the first of the best fits, unrotated ones before rotated
ones), the same merging of free sections.  What changes is the cost of the
loops over the free sections: rectpack evaluates the fitness of each section
twice in generator expressions and merges sections through
``Rectangle.join`` (three method calls and six property lookups per pair);
here both are plain loops over local numbers.  On the ten thousand plates of
a roof with welded sections those loops were most of the nesting time.

Imported by :func:`fabricate.export.nesting.layout` only (rectpack stays a
lazy import); ``tests/test_cutfiles.py`` compares its placements with
rectpack's own class.
"""
from __future__ import annotations

import rectpack


class GuillotineBssfSas(rectpack.GuillotineBssfSas):
    """``rectpack.GuillotineBssfSas`` with the section choice and merge as plain loops (same placements)."""

    def _select_fittest_section(self, w, h):
        """The free section of least fitness ``min(section w - w, section h - h)``, the first such in
        list order, unrotated fits before rotated ones (rectpack's ``min`` over the chained fits)."""
        best, sec, rot = None, None, False
        secs = self._sections
        for s in secs:
            sw, sh = s.width, s.height
            if w <= sw and h <= sh:
                f = min(sw - w, sh - h)
                if best is None or f < best:
                    best, sec = f, s
        if self.rot:
            for s in secs:
                sw, sh = s.width, s.height
                if h <= sw and w <= sh:
                    f = min(sw - h, sh - w)
                    if best is None or f < best:
                        best, sec, rot = f, s, True
        return (sec, rot) if sec is not None else (None, None)

    def _add_section(self, section):
        """Merge ``section`` with every free section it joins into a rectangle (repeatedly, in list order,
        as ``Rectangle.join`` does: containment either way, or a shared full edge), then append it."""
        section.rid = 0
        secs = self._sections
        if self._merge and secs:
            x, y, w, h = section.x, section.y, section.width, section.height
            before = -1
            while secs and before != len(secs):
                before = len(secs)
                keep = []
                for s in secs:
                    ox, oy, ow, oh = s.x, s.y, s.width, s.height
                    if oy >= y and ox >= x and oy + oh <= y + h and ox + ow <= x + w:
                        continue                                   # section contains s
                    if y >= oy and x >= ox and y + h <= oy + oh and x + w <= ox + ow:
                        x, y, w, h = ox, oy, ow, oh                # s contains section
                        continue
                    if y > oy + oh or y + h < oy or x > ox + ow or x + w < ox:
                        keep.append(s)                             # apart, not even touching
                        continue
                    if x == ox and w == ow:                        # above or below, same width
                        lo, hi = min(y, oy), max(y + h, oy + oh)
                        y, h = lo, hi - lo
                        continue
                    if y == oy and h == oh:                        # left or right, same height
                        lo, hi = min(x, ox), max(x + w, ox + ow)
                        x, w = lo, hi - lo
                        continue
                    keep.append(s)
                secs = keep
            section.x, section.y, section.width, section.height = x, y, w, h
            self._sections = secs
        self._sections.append(section)
