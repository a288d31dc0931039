"""The glass order a processing plant takes as it is: positions, drawings, labels, racks (issue 36).

``glass_order.csv`` has one row per *position*: a group of glass units of one
shape within :data:`fabricate.cad.congruence.TOLERANCE_MM` at every corner of
every ply, mirror images a position of their own (the other *hand*: a unit
turned over puts its coatings and laminate on the wrong side).  A row gives the
quantity, the unit ids it covers, the build-up per ply (thickness, heat
treatment and its product standard, edge work, coatings by surface, the blank
that holds that ply on every unit of the position), the interlayer, cavity,
gas and fill, spacer and colour, edge seal and secondary seal of an insulated
unit, the edges and corners of the drawing, area and weight per unit and in
all, the tolerances and standards, label text and place, and where the
setting blocks go.

``glass_order/<position>.dxf`` (AutoCAD R12, millimetres, the order systems'
safe version) draws the position: layer ``OUTLINE`` the cut outline of the outer
ply and nothing else, ``PLY<k>`` the cut outline of every other ply,
``BEARING`` the bearing line of every ply (where its edge bevels start),
``DIMENSIONS`` the edge lengths, ``TEXT`` the edge numbers ``E1 ..`` (those of
``glass_schedule.csv``, from the reference corner ``1``, marked by a circle),
the position and its quantity.  ``glass_order/<position>.svg`` is the same
sheet to check by eye.  ``glass_order/labels.csv`` has a row per unit: its
position, how it lies on the drawing (which of its corners is the drawing's
corner 1), the label text and place, the orientation mark, the setting blocks,
and the delivery (:mod:`fabricate.export.glass_delivery`): install order along
the roof's long plan axis, the zone, the rack and the slot on it.
``glass_order/racks.csv`` lists the racks by zone in install order (units, their
ids front first, weight within the rack limit); ``glass_order/labels_<rack>.svg``
is the rack's A4 sheet of labels, one per unit with a QR code of its id
(:mod:`fabricate.export.glass_labels`).

Hand ``A`` is drawn as the position's first unit; hand ``B`` as its exact
mirror image, so every unit of a position is within the tolerance of its
drawing (:func:`fabricate.export.check_glass_order.check_glass_order` reads
the files back and holds them to the flat data).
"""
from __future__ import annotations

import csv
import io
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from fabricate.cad.congruence import HANDS, TOLERANCE_MM, mirror_rings
from fabricate.export.glass_delivery import RACK_COLUMNS, RACK_KG, RACK_UNITS, ZONE_MM, rack_name, rack_rows, sequence

FOLDER = "glass_order"
BLOCK_MM = 100.0
"""Setting block length along the edge (DIN 18545 / ift guideline: 80 to 100 mm)."""
LABEL_INSET_MM = 30.0
"""The label's distance from both edges at the drawing's corner 1."""
TOLERANCES = ("edge lengths and diagonals to the product standard of each ply's treatment (EN 572-2, EN 1863-1, "
              "EN 12150-1, EN 14179-1); laminated offset per EN ISO 12543-5; insulated unit per EN 1279-1")


def order_columns(n_plies: int) -> tuple[str, ...]:
    """The columns of ``glass_order.csv`` for a build-up of ``n_plies`` glass plies."""
    ply = [f"ply{k}_{c}" for k in range(1, n_plies + 1) for c in
           ("thickness_mm", "treatment", "standard", "edge_work", "coatings", "blank_w_mm", "blank_h_mm")]
    return ("position", "shape", "hand", "quantity", "units", "build_up", "build_up_text", "unit_thickness_mm",
            "plies", *ply, "interlayers", "cavity_mm", "gas", "gas_fill_pct", "spacer", "spacer_colour",
            "edge_seal_mm", "secondary_seal", "step_mm", "blank_w_mm", "blank_h_mm", "area_m2", "weight_kg",
            "total_area_m2", "total_weight_kg", "edge_lengths_mm", "corner_angles_deg", "edge_bevels_deg",
            "shape_tolerance_mm", "max_deviation_mm", "tolerances", "standards", "label_text", "label_position",
            "setting_blocks", "drawing")


