"""DXF (R2010, mm) of the flat outlines of every panel and beam, laid out or nested.

Layers: ``CUT`` the outline to cut from sheet (``PartGroup.flat``: the
whole part seen from above, the V ends and ridges of a beam included),
``BEVEL`` (dashed) the bevel reference line and the two sheet faces' outlines
where they differ from the cut, and each edge's bevel angles as TEXT
(``+a/-b`` degrees from square on the upper / lower side, ``+a`` for one
plane through the thickness, none for a square edge), ``ETCH`` the id (TEXT)
and the orientation arrow, ``SHEET`` the stock sheets when nested.  Every CUT outline carries
the part id as XDATA (application ``CONICAL_FAB``, group 1000), so CAM
software and ``fabricate check`` can pair it with the STEP solid.

ezdxf builds the document (header with ``$INSUNITS = 4`` mm, tables,
layers, linetype, application id, the first sheet); the other sheets and the
per-part entities, tens of thousands of them, are written as DXF text from
templates (ezdxf takes about 1 ms per part to create them; a group's parts
in one ``%``) and inserted into the ENTITIES section with the handles ezdxf
would have given them.  The sheet template is checked against ezdxf's first
sheet (ezdxf writes every sheet when they differ).  Before writing, the
skeleton with the first sheets and parts inserted is read back and audited
by ezdxf, so that work does not grow with the drawing; ``fabricate check``
audits the whole file.
"""
from __future__ import annotations

import io
import re
import time
from pathlib import Path

import numpy as np

from fabricate.cad.parts import cut_from_sheet
from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from .flat import flat_group
from .nesting import Layout, sheet_gap
from .nesting import layout as make_layout

LAYERS = {"CUT": 1, "INNER": 2, "BEVEL": 3, "ETCH": 5, "SHEET": 8}
"""INNER holds inner contours (holes); the parts built today have none, the layer is there for CAM set-ups."""
APPID = "CONICAL_FAB"
AUDIT_SAMPLE = 24


def _skeleton(lay: Layout, every_sheet: bool = False):
    """The ezdxf document without parts: header, layers, linetype, appid, sheets.

    Only the first sheet is made by ezdxf unless ``every_sheet``; the handles of the others are kept
    free (two each, in sheet order) for :func:`_sheets_text`, so the file is the same either way.
    Returns the document and the handle of the first sheet's outline (None: no sheet)."""
    import ezdxf

    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    doc.header["$MEASUREMENT"] = 1
    doc.appids.new(APPID)
    doc.linetypes.add("DASHED", pattern=[10.0, 6.0, -4.0], description="Dashed __ __ __")
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour, linetype="DASHED" if name == "BEVEL" else "Continuous")
    msp = doc.modelspace()
    first = None
    if lay.nested and lay.sheets:
        W, H = lay.size
        step = W + sheet_gap(lay)
        count = np.bincount(np.asarray(lay.sheet, dtype=np.int64), minlength=lay.sheets)
        for s in range(lay.sheets if every_sheet else 1):
            x0 = s * step
            e = msp.add_lwpolyline([(x0, 0), (x0 + W, 0), (x0 + W, H), (x0, H)], close=True,
                                   dxfattribs={"layer": "SHEET"})
            msp.add_text(_sheet_label(lay, s, int(count[s])), height=0.01 * W,
                         dxfattribs={"layer": "SHEET", "insert": (x0, H + 0.01 * W)})
            first = int(e.dxf.handle, 16) if first is None else first
        if not every_sheet:
            handles = doc.entitydb.handles
            handles.reset(f"{int(str(handles), 16) + 2 * (lay.sheets - 1):X}")
    return doc, first


def _sheet_label(lay: Layout, s: int, parts: int) -> str:
    W, H = lay.size
    return (f"{lay.sheet_id(s)}: {W:g} x {H:g} mm, margin {lay.margin:g} mm, kerf {lay.kerf:g} mm, "
            f"{parts} parts, yield {100 * lay.utilisation[s]:.1f} %")


