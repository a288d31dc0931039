"""The cutting plan of pieces on stock bars (one-dimensional cutting stock): :func:`cutting_plan`.

A bar of stock length ``S`` holding pieces ``l_1 .. l_k`` (in the order they are sawn) uses

    ``used = end_trim + l_1 + kerf + l_2 + ... + kerf + l_k + end_trim``
    ``     = sum(l) + (k - 1) kerf + 2 end_trim <= S``

(``end_trim``: what is sawn off each mill end to square it, its saw cut included; ``kerf``: the saw
blade between two pieces).  ``offcut = S - used``: what is left at the far end of the bar (the cut that
frees the last piece comes out of it).

Per section and grade: first-fit decreasing on bars of each stock length that holds every piece, each
bar then shortened to the shortest stock length that holds its pieces; the plan buying the least length
is kept (fewest bars on a tie).  A piece longer than the longest stock bar less its two trims is never
put on a bar: it goes to a bar ``splice needed`` of its own.  The files: :mod:`fabricate.export.bars`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

BARS = {"stock_lengths_mm": (6000.0, 12000.0), "kerf_mm": 3.0, "end_trim_mm": 10.0}
"""Stock bars when the config does not say (``outputs.bars``): EN 10219 / EN 10210 hollow sections are
sold in 6 m and 12 m lengths; a band saw's kerf; 10 mm squared off each mill end."""
SPLICE = "splice needed"
"""The bar of a piece longer than the longest stock bar: a shop splices it (a full-strength butt weld)
or the design shortens it."""

@dataclass(frozen=True)
class Piece:
    """One piece sawn from a bar: part ``id``, ``section`` text, ``grade``, ``length`` mm (as the cut list
    writes it, to 0.1 mm), ``kg_per_m`` of its section."""

    id: str
    section: str
    grade: str
    length: float
    kg_per_m: float = 0.0


@dataclass(frozen=True)
class Bar:
    """One stock bar and its pieces in the order they are sawn; ``stock`` None: ``splice needed``."""

    id: str
    section: str
    grade: str
    stock: float | None
    pieces: tuple[Piece, ...]
    kerf: float
    trim: float

    @property
    def used(self) -> float:
        """mm: pieces, the kerfs between them and the two end trims."""
        k = len(self.pieces)
        return sum(p.length for p in self.pieces) + max(k - 1, 0) * self.kerf + 2 * self.trim

    @property
    def offcut(self) -> float:
        return math.nan if self.stock is None else self.stock - self.used


@dataclass(frozen=True)
class Plan:
    """The cutting plan: every bar (splices last), the settings it was made with."""

    bars: tuple[Bar, ...]
    stock_lengths: tuple[float, ...]
    kerf: float
    trim: float

    def bar_of(self) -> dict[str, str]:
        """Part id -> the bar it is sawn from (``splice needed`` for a piece too long)."""
        return {p.id: b.id for b in self.bars for p in b.pieces}

    @property
    def splices(self) -> list[Piece]:
        return [p for b in self.bars if b.stock is None for p in b.pieces]


def options(bars: dict | None) -> tuple[tuple[float, ...], float, float]:
    """``(stock lengths ascending, kerf, end trim)`` of an ``outputs.bars`` mapping (None: :data:`BARS`)."""
    o = {**BARS, **{k: v for k, v in (bars or {}).items() if v is not None}}
    stocks = tuple(sorted({float(s) for s in o["stock_lengths_mm"]}))
    kerf, trim = float(o["kerf_mm"]), float(o["end_trim_mm"])
    if not stocks or stocks[0] <= 0 or kerf < 0 or trim < 0 or 2 * trim >= stocks[-1]:
        raise ValueError(f"outputs.bars = {o!r}: expected stock lengths > 0 mm longer than two end trims, "
                         "kerf and trim >= 0")
    return stocks, kerf, trim


def _ffd(pieces: list[Piece], stock: float, kerf: float, trim: float) -> list[list[Piece]]:
    """First-fit decreasing of ``pieces`` (longest first) on bars of length ``stock``."""
    room: list[float] = []                       # what each bar still holds, a kerf counted per piece
    bins: list[list[Piece]] = []
    live: list[int] = []                         # the bars that still hold the shortest piece, in order
    cap = stock - 2 * trim + kerf
    least = pieces[-1].length + kerf if pieces else 0.0
    for p in pieces:  # first fit: the first bar with room
        need = p.length + kerf
        at = next((k for k, j in enumerate(live) if need <= room[j] + 1e-9), None)
        if at is None:
            room.append(cap - need)
            bins.append([p])
            live.append(len(bins) - 1)
            at = len(live) - 1
        else:
            room[live[at]] -= need
            bins[live[at]].append(p)
        if room[live[at]] + 1e-9 < least:        # full: no piece left fits it
            del live[at]
    return bins


def _shortest(content: list[Piece], stocks: tuple[float, ...], kerf: float, trim: float) -> float:
    need = sum(p.length for p in content) + (len(content) - 1) * kerf + 2 * trim
    return next(s for s in stocks if need <= s + 1e-9)


def cutting_plan(pieces, bars: dict | None = None) -> Plan:
    """The cutting plan of ``pieces`` (iterable of :class:`Piece`) on the stock bars ``bars``
    (``outputs.bars``: ``stock_lengths_mm``, ``kerf_mm``, ``end_trim_mm``; None: :data:`BARS`).

    Per section and grade (sorted): pieces longest first; for each stock length that holds every piece
    that fits a bar at all, first-fit decreasing on bars of that length, each bar then cut from the
    shortest stock that holds its pieces; the plan of least bought length is kept (then fewest bars).
    Bars are numbered ``BAR0001`` ... in that order; pieces too long for the longest bar go to
    ``splice needed`` bars (one per piece) after them."""
    stocks, kerf, trim = options(bars)
    groups: dict[tuple[str, str], list[Piece]] = {}
    for p in pieces:
        groups.setdefault((p.section, p.grade), []).append(p)
    out: list[Bar] = []
    too_long: list[Piece] = []
    longest = stocks[-1] - 2 * trim
    for (section, grade) in sorted(groups):  # one plan per section and grade
        todo = sorted(groups[(section, grade)], key=lambda p: (-p.length, p.id))
        too_long += [p for p in todo if p.length > longest + 1e-9]
        fits = [p for p in todo if p.length <= longest + 1e-9]
        if not fits:
            continue
        best = None
        for s in stocks:
            if fits[0].length > s - 2 * trim + 1e-9:
                continue
            bins = _ffd(fits, s, kerf, trim)
            sized = [(_shortest(b, stocks, kerf, trim), b) for b in bins]
            score = (sum(x for x, _ in sized), len(sized))
            if best is None or score < best[0]:
                best = (score, sized)
        for s, content in best[1]:
            out.append(Bar(f"BAR{len(out) + 1:04d}", section, grade, s, tuple(content), kerf, trim))
    out += [Bar(SPLICE, p.section, p.grade, None, (p,), kerf, trim) for p in too_long]
    return Plan(tuple(out), stocks, kerf, trim)