LABEL_COLUMNS = ("id", "position", "shape", "hand", "face", "drawing_corner_1", "install_seq", "zone", "rack",
                 "rack_slot", "label_text", "label_position", "orientation_mark", "label_sheet", "setting_block_edge",
                 "setting_blocks_mm", "weight_kg", "x_mm", "y_mm", "z_mm")


def _num(values, fmt: str = "{:.1f}") -> str:
    return " ".join(fmt.format(float(v)) for v in values)


def positions(parts, tol: float = TOLERANCE_MM) -> dict:
    """The order's positions, JSON-free arrays: ``ids (u,)`` unit ids, ``element (u,)`` faces, ``name (u,)``
    position of each unit, ``shape (u,)``, ``hand (u,)``, ``corner1 (u,)`` the unit's corner on the
    drawing's corner 1, ``deviation (u,)`` mm from its drawing, ``rows`` list of per-position dicts
    (``name, shape, hand, members (q,), rings (n, k, 2)`` the drawing in mm from its lower left,
    ``bevel (k, 2)``), ``n_rings``."""
    from fabricate.cad.congruence import glass_unit_rings, merge, ring_classes, ring_deviation

    ids, element, subsets = glass_unit_rings(parts)
    c = merge([(index, ring_classes(X, tol)) for index, X in subsets], len(ids))
    names = c.names("G")
    rings_of = {}
    for index, X in subsets:  # a few corner counts
        for j, i in enumerate(index.tolist()):
            rings_of[i] = (X, j)
    rows: dict[str, dict] = {}
    corner1 = np.zeros(len(ids), dtype=np.int64)
    dev = np.zeros(len(ids))
    for u in range(len(ids)):  # units grouped into their positions (bookkeeping; the fits are per position)
        rows.setdefault(names[u], {"name": names[u], "shape": int(c.label[u]), "hand": int(c.hand[u]),
                                   "members": []})["members"].append(u)
    for row in rows.values():  # one fit per position
        leader = int(c.first[row["shape"]])
        X, j = rings_of[leader]
        drawing = X[j] if row["hand"] == 0 else mirror_rings(X[j])
        members = np.asarray(row["members"])
        Y = np.stack([rings_of[m][0][rings_of[m][1]] for m in members.tolist()])
        d, s = ring_deviation(drawing, Y)
        corner1[members], dev[members] = s, d
        low = drawing.reshape(-1, 2).min(axis=0)
        row.update(members=members, rings=drawing - low, deviation=float(d.max()))
    return {"ids": ids, "element": element, "name": names, "shape": c.label, "hand": c.hand,
            "corner1": corner1, "deviation": dev, "rows": list(rows.values()), "classes": c}


def _ply_blanks(parts, element: np.ndarray) -> np.ndarray:
    """(u, n_plies, 2) each unit's blank per glass ply (``PartGroup.rect``), outside in."""
    plies = parts.spec.glass.plies()
    solids = parts.spec.glass.solids()
    members = [m.member if len(solids) > 1 else "" for m in solids if m.material == "glass"]  # one solid: ""
    row = np.full(1 + int(element.max()), -1, dtype=np.int64)
    row[element] = np.arange(len(element))
    out = np.zeros((len(element), len(plies), 2))
    for g in parts.of_kind("panel"):  # a few groups
        if g.material or g.member not in members:
            continue
        out[row[g.element], members.index(g.member)] = g.rect
    return out


def _setting_blocks(parts, pos: dict) -> tuple[np.ndarray, np.ndarray]:
    """Per unit the drawing's edge (0-based) that is lowest once installed (its midpoint lowest in the
    model) and the block centres from that edge's start corner (mm): at a tenth of the edge, at least
    ``BLOCK_MM`` from each corner."""
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.limits import edge_lengths

    n = len(pos["ids"])
    low_edge = np.zeros(n, dtype=np.int64)
    length = np.zeros(n)
    start = 0
    for g in bearing_groups(parts):  # units in the order of glass_unit_rings
        k = len(g.ring)
        P = g.vertices[:, list(g.ring)]
        mid_z = 0.5 * (P[:, :, 2] + np.roll(P, -1, axis=1)[:, :, 2])
        e = mid_z.argmin(axis=1)                                        # the unit's own edge numbering
        sel = np.arange(start, start + len(g))
        s = pos["corner1"][sel]
        mirrored = pos["hand"][sel] == 1
        low_edge[sel] = np.where(mirrored, (e + s) % k, (e - s) % k)     # in the drawing's numbering
        length[sel] = edge_lengths(g.bevel_ref)[np.arange(len(g)), e]
        start += len(g)
    at = np.maximum(np.maximum(0.1 * length, BLOCK_MM), 0.0)
    return low_edge, np.stack([at, np.maximum(length - at, at)], axis=1)


