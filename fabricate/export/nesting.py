"""Flat layout of the outlines, nested on stock sheets by ``rectpack`` (guillotine, best short side fit).

Every part is its stock rectangle (``PartGroup.rect``: it holds the whole
part, turned so that the rectangle is axis-aligned and landscape), grown by
the kerf and rounded up to whole millimetres; rectpack (Jukka Jylänki's
guillotine packer, "best short side fit, split along the shorter axis", free
rectangles merged, parts sorted by area, every sheet tried for every part:
``PackingBin.BFF``) puts them on as many sheets as needed, turning
a part by 90 degrees where that fits better when ``rotation`` is allowed.
Guillotine cuts are what a glass cutting table makes; on 1,568 outlines it
packs a strip in 0.16 s where MaxRects took 22 s, to a better yield (0.95
against 0.57).  The
sheet keeps ``margin`` mm free at its edges, the parts ``kerf`` mm between
them.  Yield of a sheet = the parts' cut outline area / sheet area.

Without a sheet the outlines go on one strip about as wide as the square root
of their total rectangle area (a drawing, not a cutting plan), packed the same
way.  Above :data:`FAST_ABOVE` parts a sheet only tries the last open sheet
(``PackingBin.BNF``: linear time, a few more sheets).

From :data:`KERNEL_FROM` rectangles on, with numba installed, :func:`pack` is one compiled call
(:mod:`fabricate.export._nest_kernel`: the guillotine rules and the loop over the sheets, rule for rule,
in integers: the same placements; on the 5,000-panel dome of RHS beams, hubs and insulated glass, 90,800
parts on the strip in 0.19 s against 1.8 s, and the 86,000 of the cut files in 0.02 s against 0.5 s).
The first call compiles it (a few seconds, once: it is cached on disk), a new process loads numba and
the cache (about 0.5 s), hence the threshold; ``CONICAL_FAB_NUMBA=0`` switches it off.  Otherwise (and
in the tests, as the reference beside rectpack's own classes) rectpack's guillotine class runs with its
two inner loops rewritten (:mod:`fabricate.export.guillotine`: the same placements, 2 to 5 times
faster), and rectpack's packer (the loop over the sheets) is
:func:`pack`, placement for placement: the parts in its order, each on the first open sheet that takes
it, else on a new one.  Its fast path: rectpack asks every open sheet in turn (1,980 plies of 6 mm glass
on 1,200 sheets: 113,000 refusals before the sheet that takes each); :func:`pack` keeps per sheet, in
numpy arrays refreshed for the sheet that took the part, the largest sides of its free sections and,
when it has at most :data:`SECTIONS_KEPT` of them, their sizes, and asks only the sheets whose free
sections can hold the part, in the same order (a sheet that cannot take it is left as it was, so
skipping it changes nothing): no refusal at all there.  A layout is computed once per parts object and
arguments (:data:`_LAYOUTS`): the DXF and the SVG of the same outlines draw the same layout, and
rectpack takes seconds on ten thousand plates.  Its arrays are read-only.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from optimize.errors import ConfigError

FAST_ABOVE = 4000
KERNEL_FROM = 2000
"""From this many rectangles on, :func:`pack` runs the compiled kernel (when numba is installed): below,
importing numba and loading the kernel (about 0.5 s) would cost more than it saves."""
_LAYOUTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""``{parts: {arguments: Layout}}``: the layouts made of each (immutable) parts object, while it lives."""


@dataclass(frozen=True)
class Layout:
    """Where every flat part goes.

    ids : (p,) str.  group, index : (p,) which ``PartGroup`` and which part in it.
    sheet : (p,) int.  x, y : (p,) float, mm, lower-left corner of the part's
    bounding rectangle on its sheet.  rotated : (p,) bool, turned 90 degrees
    counter-clockwise.  size : (W, H) of a sheet (mm).  sheets : number of
    sheets.  utilisation : (sheets,) outline area / sheet area (the yield).
    algorithm : name of the packing algorithm.  nested : stock sheets given.
    margin, kerf : mm.  name : the sheet ids' prefix (``GLASS-10``), sheet ids ``GLASS-10-S01`` ...
    """

    ids: tuple[str, ...]
    group: np.ndarray
    index: np.ndarray
    sheet: np.ndarray
    x: np.ndarray
    y: np.ndarray
    rotated: np.ndarray
    size: tuple[float, float]
    sheets: int
    utilisation: np.ndarray
    algorithm: str
    nested: bool
    margin: float = 0.0
    kerf: float = 0.0
    name: str = "S"

    def sheet_id(self, s: int) -> str:
        return f"{self.name}-S{s + 1:02d}"

    def facts(self) -> dict:
        per = [{"id": self.sheet_id(s), "parts": int((self.sheet == s).sum()),
                "yield": round(float(self.utilisation[s]), 4)} for s in range(self.sheets)]
        return {"algorithm": self.algorithm, "nested": self.nested, "sheets": self.sheets,
                "sheet_mm": list(self.size), "margin_mm": self.margin, "kerf_mm": self.kerf, "parts": len(self.ids),
                "utilisation": [round(float(u), 4) for u in self.utilisation],
                "utilisation_mean": float(np.mean(self.utilisation)) if self.sheets else 0.0, "per_sheet": per}


