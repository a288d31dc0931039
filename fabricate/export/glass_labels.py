"""Printable glass unit labels: one A4 SVG sheet per delivery rack, a QR code per unit (issue 36).

``glass_order/labels_<rack>.svg`` (``labels_R001.svg``; a rack of more than
:data:`PER_SHEET` units goes on ``labels_R001_2.svg`` ..) holds the labels of
the rack's units in slot order (front first), on the common A4 sheet of 3 x 8
self-adhesive labels of 70 x 37 mm (1 SVG unit = 1 mm).  Each label shows:

- a QR code of the unit id (:mod:`segno`, model 2 QR, error level M or better,
  with its 4-module quiet zone), drawn as one SVG path of dark module runs, no
  raster image;
- the unit id, large; its position (with its hand ``A`` / ``B``); its rack, slot,
  install sequence and zone; build-up and weight;
- the orientation mark: the circled ``1`` is the unit's reference corner (the
  drawing's corner 1), the arrow runs along edge ``E1``; ``#1 OUTSIDE``: surface 1
  faces the weather.  The label goes on the inside face at corner 1 with its arrow
  along E1 (``glass_order.csv``'s ``label_position``).

Every label is a ``<g class="label" data-unit=".." data-position="..">`` holding one
``<path class="qr">`` whose ``d`` is ``M<col>,<row>h<run>v1h-<run>z`` per run of dark
modules, in module units of the symbol (the quiet zone and the scale in its
``transform``).
"""
from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from optimize.atomic import atomic_open
from optimize.errors import write_error

PAGE_MM = (210.0, 297.0)
"""A4, portrait."""
LABEL_MM = (70.0, 37.0)
"""One label (width, height)."""
GRID = (3, 8)
"""Labels across and down a sheet."""
PER_SHEET = GRID[0] * GRID[1]
QUIET = 4
"""The QR code's quiet zone (modules), as ISO/IEC 18004 asks."""
MARGIN_MM = 2.0
CHAR_EM = 0.62
"""Width of a sans-serif character per unit of font size (for fitting a line to the label)."""


def qr_matrix(text: str) -> list[list[bool]]:
    """(n, n) the dark modules of the QR code of ``text`` (model 2, at least error level M)."""
    import segno

    return [[bool(v) for v in row] for row in segno.make_qr(text, error="m").matrix]


def qr_path(matrix: list[list[bool]]) -> str:
    """The SVG path data of the dark modules of ``matrix``: one closed rectangle per run along a row."""
    out = []
    for r, row in enumerate(matrix):  # a QR code's rows (21 .. 177)
        c, n = 0, len(row)
        while c < n:
            if not row[c]:
                c += 1
                continue
            start = c
            while c < n and row[c]:
                c += 1
            out.append(f"M{start},{r}h{c - start}v1h-{c - start}z")
    return "".join(out)


def _line(text: str, x: float, y: float, size: float, width: float, bold: bool = False) -> str:
    size = min(size, width / (CHAR_EM * max(len(text), 1)))
    weight = ' font-weight="bold"' if bold else ""
    return (f'<text x="{x:.2f}" y="{y:.2f}" font-size="{size:.2f}" font-family="sans-serif"{weight}>'
            f"{escape(text)}</text>")


def label_svg(unit: dict, x0: float, y0: float) -> str:
    """One label at ``(x0, y0)`` (its top left, mm).  unit : ``id, position, rack, slot, seq, zone,
    build_up, weight_kg``."""
    w, h = LABEL_MM
    matrix = qr_matrix(unit["id"])
    side = h - 2 * MARGIN_MM                                              # the QR code with its quiet zone
    module = side / (len(matrix) + 2 * QUIET)
    qx, qy = x0 + MARGIN_MM + QUIET * module, y0 + MARGIN_MM + QUIET * module
    tx = x0 + MARGIN_MM + side + 1.0
    tw = x0 + w - MARGIN_MM - tx
    lines = [
        _line(unit["id"], tx, y0 + 8.5, 6.5, tw, bold=True),
        _line(f"Pos {unit['position']}", tx, y0 + 13.5, 3.6, tw, bold=True),
        _line(f"Rack {unit['rack']}/{unit['slot']}  Z{unit['zone']}", tx, y0 + 17.8, 3.0, tw),
        _line(f"Seq {unit['seq']}  {unit['weight_kg']:.0f} kg", tx, y0 + 21.8, 3.0, tw),
        _line(f"Build-up {unit['build_up']}", tx, y0 + 25.8, 3.0, tw),
        _line("#1 OUTSIDE", tx, y0 + 29.6, 2.8, tw, bold=True),
    ]
    cx, cy = tx + 1.8, y0 + h - MARGIN_MM - 1.8                           # corner 1, the arrow along E1
    ax = cx + 9.0
    mark = (f'<g class="orientation"><circle cx="{cx:.2f}" cy="{cy:.2f}" r="1.7" fill="none" stroke="#000" '
            f'stroke-width="0.3"/><text x="{cx:.2f}" y="{cy + 0.8:.2f}" font-size="2.2" font-family="sans-serif" '
            f'text-anchor="middle">1</text><path d="M{cx + 1.9:.2f},{cy:.2f}H{ax:.2f}" stroke="#000" '
            f'stroke-width="0.4"/><path d="M{ax:.2f},{cy - 1.2:.2f}L{ax + 2.2:.2f},{cy:.2f}L{ax:.2f},{cy + 1.2:.2f}z"/>'
            f'<text x="{cx + 5.0:.2f}" y="{cy - 1.0:.2f}" font-size="2.2" font-family="sans-serif">E1</text></g>')
    return (f'<g class="label" data-unit={quoteattr(unit["id"])} data-position={quoteattr(unit["position"])}>'
            f'<path class="qr" transform="translate({qx:.3f},{qy:.3f}) scale({module:.5f})" '
            f'd="{qr_path(matrix)}"/>' + "".join(lines) + mark + "</g>")


def write_label_sheets(folder: Path, units: list[dict]) -> dict[str, list[str]]:
    """Write the label sheets of ``units`` (dicts as :func:`label_svg` takes, in install order) into
    ``folder``, one set per rack (atomic).  Returns ``{rack: [file names]}``."""
    racks: dict[str, list[dict]] = {}
    for u in units:  # grouped by rack, slot order kept
        racks.setdefault(u["rack"], []).append(u)
    out: dict[str, list[str]] = {}
    W, H = PAGE_MM
    left = 0.5 * (W - GRID[0] * LABEL_MM[0])
    top = 0.5 * (H - GRID[1] * LABEL_MM[1])
    for rack, members in racks.items():  # one sheet or a few per rack
        members = sorted(members, key=lambda u: u["slot"])
        names = []
        for p in range(0, len(members), PER_SHEET):  # a sheet
            page = members[p:p + PER_SHEET]
            body = [label_svg(u, left + (j % GRID[0]) * LABEL_MM[0], top + (j // GRID[0]) * LABEL_MM[1])
                    for j, u in enumerate(page)]
            name = f"labels_{rack}.svg" if p == 0 else f"labels_{rack}_{p // PER_SHEET + 1}.svg"
            svg = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{W:g}mm" height="{H:g}mm" '
                   f'viewBox="0 0 {W:g} {H:g}">\n<title>glass labels, rack {escape(rack)}</title>\n'
                   + "\n".join(body) + "\n</svg>\n")
            path = Path(folder) / name
            try:
                with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
                    fh.write(svg)
            except OSError as exc:
                raise write_error(path, "glass label sheet", exc) from exc
            names.append(name)
        out[rack] = names
    return out