SHEET_TEMPLATE = ("  0\nLWPOLYLINE\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\nSHEET\n100\nAcDbPolyline\n 90\n4\n"
                  " 70\n1\n" + " 10\n%r\n 20\n%r\n" * 4
                  + "  0\nTEXT\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\nSHEET\n100\nAcDbText\n 10\n%r\n"
                  " 20\n%r\n 30\n0.0\n 40\n%r\n  1\n%s\n100\nAcDbText\n")
"""A sheet as ezdxf writes it: outline (handle, 4 corners), label (handle, insert x, y, height, text)."""


def _sheets_text(lay: Layout, owner: str, first: int, sheets: range) -> str:
    """DXF text of the ``sheets`` (outline and label each, handles from ``first`` for sheet 0)."""
    W, H = lay.size
    step = W + sheet_gap(lay)
    count = np.bincount(np.asarray(lay.sheet, dtype=np.int64), minlength=lay.sheets)
    t = SHEET_TEMPLATE.replace("{owner}", owner)
    out = []
    for s in sheets:  # a few fields per sheet
        x0 = s * step
        x, w, y, ht = float(x0), float(x0 + W), float(H), float(0.01 * W)
        out.append(t % (first + 2 * s, x, 0.0, w, 0.0, w, y, x, y, first + 2 * s + 1, x, float(H + 0.01 * W), ht,
                        _sheet_label(lay, s, int(count[s]))))
    return "".join(out)


def _polyline(layer: str, k: int, closed: bool, xdata: bool, owner: str = "%s") -> str:
    """``%`` template of an LWPOLYLINE: fields handle (``%X`` int), k (x, y) pairs[, id]; ``owner`` written in
    (the default ``%s`` makes it a field after the handle)."""
    head = ("  0\nLWPOLYLINE\n  5\n%X\n330\n" f"{owner}\n100\nAcDbEntity\n"
            f"  8\n{layer}\n100\nAcDbPolyline\n 90\n{k}\n 70\n{int(closed)}\n")
    tail = f"1001\n{APPID}\n1000\n%s\n" if xdata else ""
    return head + " 10\n%.17g\n 20\n%.17g\n" * k + tail


TEXT_TEMPLATE = ("  0\nTEXT\n  5\n%X\n330\n{owner}\n100\nAcDbEntity\n  8\n{layer}\n100\nAcDbText\n 10\n%s\n"
                 " 20\n%s\n 30\n0.0\n 40\n%.6g\n  1\n%s\n 72\n1\n 11\n%s\n 21\n%s\n 31\n0.0\n100\nAcDbText\n"
                 " 73\n2\n")
"""Fields: handle (int), x, y (:func:`_g17` str), height, text, x, y; ``{owner}`` and ``{layer}`` filled in per file."""


def _g17(a: np.ndarray) -> np.ndarray:
    """``"%.17g"`` of every figure of ``a`` as an object array of str of its shape (printed once, used twice)."""
    flat = a.ravel().tolist()
    return np.array((("%.17g\x1f" * len(flat)) % tuple(flat)).split("\x1f")[:-1], dtype=object).reshape(a.shape)