SHEET_KINDS = ("panel", "beam", "node")


def flat_parts(parts, kinds=SHEET_KINDS, thickness: float | None = None):
    """The groups laid flat: those of ``kinds`` cut from sheet (panels, beams and a tube hub's cap plates:
    :func:`fabricate.cad.parts.cut_from_sheet`; a hub tube is ordered as a section), optionally only the
    parts of one thickness (mm)."""
    from fabricate.cad.parts import cut_from_sheet

    out = []
    for gi, g in enumerate(parts.groups):
        if (g.kind in kinds and cut_from_sheet(g.kind, g.member) and len(g)
                and (thickness is None or np.allclose(g.thickness_mm, thickness))):
            out.append((gi, g))
    return out


def layout(parts, sheet: tuple[float, float] | None = None, spacing: float = 10.0, *, kerf: float | None = None,
           rotation: bool = True, kinds=SHEET_KINDS, thickness: float | None = None,
           name: str = "S") -> Layout:
    """Lay the outlines of ``kinds`` flat; nest them on ``sheet = (W, H)`` mm when given.

    spacing : the margin at the sheet edges (mm); kerf : mm between parts (default ``spacing``);
    rotation : parts may turn by 90 degrees; thickness : only parts of this thickness.
    Raises ConfigError naming the part that cannot fit the sheet.
    """
    key = (None if sheet is None else tuple(float(s) for s in sheet), float(spacing),
           None if kerf is None else float(kerf), bool(rotation), tuple(kinds),
           None if thickness is None else float(thickness), name)
    try:
        known = _LAYOUTS.setdefault(parts, {})
    except TypeError:  # not weak-referenceable: no cache
        known = {}
    if key not in known:
        known[key] = _layout(parts, sheet, spacing, kerf, rotation, kinds, thickness, name)
    return known[key]


def _layout(parts, sheet, spacing, kerf, rotation, kinds, thickness, name, algo=None) -> Layout:
    """:func:`layout` without the cache, packed by :func:`pack`; ``algo``: a packing algorithm class
    (``rectpack.GuillotineBssfSas``) to run rectpack's own packer over instead (the same placements)."""
    import rectpack

    margin = float(spacing)
    kerf = margin if kerf is None else float(kerf)
    if margin < 0 or kerf < 0:
        raise ConfigError(f"nesting margin = {margin!r} mm, kerf = {kerf!r} mm: expected numbers >= 0")
    groups = flat_parts(parts, kinds, thickness)
    ids = tuple(i for _, g in groups for i in g.ids)
    gidx = np.concatenate([np.full(len(g), gi) for gi, g in groups]) if groups else np.zeros(0, int)
    pidx = np.concatenate([np.arange(len(g)) for _, g in groups]) if groups else np.zeros(0, int)
    rect = np.concatenate([g.rect for _, g in groups]) if groups else np.zeros((0, 2))
    area = np.concatenate([g.area_mm2 for _, g in groups]) if groups else np.zeros(0)
    w = np.ceil(rect[:, 0] + kerf).astype(np.int64)
    h = np.ceil(rect[:, 1] + kerf).astype(np.int64)
    nested = sheet is not None
    if nested:
        W, H = (float(s) for s in sheet)
        if not (W > 0 and H > 0):
            raise ConfigError(f"nesting sheet = {sheet!r}: expected two positive sizes (mm)")
        bw, bh = int(np.floor(W - 2 * margin + kerf)), int(np.floor(H - 2 * margin + kerf))
        fits = ((w <= bw) & (h <= bh)) | (rotation & (h <= bw) & (w <= bh))
        if not fits.all():
            i = int(np.argmin(fits))
            raise ConfigError(f"nesting: part {ids[i]} ({rect[i, 0]:.1f} x {rect[i, 1]:.1f} mm) does not fit the "
                              f"sheet {W:g} x {H:g} mm with margin {margin:g} mm"
                              f"{'' if rotation else ' (rotation not allowed)'}")
    else:
        strip = float(np.sqrt((w * h).sum())) * 1.1 if len(rect) else 1.0
        bw = int(max(strip, float(w.max()) if len(w) else 1.0))
        bh = int(h.sum()) + 1 if len(h) else 1
        W = bw + 2 * margin - kerf
    fast = len(rect) > FAST_ABOVE
    if algo is None:
        sheet_of, px, py, pw = pack(w, h, bw, bh, rotation, next_fit=fast)
    else:  # rectpack's own packer (the reference the fast path is tested against)
        sheet_of, px, py, pw = _rectpack(w, h, bw, bh, rotation, fast, algo)
    x, y = px + margin, py + margin
    rotated = (pw != w) & (sheet_of >= 0)
    if (sheet_of < 0).any():
        i = int(np.argmin(sheet_of))
        raise ConfigError(f"nesting: part {ids[i]} was not placed on any sheet")
    n_sheets = int(sheet_of.max()) + 1 if len(rect) else 0
    if not nested:
        top = np.where(rotated, rect[:, 0], rect[:, 1]) + y
        H = float(top.max() + margin) if len(rect) else 1.0
    util = np.bincount(sheet_of, weights=area, minlength=n_sheets)[:n_sheets] / (W * H)
    algorithm = (f"rectpack {getattr(rectpack, '__version__', '')} guillotine best short side fit, parts by area, "
                 f"{'next-fit' if fast else 'every open sheet tried'}; rotation "
                 f"{'allowed' if rotation else 'not allowed'}").replace("rectpack  ", "rectpack ")
    for a in (gidx, pidx, sheet_of, x, y, rotated, util):
        a.setflags(write=False)
    return Layout(ids=ids, group=gidx, index=pidx, sheet=sheet_of, x=x, y=y, rotated=rotated,
                  size=(float(W), float(H)), sheets=n_sheets, utilisation=util, algorithm=algorithm,
                  nested=nested, margin=margin, kerf=kerf, name=name)


