"""Flat layout of the outlines, optionally nested on stock sheets.

Algorithm: first-fit decreasing-height shelf packing of bounding rectangles
("FFDH", Coffman et al. 1980), with every outline already turned so that its
smallest bounding rectangle is axis-aligned and landscape.  Parts are taken
tallest first; each goes on the first shelf (of any open sheet) with room
left and enough height, else on a new shelf on the first sheet with height
left, else on a new sheet.  A part longer than the sheet is turned 90
degrees when it then fits.  ``spacing`` is kept between parts and from the
sheet edges.  Utilisation = outline area / sheet area.

Without a sheet the outlines are laid on one strip about as wide as the
square root of their total rectangle area (a drawing, not a cutting plan).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from optimize.errors import ConfigError


@dataclass(frozen=True)
class Layout:
    """Where every flat part goes.

    ids : (p,) str.  group, index : (p,) which ``PartGroup`` and which part in it.
    sheet : (p,) int.  x, y : (p,) float, mm, lower-left corner of the part's
    bounding rectangle on its sheet.  rotated : (p,) bool, turned 90 degrees
    counter-clockwise.  size : (W, H) of a sheet (mm).  sheets : number of
    sheets.  utilisation : (sheets,) outline area / sheet area.
    algorithm : name of the packing algorithm.  nested : stock sheets given.
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

    def facts(self) -> dict:
        return {"algorithm": self.algorithm, "nested": self.nested, "sheets": self.sheets,
                "sheet_mm": list(self.size), "parts": len(self.ids),
                "utilisation": [round(float(u), 4) for u in self.utilisation],
                "utilisation_mean": float(np.mean(self.utilisation)) if self.sheets else 0.0}


def flat_parts(parts, kinds=("panel", "beam")):
    """The groups laid flat (panels and beams; nodes are turned parts, not cut from sheet)."""
    return [(gi, g) for gi, g in enumerate(parts.groups) if g.kind in kinds and len(g)]


def layout(parts, sheet: tuple[float, float] | None = None, spacing: float = 10.0) -> Layout:
    """Lay every panel and beam outline flat; nest on ``sheet = (W, H)`` mm when given."""
    if spacing < 0:
        raise ConfigError(f"nesting spacing = {spacing!r}: expected a number >= 0 (mm)")
    groups = flat_parts(parts)
    ids = tuple(i for _, g in groups for i in g.ids)
    gidx = np.concatenate([np.full(len(g), gi) for gi, g in groups]) if groups else np.zeros(0, int)
    pidx = np.concatenate([np.arange(len(g)) for _, g in groups]) if groups else np.zeros(0, int)
    rect = np.concatenate([g.rect for _, g in groups]) if groups else np.zeros((0, 2))
    area = np.concatenate([g.area_mm2 for _, g in groups]) if groups else np.zeros(0)
    nested = sheet is not None
    if nested:
        W, H = (float(s) for s in sheet)
        if not (W > 0 and H > 0):
            raise ConfigError(f"nesting sheet = {sheet!r}: expected two positive sizes (mm)")
    else:
        strip = float(np.sqrt(((rect[:, 0] + spacing) * (rect[:, 1] + spacing)).sum())) * 1.1 if len(rect) else 1.0
        W = max(strip, float(rect[:, 0].max()) + 2 * spacing if len(rect) else 1.0)
        H = np.inf
    w, h = rect[:, 0].copy(), rect[:, 1].copy()
    rotated = np.zeros(len(rect), dtype=bool)
    if nested:
        too_long = w + 2 * spacing > W
        turn = too_long & (h + 2 * spacing <= W) & (w + 2 * spacing <= H)
        rotated[turn] = True
        w[turn], h[turn] = rect[turn, 1], rect[turn, 0]
        bad = (w + 2 * spacing > W) | (h + 2 * spacing > H)
        if bad.any():
            i = int(np.argmax(bad))
            raise ConfigError(f"nesting: part {ids[i]} ({rect[i, 0]:.1f} x {rect[i, 1]:.1f} mm) does not fit "
                              f"the sheet {W:g} x {H:g} mm with spacing {spacing:g} mm")
    order = np.lexsort((-w, -h))
    sheet_of = np.zeros(len(rect), dtype=np.int64)
    x = np.zeros(len(rect))
    y = np.zeros(len(rect))
    # shelves (at most one per part): sheet, y, height, next free x; per sheet: used height
    sh_sheet = np.zeros(len(rect), dtype=np.int64)
    sh_y, sh_h, sh_x = np.zeros(len(rect)), np.zeros(len(rect)), np.zeros(len(rect))
    n_sh = 0
    used_h: list[float] = []
    for i in order.tolist():  # one pass over parts; the shelves are searched with numpy
        wi, hi = w[i] + spacing, h[i] + spacing
        ok = (sh_h[:n_sh] >= hi - 1e-9) & (sh_x[:n_sh] + wi <= W + 1e-9)
        if ok.any():
            fit = int(np.argmax(ok))
        else:
            room = [s for s, u in enumerate(used_h) if u + hi <= H + 1e-9]
            s = room[0] if room else len(used_h)
            if not room:
                used_h.append(spacing)
            fit = n_sh
            n_sh += 1
            sh_sheet[fit], sh_y[fit], sh_h[fit], sh_x[fit] = s, used_h[s], hi, spacing
            used_h[s] += hi
        sheet_of[i] = sh_sheet[fit]
        x[i], y[i] = sh_x[fit], sh_y[fit]
        sh_x[fit] += wi
    n_sheets = len(used_h)
    if not nested:
        H = float(max(used_h)) if used_h else 1.0
    util = np.bincount(sheet_of, weights=area, minlength=n_sheets)[:n_sheets] / (W * H)
    return Layout(ids=ids, group=gidx, index=pidx, sheet=sheet_of, x=x, y=y, rotated=rotated,
                  size=(W, float(H)), sheets=n_sheets, utilisation=util,
                  algorithm="first-fit decreasing-height shelf packing (FFDH) of bounding rectangles",
                  nested=nested)


def sheet_gap(layout: Layout) -> float:
    """Gap between sheets drawn side by side (mm)."""
    return 0.1 * layout.size[0]