def _sequence(parts, pos: dict, weight: np.ndarray, rack_kg: float, rack_units: int, zone_mm: float) -> dict:
    """:func:`fabricate.export.glass_delivery.sequence` of the units of ``pos`` (their mesh faces'
    centres, the median face's side as the row width), with ``centre (u, 3)``."""
    mesh = parts.mesh
    n = len(pos["ids"])
    if mesh is None:  # no plan: one row, in id order
        C = np.zeros((n, 3))
        C[:, 0] = np.arange(n)
        size = 1.0
    else:
        C = _centres(mesh, pos["element"])
        size = float(np.sqrt(np.maximum(np.median(mesh_face_area(mesh, pos["element"])), 1.0)))
    return dict(sequence(C, weight, size, rack_kg, rack_units, zone_mm), centre=C)


def _centres(mesh, faces: np.ndarray) -> np.ndarray:
    sizes = mesh.face_sizes[faces]
    P = mesh.V[np.maximum(mesh.F[faces], 0)]
    mask = np.arange(P.shape[1])[None, :] < sizes[:, None]
    return (P * mask[..., None]).sum(axis=1) / sizes[:, None]


def mesh_face_area(mesh, faces: np.ndarray) -> np.ndarray:
    from optimize.mesh import measures

    return measures.face_areas(mesh)[faces]


