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
layers, linetype, application id, sheets); the per-part entities, tens of
thousands of them, are written as DXF text from one template per entity
kind (ezdxf takes about 1 ms per part to create them) and inserted into the
ENTITIES section with fresh handles.  Before writing, the skeleton with the
first parts inserted is read back and audited by ezdxf; ``fabricate check``
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
from optimize.errors import ExportError

from .flat import flat_group
from .nesting import Layout, layout as make_layout, sheet_gap

LAYERS = {"CUT": 1, "INNER": 2, "BEVEL": 3, "ETCH": 5, "SHEET": 8}
"""INNER holds inner contours (holes); the parts built today have none, the layer is there for CAM set-ups."""
APPID = "CONICAL_FAB"
AUDIT_SAMPLE = 24


def _skeleton(lay: Layout):
    """The ezdxf document without parts: header, layers, linetype, appid, sheets."""
    import ezdxf

    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    doc.header["$MEASUREMENT"] = 1
    doc.appids.new(APPID)
    doc.linetypes.add("DASHED", pattern=[10.0, 6.0, -4.0], description="Dashed __ __ __")
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour, linetype="DASHED" if name == "BEVEL" else "Continuous")
    msp = doc.modelspace()
    if lay.nested:
        W, H = lay.size
        step = W + sheet_gap(lay)
        for s in range(lay.sheets):
            x0 = s * step
            msp.add_lwpolyline([(x0, 0), (x0 + W, 0), (x0 + W, H), (x0, H)], close=True,
                               dxfattribs={"layer": "SHEET"})
            msp.add_text(f"{lay.sheet_id(s)}: {W:g} x {H:g} mm, margin {lay.margin:g} mm, kerf {lay.kerf:g} mm, "
                         f"{int((lay.sheet == s).sum())} parts, yield {100 * lay.utilisation[s]:.1f} %",
                         height=0.01 * W, dxfattribs={"layer": "SHEET", "insert": (x0, H + 0.01 * W)})
    return doc


def _polyline(layer: str, k: int, closed: bool, xdata: bool) -> str:
    """``%`` template of an LWPOLYLINE: fields handle, owner, k (x, y) pairs[, id]."""
    head = ("  0\nLWPOLYLINE\n  5\n%s\n330\n%s\n100\nAcDbEntity\n"
            f"  8\n{layer}\n100\nAcDbPolyline\n 90\n{k}\n 70\n{int(closed)}\n")
    tail = f"1001\n{APPID}\n1000\n%s\n" if xdata else ""
    return head + " 10\n%.17g\n 20\n%.17g\n" * k + tail


TEXT_TEMPLATE = ("  0\nTEXT\n  5\n%s\n330\n%s\n100\nAcDbEntity\n  8\n{layer}\n100\nAcDbText\n 10\n%.17g\n 20\n%.17g\n 30\n0.0\n"
        " 40\n%.6g\n  1\n%s\n 72\n1\n 11\n%.17g\n 21\n%.17g\n 31\n0.0\n100\nAcDbText\n 73\n2\n")
TEXT = TEXT_TEMPLATE.replace("{layer}", "ETCH")
ANGLE_TEXT = TEXT_TEMPLATE.replace("{layer}", "BEVEL")


