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

from fabricate.cad.parts import cut_from_sheet
from optimize.atomic import atomic_open
from optimize.errors import ExportError

from .flat import flat_group
from .nesting import Layout, layout as make_layout, sheet_gap

STYLE = (".cut{fill:none;stroke:#d00000;stroke-width:0.5}"
         ".bevel{fill:none;stroke:#008000;stroke-width:0.3;stroke-dasharray:6 4}"
         ".etch{fill:none;stroke:#0000c0;stroke-width:0.3}"
         ".sheet{fill:none;stroke:#808080;stroke-width:0.5}"
         "text{fill:#0000c0;font-family:sans-serif;text-anchor:middle;dominant-baseline:central}")


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
    for gi, g in enumerate(parts.groups):
        if not cut_from_sheet(g.kind, g.member) or not len(g) or g.ids[0] not in where:
            continue  # a layout of some groups only (one material and thickness)
        fg = flat_group(g)
        k_out = fg.outline.shape[1]
        pts = " ".join(["%.4f,%.4f"] * k_out)
        bpts = [" ".join(["%.4f,%.4f"] * b.shape[1]) for b in fg.bevels]
        apts = " ".join(["%.4f,%.4f"] * 5)
        for i, pid in enumerate(g.ids):  # text per part
            k = where[pid]
            x0, y0 = lay.x[k] + lay.sheet[k] * step, lay.y[k]
            h = g.rect[i, 1]
            place = (f"translate({x0 + h:.4f} {y0:.4f}) rotate(90)" if lay.rotated[k]
                     else f"translate({x0:.4f} {y0:.4f})")
            tx, ty = fg.text_at[i]
            parts_svg = [f'<g id="{pid}" transform="{place}">',
                         f'<polygon class="cut" points="{pts % tuple(fg.outline[i].ravel())}"/>']
            for b, fmt in zip(fg.bevels, bpts):
                parts_svg.append(f'<polygon class="bevel" points="{fmt % tuple(b[i].ravel())}"/>')
            parts_svg.append(f'<polyline class="etch" points="{apts % tuple(fg.arrow[i].ravel())}"/>')
            parts_svg.append(f'<text transform="translate({tx:.4f} {ty:.4f}) scale(1 -1)" '
                             f'font-size="{fg.text_height[i]:.3f}">{escape(pid)}</text></g>\n')
            body.append("".join(parts_svg))
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
        raise ExportError(f"{path}: cannot write the SVG file ({exc.strerror or exc})") from None
    return {"file": path.name, "bytes": path.stat().st_size, "parts": len(lay.ids), "width_mm": total_w,
            "height_mm": H, "layout": lay.facts(), "seconds": time.perf_counter() - t0}