def _rectpack(w, h, bw, bh, rotation, next_fit, algo):
    """:func:`pack` by rectpack's ``Offline`` packer over the packing class ``algo``."""
    import rectpack

    packer = rectpack.newPacker(mode=rectpack.PackingMode.Offline, rotation=rotation, pack_algo=algo,
                                sort_algo=rectpack.SORT_AREA,
                                bin_algo=rectpack.PackingBin.BNF if next_fit else rectpack.PackingBin.BFF)
    for i in range(len(w)):  # rectpack takes one rectangle per call
        packer.add_rect(int(w[i]), int(h[i]), rid=i)
    packer.add_bin(bw, bh, count=float("inf"))
    packer.pack()
    out = np.full((4, len(w)), -1, dtype=np.int64)
    for b, rx, ry, rw, _, rid in packer.rect_list():  # one placement per part
        out[:, rid] = b, rx, ry, rw
    return out[0], out[1], out[2], out[3]


def pack(w, h, bw: int, bh: int, rotation: bool = True, next_fit: bool = False):
    """Rectangles ``w x h`` ((n,) int) on as many bins ``bw x bh`` as needed: rectpack's ``Offline`` packer
    (``SORT_AREA``, ``PackingBin.BFF``, or ``BNF`` when ``next_fit``, bins without limit) over
    :class:`~fabricate.export.guillotine.GuillotineBssfSas`, placement for placement.

    The rectangles go in rectpack's order (area decreasing, equal areas in input order); each goes into
    the first open bin, in the order they were opened, whose ``add_rect`` takes it (BNF: only the last
    one), else into a new bin (none when it does not fit an empty bin: it stays unplaced).  A bin
    whose free sections cannot hold it is not asked: per bin, ``fit (5, bins)`` holds the largest width,
    height, short side, long side and area of its free sections, refreshed for the bin that took a
    rectangle; the rectangle must fit within all five (turned when ``rotation``) for any section to hold
    it; then ``sec (bins, k, 2)``, the width and height of every free section of a bin with at most
    k = :data:`SECTIONS_KEPT` of them, must show one that holds it (a bin with more is asked).  A bin
    refusing a rectangle is left unchanged, so skipping it changes nothing.

    From :data:`KERNEL_FROM` rectangles on, when numba is installed (:func:`_kernel`), all of this is one
    call of :func:`fabricate.export._nest_kernel.pack_bins` (same placements; its bins are skipped by
    their largest free width, height, short and long side only).

    Returns ``sheet, x, y, width``: (n,) int, the bin of each rectangle, the lower-left corner on it and
    its width there (``!= w`` where it was turned); all four -1 for a rectangle not placed.
    """
    n = len(w)
    kernel = _kernel() if n >= KERNEL_FROM else None
    wa, ha = np.ascontiguousarray(w, np.int64), np.ascontiguousarray(h, np.int64)
    if kernel is not None and (wa > 0).all() and (ha > 0).all():  # else rectpack's assertion, below
        w, h = wa, ha
        order = np.argsort(-(w * h), kind="stable")
        *out, failed = kernel.pack_bins(w, h, order, int(bw), int(bh), bool(rotation), bool(next_fit))
        if failed >= 0:
            raise ConfigError(f"nesting: a {w[failed]} x {h[failed]} rectangle fits no empty {bw} x {bh} bin")
        return tuple(out)
    from .guillotine import GuillotineBssfSas

    sheet = np.full(n, -1, dtype=np.int64)
    x, y, pw = np.full(n, -1, np.int64), np.full(n, -1, np.int64), np.full(n, -1, np.int64)
    bins: list = []
    fit = np.zeros((5, 16))
    sec = np.zeros((16, SECTIONS_KEPT, 2))
    many = np.zeros(16, bool)
    wl, hl = np.asarray(w, np.int64).tolist(), np.asarray(h, np.int64).tolist()
    for i in np.argsort(-(np.asarray(w, np.int64) * np.asarray(h, np.int64)), kind="stable").tolist():
        wi, hi = wl[i], hl[i]
        r, b = None, -1
        if next_fit:
            near = [len(bins) - 1] if bins else []
        elif bins:
            near = _may_take(fit[:, :len(bins)], sec, many, wi, hi, rotation)
        else:
            near = []
        for b in near:
            r = bins[b].add_rect(wi, hi, rid=i)
            if r is not None:
                break
        if r is None:
            sw, sh = (hi, wi) if rotation and (wi > bw or hi > bh) else (wi, hi)
            if sw > bw or sh > bh:  # rectpack opens no bin for it
                continue
            b = len(bins)
            bins.append(GuillotineBssfSas(bw, bh, rot=rotation))
            if b == len(many):
                fit = np.concatenate([fit, np.zeros_like(fit)], axis=1)
                sec, many = (np.concatenate([a, np.zeros_like(a)]) for a in (sec, many))
            r = bins[b].add_rect(wi, hi, rid=i)
            if r is None:
                raise ConfigError(f"nesting: a {wi} x {hi} rectangle fits no empty {bw} x {bh} bin")
        sheet[i], x[i], y[i], pw[i] = b, r.x, r.y, r.width
        if not next_fit:
            _refresh(bins[b], b, fit, sec, many)
    return sheet, x, y, pw