def write_glass_order(parts, path, tol: float = TOLERANCE_MM, *, rack_kg: float = RACK_KG,
                      rack_units: int = RACK_UNITS, zone_mm: float = ZONE_MM) -> dict:
    """Write ``glass_order.csv`` at ``path`` and ``glass_order/`` beside it (one DXF and SVG per position,
    ``labels.csv``, ``racks.csv``, a label sheet per rack), each file atomic.  ``rack_kg``,
    ``rack_units``, ``zone_mm``: the delivery's limits (:mod:`fabricate.export.glass_delivery`).
    Returns facts: ``file, bytes, rows, positions, shapes, units, racks, zones, heaviest_rack_kg, folder,
    files, seconds``."""
    from fabricate.export.glass_labels import write_label_sheets

    from fabricate.cad.glass import EDGES, TREATMENTS, unit_blank, unit_sums
    from fabricate.cad.limits import corner_angles_deg, edge_lengths

    t0 = time.perf_counter()
    path = Path(path)
    folder = path.parent / FOLDER
    spec = parts.spec
    glass = spec.glass
    plies = glass.plies()
    pos = positions(parts, tol)
    if not len(pos["ids"]):
        raise ExportError(f"{path}: no glass units: nothing to order")
    element = pos["element"]
    weight_all = unit_sums(parts, lambda g: g.volume_mm3 * spec.group_density(g) * 1e-9)
    weight = weight_all[element]
    blank_all = unit_blank(parts)[element]
    ply_blank = _ply_blanks(parts, element)
    low_edge, blocks = _setting_blocks(parts, pos)
    seq = _sequence(parts, pos, weight, rack_kg, rack_units, zone_mm)
    last = plies[-1].surfaces[1]
    label_place = (f"surface #{last} (inside face), at the drawing's corner 1, {LABEL_INSET_MM:g} mm in from both "
                   "edges")
    mark = ("arrow on the label along edge E1 from corner 1; 'OUTSIDE #1' on the weather face: #1 faces the "
            "weather, the bearing ply the beams")
    inter = []
    for side, p in (("outer", glass.outer), ("inner", glass.inner)):
        if p is not None and p.laminated:
            inter.append(f"{(side + ' ') if glass.inner is not None else ''}{p.interlayer_mm:g} {p.interlayer}")
    igu = glass.type == "insulated"
    try:
        folder.mkdir(exist_ok=True)
    except OSError as exc:
        raise write_error(folder, "glass order folder", exc) from exc
    files: list[str] = []
    rows = []
    for row in pos["rows"]:  # one row, DXF and SVG per position
        m = row["members"]
        R = row["rings"]
        ref = R[1]                                                       # ply 1's bearing line: the edges
        L, A = edge_lengths(ref[None])[0], corner_angles_deg(ref[None])[0]
        first = int(m[0])
        bevels = _bevels(parts, int(element[first]), row["hand"] == 1, int(pos["corner1"][first]))
        pb = ply_blank[m].max(axis=0)                                    # (n_plies, 2): holds every unit's ply
        ply_cols = []
        for k, p in enumerate(plies):
            ply_cols += [f"{p.thickness_mm:g}", p.treatment, TREATMENTS[p.treatment][1],
                         f"{p.edge} ({EDGES[p.edge][0]})", " ".join(f"#{s} {c}" for s, c in p.coatings),
                         f"{pb[k, 0]:.1f}", f"{pb[k, 1]:.1f}"]
        blank = blank_all[m].max(axis=0)
        area = float(_area(ref))
        w = float(weight[m].mean())
        edges = np.bincount(low_edge[m], minlength=len(ref))
        block_text = "; ".join(f"E{e + 1} x{int(c)}" for e, c in enumerate(edges.tolist()) if c)
        block_text = (f"{BLOCK_MM:g} mm blocks under the lowest edge as installed ({block_text}; per unit: "
                      f"{FOLDER}/labels.csv), at a tenth of the edge and at least {BLOCK_MM:g} mm from its corners")
        name = row["name"]
        hand = HANDS[row["hand"]] if name[-1] in HANDS else ""
        label = f"<unit id> | {name} | {glass.short()} | #1 OUTSIDE"
        rows.append((name, f"G{name[1:].rstrip('AB')}", hand, len(m), " ".join(pos["ids"][i] for i in m.tolist()),
                     glass.short(), glass.describe(), f"{glass.thickness_mm:.2f}", len(plies), *ply_cols,
                     "; ".join(inter), f"{glass.cavity_mm:g}" if igu else "", glass.gas if igu else "",
                     f"{glass.gas_fill_pct:g}" if igu else "", glass.spacer, glass.spacer_colour,
                     f"{glass.edge_seal_mm:g}" if igu else "", glass.secondary_seal,
                     f"{glass.step_mm:g}" if igu else "", f"{blank[0]:.1f}", f"{blank[1]:.1f}",
                     f"{area * 1e-6:.4f}", f"{w:.1f}", f"{area * 1e-6 * len(m):.3f}", f"{weight[m].sum():.1f}",
                     _num(L), _num(A), _num(bevels.ravel(), "{:+.2f}"), f"{tol:g}", f"{row['deviation']:.3f}",
                     TOLERANCES, "; ".join(glass.standards()), label, label_place, block_text,
                     f"{FOLDER}/{name}.dxf"))
        facts = {"name": name, "quantity": len(m), "build_up": glass.short(), "blank": blank}
        _write_dxf(folder / f"{name}.dxf", R, facts)
        _write_svg(folder / f"{name}.svg", R, facts)
        files += [f"{name}.dxf", f"{name}.svg"]
    _write_csv(path, order_columns(len(plies)), rows)
    order = np.argsort(seq["seq"]).tolist()
    sheets = write_label_sheets(folder, [
        {"id": pos["ids"][u], "position": pos["name"][u], "rack": rack_name(seq["rack"][u]),
         "slot": int(seq["slot"][u]), "seq": int(seq["seq"][u]), "zone": int(seq["zone"][u]),
         "build_up": glass.short(), "weight_kg": float(weight[u])} for u in order])
    labels = []
    for u in order:  # in install order
        uid, name = pos["ids"][u], pos["name"][u]
        c = seq["centre"][u]
        rack = rack_name(seq["rack"][u])
        labels.append((uid, name, f"G{name[1:].rstrip('AB')}", HANDS[int(pos["hand"][u])] if name[-1] in HANDS else "",
                       int(element[u]), int(pos["corner1"][u]) + 1, int(seq["seq"][u]), int(seq["zone"][u]),
                       rack, int(seq["slot"][u]), f"{uid} | {name} | {glass.short()} | #1 OUTSIDE", label_place, mark,
                       " ".join(sheets[rack]), f"E{int(low_edge[u]) + 1}", _num(blocks[u]), f"{weight[u]:.1f}",
                       f"{c[0]:.1f}", f"{c[1]:.1f}", f"{c[2]:.1f}"))
    _write_csv(folder / "labels.csv", LABEL_COLUMNS, labels)
    racks = rack_rows(seq, pos["ids"], pos["name"], weight, blank_all,
                      {int(r[1:]): " ".join(v) for r, v in sheets.items()})
    _write_csv(folder / "racks.csv", RACK_COLUMNS, racks)
    files += ["labels.csv", "racks.csv"] + [f for v in sheets.values() for f in v]
    c = pos["classes"]
    return {"file": path.name, "bytes": path.stat().st_size, "rows": len(rows), "positions": len(rows),
            "shapes": c.count, "units": len(pos["ids"]), "racks": len(racks), "zones": int(seq["zone"].max()),
            "heaviest_rack_kg": max(float(r[7]) for r in racks), "rack_kg": float(rack_kg),
            "tolerance_mm": tol, "largest_deviation_mm": float(pos["deviation"].max()), "folder": FOLDER,
            "files": len(files), "seconds": time.perf_counter() - t0}


