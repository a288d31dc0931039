"""Pictures of the shop drawings: nested stock sheets and the layout plan (headless matplotlib).

- :func:`picture_sheets`: one or two real stock sheets of the nested cut files
  (:func:`fabricate.export.cutfiles.nest_cut_files`, the same layout the DXF and SVG
  cut files are written from): the sheet with its margin, every part's cut
  outline where the nesting put it, its id, and the sheet's id, size, part
  count and yield;
- :func:`picture_plan`: the layout plan (plan view, model x and y, as
  ``layout_plan.dxf``): every glass unit's bearing outline with its unit id and
  every beam's glass edge with its id, where they sit on the roof, the ids placed
  apart (:mod:`fabricate.export.plan_labels`).

The data come in as plain arrays (:func:`sheet_drawings`, :func:`plan_drawing`
make them from the nested batches and the parts).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .pictures import MAX_SHEET_INCH, _figure, _id_patch, _save, upright_or_turned

SHEET_INCH = 11.0
"""Width of one drawn sheet (inches)."""
PLAN_LABEL_INCH = 1.1
"""The plan is drawn so that the median panel is this wide (inches): its id fits inside."""
PLAN_MIN_PT = 4.5
"""The smallest id on the layout plan picture (points): every beam's, a small panel's."""
PLAN_MAX_PT = 9.0
"""The largest panel id on the layout plan picture (points)."""


def sheet_drawings(batches: list[dict], most: int = 2) -> list[dict]:
    """The sheets to draw: the fullest sheet (best yield) of the glass batch with the most parts and of the steel
    batch with the most parts (at most ``most``).  Each: ``id, size (W, H), margin, kerf, yield,
    parts, thickness_mm, material, outlines [(id, (k, 2) mm on the sheet)]``."""
    from fabricate.export.dxf import _placed
    from fabricate.export.nesting import sheet_gap

    out = []
    for material in ("glass", "steel"):
        mine = [b for b in batches if b["material"] == material and b["layout"].sheets]
        if not mine or len(out) >= most:
            continue
        b = max(mine, key=lambda b: len(b["layout"].ids))
        lay, parts = b["layout"], b["parts"]
        s = int(np.argmax(lay.utilisation))                 # the fullest sheet (best yield)
        outlines = []
        for gi in np.unique(lay.group[lay.sheet == s]).tolist():  # a few groups on one sheet
            g = parts.groups[gi]
            rows = np.nonzero((lay.sheet == s) & (lay.group == gi))[0]
            idx = lay.index[rows]
            P = g.flat[idx]
            placed = _placed(lay, rows, g.rect[idx, 1], P)
            placed[..., 0] -= s * (lay.size[0] + sheet_gap(lay))
            outlines += [(g.ids[i], q) for i, q in zip(idx.tolist(), placed)]
        out.append({"id": lay.sheet_id(s), "size": lay.size, "margin": lay.margin, "kerf": lay.kerf,
                    "yield": float(lay.utilisation[s]), "parts": len(outlines), "of_sheets": lay.sheets,
                    "thickness_mm": b["thickness_mm"], "material": material, "file": b["stem"] + ".dxf",
                    "outlines": outlines})
    return out


def picture_sheets(sheets: list[dict], path: str | Path, *, title: str) -> Path:
    """One row per sheet of :func:`sheet_drawings`: the sheet, its margin (dashed), the parts with their ids."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Rectangle

    if not sheets:
        fig = _figure((7.0, 3.0))
        ax = fig.add_subplot(111)
        ax.text(0.5, 0.5, "no nested sheets (outputs.cut_files off)", ha="center", va="center",
                transform=ax.transAxes)
        ax.set_axis_off()
        return _save(fig, path)
    heights = [SHEET_INCH * s["size"][1] / s["size"][0] for s in sheets]
    fig = _figure((SHEET_INCH + 0.6, sum(heights) + 0.9 * len(sheets) + 0.4))
    total = fig.get_figheight()
    top = total - 0.4
    for s, h in zip(sheets, heights):  # one or two sheets
        W, H = s["size"]
        ax = fig.add_axes((0.3 / fig.get_figwidth(), (top - h - 0.55) / total, SHEET_INCH / fig.get_figwidth(),
                           h / total))
        top -= h + 0.9
        ax.add_patch(Rectangle((0, 0), W, H, facecolor=(0.96, 0.96, 0.93), edgecolor="k", lw=0.8))
        m = s["margin"]
        ax.add_patch(Rectangle((m, m), W - 2 * m, H - 2 * m, fill=False, edgecolor="0.5", lw=0.5, ls="--"))
        colour = (0.78, 0.88, 0.96, 1.0) if s["material"] == "glass" else (0.78, 0.79, 0.82, 1.0)
        polys = [q for _, q in s["outlines"]]
        ax.add_collection(PolyCollection(polys, facecolors=colour, edgecolors="k", linewidths=0.4))
        pt = 72.0 * SHEET_INCH / W                                  # points per mm on this drawing
        lo = np.array([q.min(axis=0) for q in polys])
        size = np.array([q.max(axis=0) for q in polys]) - lo
        ids = [pid for pid, _ in s["outlines"]]
        fs, turned = upright_or_turned(size[:, 0] * pt, size[:, 1] * pt, ids)
        labels = [(pid, lo_ + 0.5 * sz, f / pt, t) for pid, lo_, sz, f, t in zip(ids, lo, size, fs, turned) if f > 0]
        if labels:
            ax.add_artist(_id_patch(labels))
        ax.set_xlim(-0.01 * W, 1.01 * W)
        ax.set_ylim(-0.01 * W, H + 0.01 * W)
        ax.set_aspect("equal")
        ax.set_axis_off()
        small = int(np.sum(fs == 0))
        note = f"; {small} ids too small to draw here" if small else ""
        ax.set_title(f"{s['id']} ({s['file']}, sheet of {s['of_sheets']}): {s['material']} {s['thickness_mm']:g} mm, "
                     f"{W:g} x {H:g} mm, margin {m:g} mm, kerf {s['kerf']:g} mm, {s['parts']} parts, "
                     f"yield {100 * s['yield']:.1f} %{note}", fontsize=8, loc="left")
    fig.suptitle(title, fontsize=10, x=0.02, ha="left")
    return _save(fig, path)