def _placed(lay: Layout, rows: np.ndarray, rect_h: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Points ``P (q, m, 2)`` of layout rows ``rows (q,)`` in drawing coordinates."""
    rot = lay.rotated[rows]
    X = np.where(rot[:, None], rect_h[:, None] - P[..., 1], P[..., 0])
    Y = np.where(rot[:, None], P[..., 0], P[..., 1])
    x0 = lay.x[rows] + lay.sheet[rows] * (lay.size[0] + sheet_gap(lay))
    return np.stack([X + x0[:, None], Y + lay.y[rows][:, None]], axis=2)


def _group_text(g, fg, lay: Layout, rows: np.ndarray, owner: str, handle: int) -> tuple[str, int]:
    """DXF text of the first ``q = len(rows)`` parts of group ``g`` (drawing data ``fg``, layout rows
    ``rows (q,)``) with handles from ``handle`` on, and the next free handle.

    Per part: the CUT outline (id as XDATA), the arrow, the id, the bevel lines, the labels of the
    edges that are not square.  One ``%`` over the group: the parts' templates joined (a part's
    template depends only on its number of labels) and their fields, row by row, out of a
    ``(q, fields)`` object table with the unused label slots masked."""
    q = len(rows)
    h = g.rect[:q, 1]
    k = fg.outline.shape[1]
    label = fg.angle_text[:q]
    keep = label != "0"                                                       # (q, k) labels drawn
    n_lab = keep.sum(axis=1)
    text = TEXT_TEMPLATE.replace("{owner}", owner)
    base = (_polyline("CUT", k, True, True, owner) + _polyline("ETCH", 5, False, False, owner)
            + text.replace("{layer}", "ETCH")
            + "".join(_polyline("BEVEL", b.shape[1], True, False, owner) for b in fg.bevels))
    angle = text.replace("{layer}", "BEVEL")
    blocks = [_placed(lay, rows, h, fg.outline[:q]).reshape(q, -1), np.array(g.ids[:q], dtype=object)[:, None],
              _placed(lay, rows, h, fg.arrow[:q]).reshape(q, -1)]
    xy = _g17(_placed(lay, rows, h, fg.text_at[:q, None, :])[:, 0])
    th = fg.text_height[:q]
    blocks.append(np.column_stack([xy, th, blocks[1][:, 0], xy]))
    first = handle + np.concatenate([[0], np.cumsum(3 + len(fg.bevels) + n_lab)[:-1]])   # (q,) first handle
    cols = [first[:, None], blocks[0], blocks[1], first[:, None] + 1, blocks[2], first[:, None] + 2, blocks[3]]
    for j, b in enumerate(fg.bevels):
        cols += [first[:, None] + 3 + j, _placed(lay, rows, h, b[:q]).reshape(q, -1)]
    at = np.empty((q, k, 2), dtype=object)                                   # the labels drawn printed
    at[keep] = _g17(_placed(lay, rows, h, fg.angle_at[:q])[keep])
    lab = np.empty((q, k, 7), dtype=object)
    lab[..., 0] = first[:, None] + 3 + len(fg.bevels) + np.cumsum(keep, axis=1) - 1
    lab[..., 1:3] = at
    lab[..., 3] = 0.5 * th[:, None]
    lab[..., 4] = label
    lab[..., 5:7] = at
    widths = [c.shape[1] for c in cols]
    V = np.empty((q, sum(widths) + 7 * k), dtype=object)
    c0 = 0
    for c, w in zip(cols, widths):
        V[:, c0:c0 + w] = c
        c0 += w
    V[:, c0:] = lab.reshape(q, -1)
    used = np.ones(V.shape, dtype=bool)
    used[:, c0:] = np.repeat(keep, 7, axis=1)
    templates = np.array([base + angle * n for n in range(k + 1)], dtype=object)
    out = "".join(templates[n_lab].tolist()) % tuple(V[used].tolist())
    return out, handle + int(np.sum(3 + len(fg.bevels) + n_lab))


def _drawn(parts, lay: Layout) -> list[tuple]:
    """``[(group, drawing data, layout rows (p,))]`` of the groups laid out in ``lay``."""
    row_of = {pid: k for k, pid in enumerate(lay.ids)}
    out = []
    for g in parts.groups:
        if not cut_from_sheet(g.kind, g.member) or not len(g) or g.ids[0] not in row_of:
            continue
        out.append((g, flat_group(g), np.array([row_of[i] for i in g.ids])))
    return out


def _entities(drawn: list[tuple], lay: Layout, owner: str, seed: int, limit: int | None = None) -> tuple[str, int, int]:
    """DXF text of the parts' entities (the first ``limit`` parts; None: all), the next free handle and the
    number of parts written.  drawn : :func:`_drawn`."""
    out, handle, n = [], seed, 0
    for g, fg, rows in drawn:
        take = len(g) if limit is None else max(0, min(len(g), limit - n))
        if take == 0:
            break
        text, handle = _group_text(g, fg, lay, rows[:take], owner, handle)
        out.append(text)
        n += take
    return "".join(out), handle, n


def _assemble(skeleton: str, next_handle: int) -> tuple[str, str]:
    """The skeleton split at the end of its ENTITIES section (the text before, with ``$HANDSEED`` moved to
    ``next_handle``, and the text after): the entities go between."""
    start = skeleton.index("  2\nENTITIES\n")
    end = skeleton.index("  0\nENDSEC\n", start)
    head = re.sub(r"(\$HANDSEED\n  5\n)([0-9A-Fa-f]+)", lambda m: m.group(1) + f"{next_handle:X}", skeleton[:end],
                  count=1)
    return head, skeleton[end:]


def _written(doc) -> str:
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue()


def write_dxf(parts, path, *, sheet: tuple[float, float] | None = None, spacing: float = 10.0,
              lay: Layout | None = None) -> dict:
    """Write the flat outlines of every panel and beam to a DXF file (atomic).

    sheet : stock sheet ``(W, H)`` mm to nest on (None: one drawing strip).
    spacing : mm between parts and from sheet edges.  lay : a ready layout.
    Returns facts: ``file, bytes, outlines, entities, layers, audit, layout, seconds``.
    Raises ExportError when the audit of the sample finds errors or the file cannot be written.
    """
    import ezdxf

    t0 = time.perf_counter()
    path = Path(path)
    lay = lay or make_layout(parts, sheet, spacing)
    doc, first = _skeleton(lay)
    owner = doc.modelspace().block_record_handle
    skeleton = _written(doc)
    sheets = sample_sheets = ""
    if first is not None:  # ezdxf wrote the first sheet: the template must write it the same, or ezdxf writes all
        start = skeleton.index("  2\nENTITIES\n") + len("  2\nENTITIES\n")
        if skeleton[start:skeleton.index("  0\nENDSEC\n", start)] == _sheets_text(lay, owner, first, range(1)):
            sheets = _sheets_text(lay, owner, first, range(1, lay.sheets))
            sample_sheets = _sheets_text(lay, owner, first, range(1, min(lay.sheets, AUDIT_SAMPLE)))
        else:
            skeleton = _written(_skeleton(lay, every_sheet=True)[0])
    seed = int(re.search(r"\$HANDSEED\n  5\n([0-9A-Fa-f]+)", skeleton).group(1), 16)
    drawn = _drawn(parts, lay)
    sample, sample_next, n_sample = _entities(drawn, lay, owner, seed, limit=AUDIT_SAMPLE)
    head, tail = _assemble(skeleton, sample_next)
    try:
        auditor = ezdxf.read(io.StringIO(head + sample_sheets + sample + tail)).audit()
    except ezdxf.DXFError as exc:
        raise ExportError(f"{path}: the DXF template does not read back ({exc})") from None
    if auditor.has_errors:
        raise ExportError(f"{path}: ezdxf audit of the first {n_sample} parts found {len(auditor.errors)} "
                          f"error(s), first: {auditor.errors[0].message}")
    entities, next_handle, n = _entities(drawn, lay, owner, seed)
    head, tail = _assemble(skeleton, next_handle)
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
            for text in (head, sheets, entities, tail):
                fh.write(text)
    except OSError as exc:
        raise write_error(path, "DXF file", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "outlines": n, "entities": next_handle - seed,
            "units": "mm", "layers": list(LAYERS),
            "audit": f"ezdxf audit clean on the document with the first {n_sample} parts "
                     f"({len(auditor.fixes)} fixes); fabricate check audits the whole file",
            "layout": lay.facts(), "seconds": time.perf_counter() - t0}


def read_outlines(path) -> tuple[dict[str, np.ndarray], dict]:
    """``{part id: CUT outline (k, 2)}`` of a DXF written here, and its audit facts."""
    import ezdxf

    try:
        doc = ezdxf.readfile(str(path))
    except (OSError, ezdxf.DXFError) as exc:
        raise ExportError(f"{path}: not a readable DXF file ({exc})") from None
    auditor = doc.audit()
    out = {}
    for e in doc.modelspace().query("LWPOLYLINE[layer=='CUT']"):
        if e.has_xdata(APPID):
            pid = next((v for code, v in e.get_xdata(APPID) if code == 1000), None)
            out[pid] = np.array([(x, y) for x, y, *_ in e.get_points()], dtype=float)
    texts = sum(1 for _ in doc.modelspace().query("TEXT[layer=='ETCH']"))
    return out, {"audit_errors": len(auditor.errors), "audit_fixes": len(auditor.fixes),
                 "units": int(doc.header.get("$INSUNITS", 0)), "texts": texts}