def _kernel():
    """:mod:`fabricate.export._nest_kernel` (numba, imported on first use), or None without numba or when
    the compiled kernels are switched off (:func:`optimize.kernels.load`)."""
    from optimize import kernels

    return kernels.load("fabricate.export._nest_kernel")


SECTIONS_KEPT = 8
""":func:`pack` keeps the sizes of up to this many free sections of a bin (a bin with more is always asked)."""


def _may_take(fit, sec, many, w: int, h: int, rotation: bool) -> list[int]:
    """The bins, in order, that a ``w x h`` rectangle may fit: those passing the five largest sizes
    ``fit (5, bins)``, then among them those with a free section ``sec (bins, k, 2)`` (w, h) that holds
    it or with more than ``k`` sections (``many (bins,)``)."""
    mw, mh, ml, mu, ma = fit
    ok = mw >= w
    ok &= mh >= h
    if rotation:
        ok |= (mw >= h) & (mh >= w)
    lo, up = (w, h) if w <= h else (h, w)
    ok &= ml >= lo
    ok &= mu >= up
    ok &= ma >= w * h
    near = np.flatnonzero(ok)
    if len(near):
        S = sec[near]
        hold = (S[:, :, 0] >= w) & (S[:, :, 1] >= h)
        if rotation:
            hold |= (S[:, :, 0] >= h) & (S[:, :, 1] >= w)
        near = near[hold.any(axis=1) | many[near]]
    return near.tolist()


def _refresh(abin, b: int, fit, sec, many) -> None:
    """Row ``b`` of :func:`_may_take`'s arrays from the free sections of ``abin``."""
    k = sec.shape[1]
    secs = abin._sections
    if len(secs) > k:
        A = abin.free_sizes()
        lo, up = A.min(axis=1), A.max(axis=1)
        fit[:, b] = A[:, 0].max(), A[:, 1].max(), lo.max(), up.max(), (A[:, 0] * A[:, 1]).max()
        many[b] = True
        return
    wh = [(s.width, s.height) for s in secs]
    fit[:, b] = (max((w for w, _ in wh), default=0), max((h for _, h in wh), default=0),
              max((min(p) for p in wh), default=0), max((max(p) for p in wh), default=0),
              max((w * h for w, h in wh), default=0))
    many[b] = False
    sec[b] = 0
    if wh:
        sec[b, :len(wh)] = wh


def sheet_gap(layout: Layout) -> float:
    """Gap between sheets drawn side by side (mm)."""
    return 0.1 * layout.size[0]