def _placed(lay: Layout, rows: np.ndarray, rect_h: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Points ``P (q, m, 2)`` of layout rows ``rows (q,)`` in drawing coordinates."""
    rot = lay.rotated[rows]
    X = np.where(rot[:, None], rect_h[:, None] - P[..., 1], P[..., 0])
    Y = np.where(rot[:, None], P[..., 0], P[..., 1])
    x0 = lay.x[rows] + lay.sheet[rows] * (lay.size[0] + sheet_gap(lay))
    return np.stack([X + x0[:, None], Y + lay.y[rows][:, None]], axis=2)


def _entities(parts, lay: Layout, owner: str, seed: int, limit: int | None = None) -> tuple[str, int, int]:
    """DXF text of every part's entities, the next free handle and the number of parts written."""
    row_of = {pid: k for k, pid in enumerate(lay.ids)}
    out, handle, n = [], seed, 0
    for g in parts.groups:
        if not cut_from_sheet(g.kind, g.member) or not len(g) or g.ids[0] not in row_of:
            continue
        fg = flat_group(g)
        take = len(g) if limit is None else max(0, min(len(g), limit - n))
        if take == 0:
            break
        rows = np.array([row_of[i] for i in g.ids[:take]])
        h = g.rect[:take, 1]
        cut = _placed(lay, rows, h, fg.outline[:take]).reshape(take, -1).tolist()
        bevels = [_placed(lay, rows, h, b[:take]).reshape(take, -1).tolist() for b in fg.bevels]
        arrow = _placed(lay, rows, h, fg.arrow[:take]).reshape(take, -1).tolist()
        text_at = _placed(lay, rows, h, fg.text_at[:take, None, :])[:, 0].tolist()
        angle_at = _placed(lay, rows, h, fg.angle_at[:take]).tolist()
        t_cut = _polyline("CUT", fg.outline.shape[1], True, True)
        t_bevels = [_polyline("BEVEL", b.shape[1], True, False) for b in fg.bevels]
        t_arrow = _polyline("ETCH", 5, False, False)
        for i in range(take):  # a few small templates per part
            pid = g.ids[i]
            out.append(t_cut % ((f"{handle:X}", owner) + tuple(cut[i]) + (pid,)))
            out.append(t_arrow % ((f"{handle + 1:X}", owner) + tuple(arrow[i])))
            (x, y), th = text_at[i], fg.text_height[i]
            out.append(TEXT % (f"{handle + 2:X}", owner, x, y, th, pid, x, y))
            handle += 3
            for t_b, b in zip(t_bevels, bevels):
                out.append(t_b % ((f"{handle:X}", owner) + tuple(b[i])))
                handle += 1
            for (x, y), label in zip(angle_at[i], fg.angle_text[i]):
                if label != "0":
                    out.append(ANGLE_TEXT % (f"{handle:X}", owner, x, y, 0.5 * th, label, x, y))
                    handle += 1
        n += take
    return "".join(out), handle, n


def _assemble(skeleton: str, entities: str, next_handle: int) -> str:
    """Insert ``entities`` at the end of the ENTITIES section and move ``$HANDSEED`` past them."""
    start = skeleton.index("  2\nENTITIES\n")
    end = skeleton.index("  0\nENDSEC\n", start)
    text = skeleton[:end] + entities + skeleton[end:]
    return re.sub(r"(\$HANDSEED\n  5\n)([0-9A-Fa-f]+)", lambda m: m.group(1) + f"{next_handle:X}", text, count=1)


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
    doc = _skeleton(lay)
    owner = doc.modelspace().block_record_handle
    buf = io.StringIO()
    doc.write(buf)
    skeleton = buf.getvalue()
    seed = int(re.search(r"\$HANDSEED\n  5\n([0-9A-Fa-f]+)", skeleton).group(1), 16)
    sample, sample_next, n_sample = _entities(parts, lay, owner, seed, limit=AUDIT_SAMPLE)
    try:
        auditor = ezdxf.read(io.StringIO(_assemble(skeleton, sample, sample_next))).audit()
    except ezdxf.DXFError as exc:
        raise ExportError(f"{path}: the DXF template does not read back ({exc})") from None
    if auditor.has_errors:
        raise ExportError(f"{path}: ezdxf audit of the first {n_sample} parts found {len(auditor.errors)} "
                          f"error(s), first: {auditor.errors[0].message}")
    entities, next_handle, n = _entities(parts, lay, owner, seed)
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(_assemble(skeleton, entities, next_handle))
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the DXF file ({exc.strerror or exc})") from None
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
