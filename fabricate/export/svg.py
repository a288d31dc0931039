"""SVG (mm) of the flat outlines, laid out like the DXF (same layout, same drawing data).

One ``<g id="P0001">`` per part with the outline (class ``cut``), the bevel
outline where it differs (``bevel``, dashed), the id and the orientation
arrow (``etch``); sheets side by side when nested (``sheet``).  The drawing
uses y up (one flip at the top), so coordinates read like the DXF.
"""
from __future__ import annotations

import time
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from fabricate.cad.parts import cut_from_sheet
from optimize.atomic import atomic_open
from optimize.errors import write_error

from .flat import flat_group
from .nesting import Layout, sheet_gap
from .nesting import layout as make_layout

STYLE = (".cut{fill:none;stroke:#d00000;stroke-width:0.5}"
         ".bevel{fill:none;stroke:#008000;stroke-width:0.3;stroke-dasharray:6 4}"
         ".etch{fill:none;stroke:#0000c0;stroke-width:0.3}"
         ".sheet{fill:none;stroke:#808080;stroke-width:0.5}"
         "text{fill:#0000c0;font-family:sans-serif;text-anchor:middle;dominant-baseline:central}")


def _group_svg(g, fg, lay: Layout, rows: np.ndarray, step: float) -> str:
    """SVG text of every part of group ``g`` (drawing data ``fg``, layout rows ``rows (p,)``, sheets ``step``
    mm apart): one ``%`` over the group, the parts' templates (turned or not) joined."""
    p = len(g)

    def points(m: int) -> str:
        return " ".join(["%.4f,%.4f"] * m)

    tail = ('<polyline class="etch" points="' + points(5) + '"/><text transform="translate(%.4f %.4f) scale(1 -1)" '
            'font-size="%.3f">%s</text></g>\n')
    shapes = ('<polygon class="cut" points="' + points(fg.outline.shape[1]) + '"/>'
              + "".join('<polygon class="bevel" points="' + points(b.shape[1]) + '"/>' for b in fg.bevels) + tail)
    templates = np.array(['<g id="%s" transform="translate(%.4f %.4f)">' + shapes,
                          '<g id="%s" transform="translate(%.4f %.4f) rotate(90)">' + shapes], dtype=object)
    rot = lay.rotated[rows]
    x0, y0 = lay.x[rows] + lay.sheet[rows] * step, lay.y[rows]
    ids = np.array(g.ids, dtype=object)[:, None]
    cols = [ids, np.where(rot, x0 + g.rect[:, 1], x0)[:, None], y0[:, None], fg.outline.reshape(p, -1)]
    cols += [b.reshape(p, -1) for b in fg.bevels]
    cols += [fg.arrow.reshape(p, -1), fg.text_at, fg.text_height[:, None],
             np.array([escape(pid) for pid in g.ids], dtype=object)[:, None]]
    V = np.empty((p, sum(c.shape[1] for c in cols)), dtype=object)
    c0 = 0
    for c in cols:
        V[:, c0:c0 + c.shape[1]] = c
        c0 += c.shape[1]
    return "".join(templates[rot.astype(np.int64)].tolist()) % tuple(V.ravel().tolist())


def write_svg(parts, path, *, sheet: tuple[float, float] | None = None, spacing: float = 10.0,
              lay: Layout | None = None) -> dict:
    """Write the flat outlines of every panel and beam to an SVG file (atomic).

    Returns facts: ``file, bytes, parts, width_mm, height_mm, layout, seconds``.
    """
    t0 = time.perf_counter()
    path = Path(path)
    lay = lay or make_layout(parts, sheet, spacing)
    W, H = lay.size
    step = W + sheet_gap(lay)
    total_w = max(lay.sheets, 1) * step - sheet_gap(lay)
    where = {pid: k for k, pid in enumerate(lay.ids)}
    body = []
    for g in parts.groups:
        if not cut_from_sheet(g.kind, g.member) or not len(g) or g.ids[0] not in where:
            continue  # a layout of some groups only (one material and thickness)
        body.append(_group_svg(g, flat_group(g), lay, np.array([where[pid] for pid in g.ids]), step))
    if lay.nested:
        for s in range(lay.sheets):
            body.append(f'<rect class="sheet" x="{s * step:.4f}" y="0" width="{W:.4f}" height="{H:.4f}"/>\n')
    text = ('<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{total_w:.3f}mm" height="{H:.3f}mm" '
            f'viewBox="0 0 {total_w:.4f} {H:.4f}">\n<title>conical-fab outlines (mm)</title>\n'
            f'<style>{STYLE}</style>\n<g transform="matrix(1 0 0 -1 0 {H:.4f})">\n'
            + "".join(body) + "</g>\n</svg>\n")
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        raise write_error(path, "SVG file", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "parts": len(lay.ids), "width_mm": total_w,
            "height_mm": H, "layout": lay.facts(), "seconds": time.perf_counter() - t0}
