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

rectpack's guillotine class runs with its two inner loops rewritten (:mod:`fabricate.export.guillotine`:
the same placements, 2 to 5 times faster).  A layout is computed once per parts object and arguments (:data:`_LAYOUTS`): the DXF and the SVG of the
same outlines draw the same layout, and rectpack takes seconds on ten thousand plates.  Its arrays are
read-only.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from optimize.errors import ConfigError

FAST_ABOVE = 4000
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
    """:func:`layout` without the cache; ``algo``: the packing algorithm class (default
    :class:`fabricate.export.guillotine.GuillotineBssfSas`, rectpack's placements)."""
    import rectpack

    from .guillotine import GuillotineBssfSas

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
    packer = rectpack.newPacker(mode=rectpack.PackingMode.Offline, rotation=rotation,
                                pack_algo=algo or GuillotineBssfSas, sort_algo=rectpack.SORT_AREA,
                                bin_algo=rectpack.PackingBin.BNF if fast else rectpack.PackingBin.BFF)
    for i in range(len(rect)):  # rectpack takes one rectangle per call
        packer.add_rect(int(w[i]), int(h[i]), rid=i)
    packer.add_bin(bw, bh, count=float("inf"))
    packer.pack()
    sheet_of = np.full(len(rect), -1, dtype=np.int64)
    x, y = np.zeros(len(rect)), np.zeros(len(rect))
    rotated = np.zeros(len(rect), dtype=bool)
    for b, rx, ry, rw, rh, rid in packer.rect_list():  # one placement per part
        sheet_of[rid], x[rid], y[rid] = b, rx + margin, ry + margin
        rotated[rid] = rw != w[rid]
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


def sheet_gap(layout: Layout) -> float:
    """Gap between sheets drawn side by side (mm)."""
    return 0.1 * layout.size[0]