def plan_drawing(parts) -> dict:
    """The layout plan as arrays: ``panels [(unit id, (k, 2))]``, ``beams [(id, (2, 2))]`` in plan (x, y, mm)
    (the same as ``layout_plan.dxf``: :func:`fabricate.export.cutfiles.plan_items`)."""
    from fabricate.export.cutfiles import plan_items

    panels, beams = [], []
    for it in plan_items(parts):
        if it["kind"] == "beam":
            beams.append((it["text"], it["segment"]))
        else:
            panels.append((it["text"], it["polygon"]))
    return {"panels": panels, "beams": beams}


def plan_layout(plan: dict) -> dict:
    """How :func:`picture_plan` draws ``plan``: ``inch_per_mm``, ``lo``, ``hi`` (mm) and the ``labels`` of
    :func:`fabricate.export.plan_labels.place_labels` in mm, sized from points: a panel's id up to
    :data:`PLAN_MAX_PT` as it fits, a beam's :data:`PLAN_MIN_PT` (none smaller), their ink boxes
    (:func:`~fabricate.report.pictures.glyph_extent`) apart."""
    from fabricate.export.plan_labels import place_labels

    from .pictures import glyph_extent

    panels, beams = plan["panels"], plan["beams"]
    allp = np.concatenate([q for _, q in panels] + [q for _, q in beams]) if panels or beams else np.zeros((1, 2))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = np.maximum(hi - lo, 1.0)
    sizes = np.array([np.ptp(q, axis=0) for _, q in panels]) if panels else np.ones((1, 2))
    inch_per_mm = PLAN_LABEL_INCH / max(float(np.median(sizes.max(axis=1))), 1e-9)
    inch_per_mm = min(max(inch_per_mm, 11.0 / float(span.max())), MAX_SHEET_INCH / float(span.max()))
    pt = 72.0 * inch_per_mm                                            # points per mm on the drawing
    items = ([{"text": i, "kind": "panel", "polygon": q, "anchor": q.mean(axis=0)} for i, q in panels]
             + [{"text": i, "kind": "beam", "segment": q, "anchor": q.mean(axis=0)} for i, q in beams])
    labels = place_labels(items, glyph_extent, PLAN_MIN_PT / pt, PLAN_MAX_PT / pt, beam_size=PLAN_MIN_PT / pt)
    return {"inch_per_mm": inch_per_mm, "lo": lo, "hi": hi, "labels": labels}


def picture_plan(plan: dict, path: str | Path, *, title: str) -> Path:
    """The layout plan: panels (light blue) with their unit ids, beams (grey lines) with theirs, plan view.

    The drawing is scaled so the median panel is :data:`PLAN_LABEL_INCH` wide (7 to
    :data:`~fabricate.report.pictures.MAX_SHEET_INCH` inches, at least 11); the ids are placed by
    :func:`plan_layout`: inside their panel, beside their beam, or on a leader, never on top of one
    another; the title counts the leaders and the ids left out."""
    from matplotlib.collections import LineCollection, PolyCollection

    from fabricate.export.plan_labels import label_counts

    panels, beams = plan["panels"], plan["beams"]
    lay = plan_layout(plan)
    lo, hi, inch_per_mm = lay["lo"], lay["hi"], lay["inch_per_mm"]
    span = np.maximum(hi - lo, 1.0)
    fig = _figure((float(span[0] * inch_per_mm) + 1.0, float(span[1] * inch_per_mm) + 1.2))
    ax = fig.add_axes((0.5 / fig.get_figwidth(), 0.5 / fig.get_figheight(),
                       1 - 1.0 / fig.get_figwidth(), 1 - 1.2 / fig.get_figheight()))
    ax.add_collection(PolyCollection([q for _, q in panels], facecolors=(0.82, 0.9, 0.97, 1.0),
                                     edgecolors=(0.3, 0.45, 0.6, 1.0), linewidths=0.4))
    ax.add_collection(LineCollection([q for _, q in beams], colors=(0.35, 0.35, 0.38, 1.0), linewidths=0.9))
    placed = [lab for lab in lay["labels"] if lab["how"] != "skipped"]
    leaders = [lab["leader"] for lab in placed if lab["leader"] is not None]
    if leaders:
        ax.add_collection(LineCollection(leaders, colors=(0.2, 0.2, 0.2, 1.0), linewidths=0.3))
    if placed:
        ax.add_artist(_id_patch([(lab["text"], lab["centre"], lab["size"]) for lab in placed]))
    pad = 0.02 * float(span.max())
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    counts = label_counts(lay["labels"])
    note = ", ".join(t for t in (f"{counts['leader']} ids on leaders" if counts["leader"] else "",
                                 f"{counts['skipped']} ids left out: no free room near their part" if counts["skipped"]
                                 else "") if t)
    ax.set_title(f"{title}: {len(panels)} glass units, {len(beams)} beams, plan view"
                 + (f" ({note})" if note else ""), fontsize=10)
    return _save(fig, path)