def _area(Q: np.ndarray) -> float:
    x, y = Q[:, 0], Q[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _bevels(parts, face: int, mirrored: bool, shift: int) -> np.ndarray:
    """(k, 2) the edge bevels (deg, [+z, -z] of the bearing ply) of the unit on ``face`` in the drawing's
    edge numbering (hand B: the drawing is the unit itself, its corners relabelled the other way)."""
    from fabricate.cad.glass import bearing_groups

    for g in bearing_groups(parts):  # a few groups
        hit = np.flatnonzero(g.element == face)
        if len(hit):
            b = g.bevel_deg[hit[0]]
            k = len(b)
            if not mirrored:
                return b[(np.arange(k) + shift) % k]
            return b[(np.arange(k) - shift) % k]
    return np.zeros((0, 2))


def _write_csv(path: Path, columns, rows) -> None:
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(columns)
    w.writerows(rows)
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            fh.write(buf.getvalue())
    except OSError as exc:
        raise write_error(path, "glass order", exc) from exc


LAYERS = {"OUTLINE": 7, "BEARING": 8, "DIMENSIONS": 3, "TEXT": 2}
"""DXF layers and their colours (ACI); ``PLY<k>`` (colour 5) for the other plies' outlines."""


def _write_dxf(path: Path, R: np.ndarray, facts: dict) -> None:
    """One position as DXF R12 (mm): rings ``R (2 n, k, 2)`` = per ply its cut outline and bearing line."""
    import logging

    import ezdxf

    log = logging.getLogger("ezdxf")
    level = log.level
    log.setLevel(logging.ERROR)                     # ezdxf.new warns that R12 has no $INSUNITS: mm is stated
    try:
        doc = ezdxf.new("R12")
    finally:
        log.setLevel(level)
    doc.header["$MEASUREMENT"] = 1                                      # metric
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    n = len(R) // 2
    for j in range(n):  # a few plies
        layer = "OUTLINE" if j == 0 else f"PLY{j + 1}"
        if j:
            doc.layers.add(layer, color=5)
        msp.add_polyline2d([tuple(map(float, p)) for p in R[2 * j]], close=True, dxfattribs={"layer": layer})
        msp.add_polyline2d([tuple(map(float, p)) for p in R[2 * j + 1]], close=True, dxfattribs={"layer": "BEARING"})
    _annotate(R[1], facts, lambda a, b: msp.add_line(a, b, dxfattribs={"layer": "DIMENSIONS"}),
              lambda text, at, h, layer: msp.add_text(text, dxfattribs={"layer": layer, "height": h, "insert": at}),
              lambda c, r: msp.add_circle(c, r, dxfattribs={"layer": "TEXT"}))
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
            doc.write(fh)
    except OSError as exc:
        raise write_error(path, "glass order drawing", exc) from exc


def _annotate(ref: np.ndarray, facts: dict, line, text, circle) -> None:
    """Edge numbers, dimension lines with lengths, corner 1 and the title: the same on DXF and SVG."""
    k = len(ref)
    size = float(np.ptp(ref, axis=0).max())
    h = max(size / 60.0, 10.0)
    centre = ref.mean(axis=0)
    for j in range(k):  # one edge each
        a, b = ref[j], ref[(j + 1) % k]
        d = b - a
        L = float(np.hypot(*d))
        out = np.array([d[1], -d[0]]) / max(L, 1e-9)                      # outward (ccw outline)
        off = 3.0 * h
        line(tuple(a + out * off), tuple(b + out * off))
        mid = 0.5 * (a + b)
        text(f"{L:.1f}", tuple(mid + out * (off + 0.5 * h)), h, "DIMENSIONS")
        text(f"E{j + 1}", tuple(mid - out * 2.0 * h), h, "TEXT")
    circle(tuple(ref[0] + (centre - ref[0]) * (2.0 * h / max(np.hypot(*(centre - ref[0])), 1e-9))), 0.8 * h)
    text("1", tuple(ref[0] + (centre - ref[0]) * (4.0 * h / max(np.hypot(*(centre - ref[0])), 1e-9))), h, "TEXT")
    blank = facts["blank"]
    text(f"{facts['name']}  {facts['quantity']} off  {facts['build_up']}  blank {blank[0]:.0f} x {blank[1]:.0f}",
         (float(ref[:, 0].min()), float(ref[:, 1].min()) - 8.0 * h), 1.5 * h, "TEXT")


def _write_svg(path: Path, R: np.ndarray, facts: dict) -> None:
    """The position's sheet as SVG (1 unit = 1 mm, y up as in the DXF)."""
    pts = R.reshape(-1, 2)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.15 * float((hi - lo).max()) + 50.0
    W, H = hi - lo + 2 * pad
    out = []

    def xy(p) -> str:
        return f"{p[0] - lo[0] + pad:.2f},{hi[1] - p[1] + pad:.2f}"

    def poly(P, style) -> str:
        return f'<polygon points="{" ".join(xy(p) for p in P)}" {style}/>'

    n = len(R) // 2
    for j in range(n):  # a few plies
        out.append(poly(R[2 * j], 'fill="none" stroke="#000" stroke-width="2"' if j == 0 else
                        'fill="none" stroke="#2060c0" stroke-width="1"'))
        out.append(poly(R[2 * j + 1], 'fill="none" stroke="#888" stroke-width="1" stroke-dasharray="12 8"'))

    def line(a, b):
        out.append(f'<line x1="{xy(a).split(",")[0]}" y1="{xy(a).split(",")[1]}" x2="{xy(b).split(",")[0]}" '
                   f'y2="{xy(b).split(",")[1]}" stroke="#080" stroke-width="1"/>')

    def text(t, at, h, layer):
        x, y = xy(at).split(",")
        colour = "#080" if layer == "DIMENSIONS" else "#a00"
        out.append(f'<text x="{x}" y="{y}" font-size="{h:.1f}" fill="{colour}" font-family="sans-serif">{t}</text>')

    def circle(c, r):
        x, y = xy(c).split(",")
        out.append(f'<circle cx="{x}" cy="{y}" r="{r:.1f}" fill="none" stroke="#a00" stroke-width="2"/>')

    _annotate(R[1], facts, line, text, circle)
    svg = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{W:.0f}mm" height="{H:.0f}mm" '
           f'viewBox="0 0 {W:.2f} {H:.2f}">\n<title>{facts["name"]}</title>\n' + "\n".join(out) + "\n</svg>\n")
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(svg)
    except OSError as exc:
        raise write_error(path, "glass order sheet", exc) from exc
