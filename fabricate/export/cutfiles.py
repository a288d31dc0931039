"""Cut files by material and thickness, nested on stock sheets, and the layout plan of the roof.

``write_cut_files`` writes, for every material and thickness (glass panels of
each thickness, steel plates of each thickness: beam plates and the cap plates of
tube hubs together), ``cut_<material>_<t>mm.dxf``
and ``.svg``: the parts nested on the material's stock sheets
(:func:`fabricate.export.nesting.layout`: sheet size, margin, kerf,
rotation), every sheet framed on layer SHEET with its id
(``GLASS-10-S01``), its part count and its yield.  A part larger than the
sheet is not nested: it is listed under ``oversize`` (and, for glass, flagged
by the sheet limit); ``outlines.dxf`` still draws it.

``write_layout_plan`` writes ``layout_plan.dxf``: the roof seen from above
(model x, y in mm), every glass unit's bearing outline (layer PANELS, the unit id) and every
beam's glass-side edge (layer BEAMS) with its id where it sits, readable at the plot scale and
never on top of another id (:mod:`fabricate.export.plan_labels`).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from .nesting import layout

MATERIAL = {"panel": "glass", "beam": "steel", "node": "steel"}


def _batches(parts):
    """``[(material, thickness_mm, kinds)]`` of the parts cut from sheet, in order: one batch per material
    and thickness, whatever kind the parts are (a 12 mm flange and a 12 mm hub cap share the 12 mm
    plate).  A glass unit's interlayers are not cut from sheet: they come from the roll and are trimmed
    after laminating; a hub tube is ordered as a section (:func:`fabricate.cad.parts.cut_from_sheet`)."""
    from fabricate.cad.parts import cut_from_sheet

    seen: dict[tuple[str, float], list[str]] = {}
    for g in parts.groups:
        if g.kind in MATERIAL and len(g) and not g.material and cut_from_sheet(g.kind, g.member):
            kinds = seen.setdefault((MATERIAL[g.kind], round(float(g.thickness_mm[0]), 3)), [])
            if g.kind not in kinds:
                kinds.append(g.kind)
    return [(m, t, tuple(kinds)) for (m, t), kinds in seen.items()]


def nest_cut_files(parts, nesting: dict) -> list[dict]:
    """Every material and thickness nested on its sheets (no file written).

    nesting : ``{"glass": {"sheet_mm", "margin_mm", "kerf_mm", "rotation"}, "steel": {...}}``.
    Returns ``[{"stem", "material", "thickness_mm", "kind", "kinds", "layout", "parts", "oversize"}]``: the
    :class:`~fabricate.export.nesting.Layout` of ``parts`` (the parts of that batch that fit a sheet);
    ``kinds`` the part kinds on it (``("beam", "node")``: beam plates and hub caps), ``kind`` the first.
    """
    import dataclasses

    from fabricate.cad.parts import cut_from_sheet

    sheet_parts = dataclasses.replace(parts, groups=tuple(g for g in parts.groups if not g.material))
    out = []
    for material, t, kinds in _batches(parts):
        opts = nesting[material]
        W, H = (float(v) for v in opts["sheet_mm"])
        margin, kerf = float(opts["margin_mm"]), float(opts["kerf_mm"])
        rot = bool(opts["rotation"])
        big = []
        for g in sheet_parts.groups:  # parts that fit no sheet are listed, not nested
            if g.kind in kinds and cut_from_sheet(g.kind, g.member) and np.isclose(g.thickness_mm[0], t):
                w, h = g.rect[:, 0] + 2 * margin, g.rect[:, 1] + 2 * margin
                fits = ((w <= W) & (h <= H)) | (rot & (w <= H) & (h <= W))
                big += [i for i, ok in zip(g.ids, fits) if not ok]
        sub = sheet_parts if not big else _without(sheet_parts, set(big))
        stem = f"cut_{material}_{t:g}mm"
        name = f"{material.upper()}-{t:g}"
        try:
            lay = layout(sub, (W, H), margin, kerf=kerf, rotation=rot, kinds=kinds, thickness=t, name=name)
        except ValueError as exc:
            raise ExportError(f"{stem}: nesting failed ({exc})") from None
        out.append({"stem": stem, "material": material, "thickness_mm": t, "kind": kinds[0], "kinds": kinds,
                    "layout": lay, "parts": sub, "oversize": big})
    return out


def write_cut_files(parts, folder, nesting: dict, batches: list[dict] | None = None) -> dict:
    """Every material and thickness nested on its sheets: DXF and SVG per batch (atomic, each).

    nesting : as :func:`nest_cut_files`; batches : its result when already nested.
    Returns ``{file name: facts}`` (the DXF's facts carry the layout: sheets with ids and yields).
    """
    from .dxf import write_dxf
    from .svg import write_svg

    folder = Path(folder)
    out = {}
    for b in batches if batches is not None else nest_cut_files(parts, nesting):
        stem, lay, sub = b["stem"], b["layout"], b["parts"]
        facts = write_dxf(sub, folder / f"{stem}.dxf", lay=lay)
        facts.update(material=b["material"], thickness_mm=b["thickness_mm"], oversize=b["oversize"])
        out[f"{stem}.dxf"] = facts
        out[f"{stem}.svg"] = dict(write_svg(sub, folder / f"{stem}.svg", lay=lay), material=b["material"],
                                  thickness_mm=b["thickness_mm"])
    return out


def _without(parts, drop: set):
    """A view of ``parts`` without the ids in ``drop`` (groups filtered; used for the oversize parts)."""
    import dataclasses

    groups = []
    for g in parts.groups:
        keep = np.array([i not in drop for i in g.ids])
        if keep.all():
            groups.append(g)
            continue
        if not keep.any():
            continue
        changes = {}
        for f in dataclasses.fields(g):
            v = getattr(g, f.name)
            if isinstance(v, np.ndarray) and v.ndim >= 1 and len(v) == len(g) and f.name != "cuts":
                changes[f.name] = v[keep]
            elif f.name in ("ids", "neighbours"):
                changes[f.name] = tuple(x for x, k in zip(v, keep) if k)
            elif f.name == "flat_faces":
                changes[f.name] = tuple(a[keep] for a in v)
        groups.append(dataclasses.replace(g, **changes))
    return dataclasses.replace(parts, groups=tuple(groups))


def plan_groups(parts) -> list[tuple]:
    """``[(group, ids)]`` the layout plan draws: per glass unit its ply on the beams, labelled with the
    unit id (``P0001``), and every beam."""
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.parts import unit_id

    from .schedules import beam_units

    out = [(g, tuple(unit_id(i) for i in g.ids)) for g in bearing_groups(parts) if len(g)]
    return out + [(g, tuple(unit_id(i) for i in g.ids)) for g in beam_units(parts) if len(g)]  # a beam once


def plan_items(parts) -> list[dict]:
    """The layout plan's parts in plan (model x, y, mm) as :func:`fabricate.export.plan_labels.place_labels`
    takes them: per glass unit its bearing outline (``polygon``, its unit id), per beam its glass-side
    edge A0 B0 (``segment``)."""
    out = []
    for g, ids in plan_groups(parts):
        P = g.vertices[:, list(g.ring)][..., :2]
        if g.kind == "beam":
            C = g.centre_line if g.centre_line is not None else g.vertices[:, :4]
            S = C[:, :2, :2]                               # the glass-side edge A0 B0
            out += [{"text": pid, "kind": "beam", "segment": S[i], "anchor": S[i].mean(axis=0)}
                    for i, pid in enumerate(ids)]
        else:
            out += [{"text": pid, "kind": "panel", "polygon": P[i], "anchor": P[i].mean(axis=0)}
                    for i, pid in enumerate(ids)]
    return out


def write_layout_plan(parts, path) -> dict:
    """``layout_plan.dxf``: every panel and beam with its id where it sits on the roof (plan view, mm).

    The ids are placed by :func:`fabricate.export.plan_labels.place_labels` for the plot scale
    :func:`~fabricate.export.plan_labels.plot_scale` chooses (text at least 2.5 mm on paper): a panel's id
    inside it, scaled to it; a beam's beside its line; where neither fits, on a free spot nearby with a
    leader (layer LEADERS); the label boxes never overlap.  The scale and the counts are in the facts and
    in a note (MTEXT, layer TITLE) under the plan."""
    import ezdxf

    from .plan_labels import PAPER_TEXT_MM, dxf_measure, label_counts, panel_fits, place_labels, plot_scale

    t0 = time.perf_counter()
    path = Path(path)
    doc = ezdxf.new("R2010", units=ezdxf.units.MM)
    for name, colour in (("PANELS", 4), ("BEAMS", 8), ("IDS", 5), ("LEADERS", 5), ("TITLE", 7)):
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    items = plan_items(parts)
    shapes = [it["polygon"] if it["kind"] == "panel" else it["segment"] for it in items]
    allp = np.concatenate(shapes) if shapes else np.zeros((1, 2))
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fits = panel_fits(items, dxf_measure)
    scale = plot_scale(lo, hi, float(np.median(fits)) if len(fits) else float(np.ptp(allp[:, 0])))
    size = PAPER_TEXT_MM * scale
    labels = place_labels(items, dxf_measure, size, 3 * size)
    for it, lab in zip(items, labels):  # ezdxf entities per part (a plan, not a cut file)
        if it["kind"] == "panel":
            msp.add_lwpolyline(it["polygon"].tolist(), close=True, dxfattribs={"layer": "PANELS"})
        else:
            msp.add_lwpolyline(it["segment"].tolist(), close=False, dxfattribs={"layer": "BEAMS"})
        if lab["how"] == "skipped":
            continue
        msp.add_text(lab["text"], height=lab["size"], dxfattribs={"layer": "IDS"}).set_placement(
            tuple(lab["centre"]), align=ezdxf.enums.TextEntityAlignment.MIDDLE_CENTER)
        if lab["leader"] is not None:
            msp.add_line(*(tuple(p) for p in lab["leader"]), dxfattribs={"layer": "LEADERS"})
    counts = label_counts(labels)
    note = (f"LAYOUT PLAN (plan view, mm), plot at 1:{scale}: ids {PAPER_TEXT_MM:g} to {3 * PAPER_TEXT_MM:g} mm "
            f"on paper; {counts['inside']} inside their panel, {counts['beside']} beside their beam, "
            f"{counts['leader']} on a leader, {counts['skipped']} left out")
    msp.add_mtext(note, dxfattribs={"layer": "TITLE", "char_height": size}).set_location(
        (float(lo[0]), float(lo[1]) - 3 * size))
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
            doc.write(fh)
    except OSError as exc:
        raise write_error(path, "layout plan", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "parts": len(items), "view": "plan (model x, y), mm",
            "plot_scale": f"1:{scale}", "text_mm": [size, 3 * size], "labels": counts,
            "seconds": time.perf_counter() - t0}
