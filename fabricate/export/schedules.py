"""Schedules a glass supplier and a steel shop order from (CSV, mm, degrees, kg).

- ``glass_schedule.csv``: one row per glass unit (a panel, whatever its
  build-up): the build-up (``10/16/88.4`` and spelled out), its total
  thickness (cavity included), its solids (``P0001.1 ...``: plies and
  interlayers, outside in), the spacer setback of an insulated unit (edge
  seal width), area, the stock blank (the largest width and height over its
  plies: it holds every ply), per edge (in the order of the bearing face, counter-clockwise
  seen from the beams) its length, the corner angle at its start, its bevel
  (degrees from square, positive when the face away from the beams is the
  smaller one), the beam under it and the neighbouring panel across it;
  weight (every ply and interlayer: volume x density; spacer and seal not
  included), warp (mm: distance between the diagonals of the mesh face, the
  planarity times the mean diagonal; n-gons: twice the largest distance from
  the plane), the limits it breaks.
- ``steel_cut_list.csv``: one row per beam: section (``plate 60 x 212``,
  ``RHS 200x100x8``, ``T 200x120x10/12``: depth x width x web / flange, mm),
  ``member`` (``beam``), how many plates it is welded from, grade, length (node
  axis to node axis along the glass edge, or to the hub), both end cuts as
  mitre (in the plate, degrees from square, positive when the beam is longer
  on the glass side) and bevel (through the thickness, ``+`` and ``-`` side),
  the ridge under the glass, the dihedral between the two panels it carries
  (inside the beam; 180 flat), weight (all its plates), the limits it breaks.
  A section of several plates is followed by one row per plate (``B0012.1``
  ...: ``PL<t>``, the member it is, its stock blank and its own end cuts and
  weight).  A plate beam is one row, its own blank.  Then one row per hub
  (``N0001``, member ``hub``: ``tube hub CHS 160 x 8 + 2 caps PL12 24-gon D160``,
  length = hub height, weight of its pieces) and, for a tube hub, its tube
  (``N0001.1``: ``CHS 160 x 8``, length = the tube cut between the caps) and its
  two caps (``PL12``, their blank): :func:`hub_rows`.  ``bar``: on a beam's row and a hub tube's, the
  stock bar it is sawn from (``bar_cutting.csv``, :mod:`fabricate.export.bars`; ``splice needed``:
  longer than the longest stock bar).
- every schedule's ``type`` column names the part's type, the same for parts
  that are congruent within 1 mm (:mod:`fabricate.cad.congruence`): ``G007``
  a glass shape (``G007A`` / ``G007B`` its two mirror hands where both are
  made), ``BT012`` a beam type (its plates and its rows), ``NT003`` a node type
  (the hub rows of the cut list too): :func:`glass_types`, :func:`beam_types`,
  :func:`node_types`.
- ``node_schedule.csv``: one row per node: position, axis direction (glass
  toward beams), the incoming beams with their angle around the axis
  (azimuth, from the first one, counter-clockwise seen along the axis) and
  their elevation from the plane normal to the axis, the hub (text; outside
  diameter, tube wall and height in mm; empty without a hub).
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from fabricate.cad.geometry import polygon_area_2d
from fabricate.cad.limits import corner_angles_deg, edge_lengths

GLASS_COLUMNS = ("id", "face", "type", "build_up", "thickness_mm", "solids", "spacer_setback_mm", "area_m2", "blank_w_mm",
                 "blank_h_mm", "edge_lengths_mm", "corner_angles_deg", "edge_bevels_deg", "beams", "neighbours",
                 "weight_kg", "warp_mm", "planarity", "flags")
STEEL_COLUMNS = ("id", "edge", "type", "assembly", "section", "member", "plates", "grade", "length_mm",
                 "system_length_mm", "blank_w_mm", "blank_h_mm",
                 "end_a_mitre_deg", "end_a_bevel_deg", "end_b_mitre_deg", "end_b_bevel_deg", "top_bevel_deg",
                 "dihedral_deg", "weight_kg", "panels", "nodes", "flags", "bar")
NODE_COLUMNS = ("id", "vertex", "type", "assembly", "x_mm", "y_mm", "z_mm", "axis_x", "axis_y", "axis_z", "valence", "beams",
                "azimuth_deg", "elevation_deg", "hub", "hub_diameter_mm", "hub_wall_mm", "hub_height_mm")


def _flags(parts) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for key, entry in (parts.report.get("limits") or {}).items():
        for pid in entry.get("ids", []):
            out.setdefault(pid, []).append(f"{key} {entry['limit']}")
    return out


def _write(path: Path, columns, rows) -> int:
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(columns)
            n = 0
            for row in rows:  # one CSV row per part
                w.writerow(row)
                n += 1
    except OSError as exc:
        raise write_error(path, "schedule", exc) from exc
    return n


def _num(values, fmt: str = "{:.1f}") -> str:
    return " ".join(fmt.format(float(v)) for v in values)


def warp_mm(mesh, faces: np.ndarray) -> np.ndarray:
    """(q,) mm: distance between the diagonals of quad faces, twice the largest distance from the
    least-squares plane of other faces (``mesh`` in mm)."""
    sizes = mesh.face_sizes[faces]
    out = np.zeros(len(faces))
    q = sizes == 4
    if q.any():
        P = mesh.V[mesh.F[faces[q], :4]]
        d1, d2 = P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]
        c = np.cross(d1, d2)
        out[q] = np.abs(((P[:, 1] - P[:, 0]) * c).sum(axis=1)) / np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    for k in np.unique(sizes[~q]).tolist():  # one batch per other face size
        sel = np.nonzero(sizes == k)[0]
        P = mesh.V[mesh.F[faces[sel], :k]]
        C = P - P.mean(axis=1, keepdims=True)
        n = np.linalg.svd(C)[2][:, -1]
        out[sel] = 2 * np.abs(np.einsum("pki,pi->pk", C, n)).max(axis=1)
    return out


def mean_diagonal(mesh, faces: np.ndarray) -> np.ndarray:
    sizes = mesh.face_sizes[faces]
    P = mesh.V[np.maximum(mesh.F[faces], 0)]
    out = np.zeros(len(faces))
    for k in np.unique(sizes).tolist():  # per face size
        sel = np.nonzero(sizes == k)[0]
        Q = P[sel, :k]
        if k == 4:
            out[sel] = 0.5 * (np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1) + np.linalg.norm(Q[:, 3] - Q[:, 1], axis=1))
        else:
            out[sel] = np.linalg.norm(np.roll(Q, -1, axis=1) - Q, axis=2).mean(axis=1)
    return out


def build_up_text(spec) -> str:
    """The glass build-up as a supplier writes it (``insulated 10/16/88.4 (10 | 16 argon | 8 + 1.52 PVB + 8 ...)``)."""
    return spec.glass.describe()


def write_glass_schedule(parts, path) -> dict:
    """Write ``glass_schedule.csv`` (atomic).  Returns facts: ``file, bytes, rows, seconds``."""
    t0 = time.perf_counter()
    path = Path(path)
    from fabricate.cad.glass import bearing_groups, unit_blank, unit_sums
    from fabricate.cad.parts import unit_id

    flags: dict[str, list[str]] = {}
    for pid, fl in _flags(parts).items():  # a ply's flags are its unit's
        flags.setdefault(unit_id(pid), []).extend(f for f in fl if f not in flags.get(unit_id(pid), []))
    beam_panels: dict[str, list[str]] = {}   # the glass units each beam carries (on any of its plates)
    for g in parts.of_kind("beam"):
        for i, pid in enumerate(g.ids):
            got = beam_panels.setdefault(unit_id(pid), [])
            got += [unit_id(n) for n in g.neighbours[i] if n[0] == "P" and unit_id(n) not in got]
    spec = parts.spec
    build_up = build_up_text(spec)
    solids = spec.glass.solids()
    seal = f"{spec.glass.edge_seal_mm:g}" if spec.glass.type == "insulated" else ""
    mesh = parts.mesh
    weight_of = unit_sums(parts, lambda g: g.volume_mm3 * spec.group_density(g) * 1e-9)
    blank = unit_blank(parts)
    ids, names, _ = glass_types(parts)
    types = dict(zip(ids, names))

    def rows():
        for g in bearing_groups(parts):
            L, A = edge_lengths(g.bevel_ref), corner_angles_deg(g.bevel_ref)
            area = polygon_area_2d(g.bevel_ref)                # the glass (bearing face), not the blank
            side = g.cuts[:, 0] - 2                       # the side face (and beam) under each edge
            bevel = g.bevel_deg[..., 1]
            weight = weight_of[g.element]
            warp = warp_mm(mesh, g.element) if mesh is not None else 2 * g.planarity_mm
            diag = mean_diagonal(mesh, g.element) if mesh is not None else np.ones(len(g))
            for i, ply in enumerate(g.ids):
                pid = unit_id(ply)
                beams = [b for b in g.neighbours[i] if b[0] == "B"]
                beams = [beams[s] for s in side.tolist()]
                across = [next((p for p in beam_panels.get(b, []) if p != pid), "-") for b in beams]
                members = " ".join(f"{pid}.{k + 1}" for k in range(len(solids))) if len(solids) > 1 else pid
                yield (pid, int(g.element[i]), types.get(pid, ""), build_up, f"{spec.glass.thickness_mm:.2f}", members, seal,
                       f"{area[i] * 1e-6:.4f}", f"{blank[g.element[i], 0]:.1f}", f"{blank[g.element[i], 1]:.1f}",
                       _num(L[i]), _num(A[i]), _num(bevel[i], "{:+.2f}"), " ".join(beams), " ".join(across),
                       f"{weight[i]:.1f}", f"{warp[i]:.3g}", f"{warp[i] / diag[i]:.2e}",
                       "; ".join(flags.get(pid, [])))
    n = _write(path, GLASS_COLUMNS, rows())
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "build_up": build_up,
            "build_up_short": spec.glass.short(), "unit_thickness_mm": spec.glass.thickness_mm,
            "solids_per_unit": len(solids), "seconds": time.perf_counter() - t0}


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def beam_angles(g) -> dict[str, np.ndarray]:
    """End cuts and dihedrals of one beam plate group (degrees): ``mitre (p, 2)`` at ends a, b (in the
    plate, from square; positive: longer on its outline edge 0, the glass side of a plate or web, the
    weld edge of a flange), ``end_bevel (p, 2, 2)`` [end, side], ``top_bevel (p, 2)`` (edge 0),
    ``dihedral (p,)`` (between the ridge planes of a plate or web; NaN for other plates)."""
    R = g.bevel_ref                                          # 4 corners: edge 0, end, edge 2, end
    t = _unit(R[:, 1] - R[:, 0])

    def along(e):
        return np.einsum("pi,pi->p", t, _unit(e))

    first = -np.degrees(np.arcsin(np.clip(along(R[:, 0] - R[:, 3]), -1, 1)))
    second = -np.degrees(np.arcsin(np.clip(along(R[:, 2] - R[:, 1]), -1, 1)))
    a_first = np.ones(len(g), dtype=bool)
    if g.centre_line is not None:  # which end of the ring is end a (a mirrored flange starts at b)
        V0 = g.vertices[:, g.ring[0]]
        C = g.centre_line
        a_first = np.linalg.norm(V0 - C[:, 0], axis=1) <= np.linalg.norm(V0 - C[:, 1], axis=1)
    mitre = np.where(a_first[:, None], np.stack([first, second], 1), np.stack([second, first], 1))
    bev = g.bevel_deg[:, [3, 1]]
    end_bevel = np.where(a_first[:, None, None], bev, bev[:, ::-1])
    dihedral = np.full(len(g), np.nan)
    if len(g.faces) == 10:                                  # the plate / web: T0+ and T0- (the glass bears on them)
        dihedral = _dihedral(g.normals[:, 2], g.normals[:, 3])
    return {"mitre": mitre, "end_bevel": end_bevel, "top_bevel": g.bevel_deg[:, 0], "dihedral": dihedral}


def _dihedral(n_p, n_m) -> np.ndarray:
    return 180.0 - np.degrees(np.arccos(np.clip(np.einsum("pi,pi->p", n_p, n_m), -1, 1)))


def beam_units(parts) -> list:
    """The first plate group of every beam (the plate, a web, an RHS's ``web +``): one per unit."""
    from fabricate.cad.sections import MEMBERS

    firsts = {m[0] for m in MEMBERS.values()}
    return [g for g in parts.of_kind("beam") if g.member in firsts]


def unit_facts(parts) -> dict[str, np.ndarray]:
    """Per beam (mesh edge index ``e``): ``weight_kg (e,)`` of all its plates, ``dihedral (e,)`` deg,
    ``mitre (e, 2)`` deg from the beam's centre line (end a, b), ``length (e,)`` mm along its glass edge."""
    gs = parts.of_kind("beam")
    n = 1 + max(int(g.element.max()) for g in gs)
    weight = np.zeros(n)
    dihedral = np.full(n, np.nan)
    ridge: dict[str, np.ndarray] = {}
    for g in gs:
        np.add.at(weight, g.element, g.volume_mm3 * parts.spec.density("beam") * 1e-9)
        if len(g.faces) == 10:
            dihedral[g.element] = _dihedral(g.normals[:, 2], g.normals[:, 3])
        elif g.member in ("top flange +", "top flange -"):
            ridge[g.member[-1]] = (g.element, g.normals[:, 0])
    if len(ridge) == 2 and np.isnan(dihedral).all():  # an rhs: the top flanges lie in T0+ and T0-
        (e, n_p), (_, n_m) = ridge["+"], ridge["-"]
        dihedral[e] = _dihedral(n_p, n_m)
    C = np.zeros((n, 4, 3))
    for g in beam_units(parts):
        C[g.element] = g.centre_line if g.centre_line is not None else g.vertices[:, :4]
    t = _unit(C[:, 1] - C[:, 0])
    mitre_a = -np.degrees(np.arcsin(np.clip(np.einsum("pi,pi->p", t, _unit(C[:, 0] - C[:, 3])), -1, 1)))
    mitre_b = -np.degrees(np.arcsin(np.clip(np.einsum("pi,pi->p", t, _unit(C[:, 2] - C[:, 1])), -1, 1)))
    return {"weight_kg": weight, "dihedral": dihedral, "mitre": np.stack([mitre_a, mitre_b], axis=1),
            "length": np.linalg.norm(C[:, 1] - C[:, 0], axis=1)}


def beam_axes(g) -> np.ndarray:
    """(p, 3) unit vectors: the axis of the beam each solid of beam group ``g`` belongs to (its centre
    line ``A0 -> B0``, the glass edge from node axis to node axis)."""
    C = g.centre_line if g.centre_line is not None else g.vertices[:, :4]
    return _unit(C[:, 1] - C[:, 0])


def flat_in_model(g) -> np.ndarray:
    """(p, k, 3) the flat outline of every solid of ``g`` (the contour the shop cuts) placed in the model
    (``transform``)."""
    F = np.asarray(g.flat, dtype=float)
    T = np.asarray(g.transform, dtype=float)
    return np.einsum("pij,pkj->pki", T[:, :3, :2], F) + T[:, None, :3, 3]


def beam_lengths(parts) -> tuple[dict[str, float], dict[str, float]]:
    """The one length of every beam and of its plates (mm): ``(by solid id, by beam id)``.

    A plate's length is the extent of its cut outline (``flat``) along its beam's axis (the NC1 file's
    length, its contour drawn with x along that axis); a beam's is the extent of all its plates' outlines
    along the axis: the longest of the assembly as welded, end cut to end cut.  The steel cut list
    (``length_mm``), the NC1 headers and the IFC members give these figures; the node-axis to node-axis
    length along the glass edge is the cut list's ``system_length_mm``."""
    from fabricate.cad.parts import unit_id

    plate: dict[str, float] = {}
    lo: dict[str, float] = {}
    hi: dict[str, float] = {}
    for g in parts.of_kind("beam"):
        s = np.einsum("pki,pi->pk", flat_in_model(g), beam_axes(g))
        a, b = s.min(axis=1), s.max(axis=1)
        for pid, x, y in zip(g.ids, a.tolist(), b.tolist()):  # per solid: dictionaries by id
            plate[pid] = y - x
            u = unit_id(pid)
            lo[u], hi[u] = min(x, lo.get(u, x)), max(y, hi.get(u, y))
    return plate, {u: hi[u] - lo[u] for u in lo}


def _depth(parts) -> float:
    """The beams' depth (mm): the span of the layers."""
    return float(abs(np.diff(parts.report.get("layers_mm", [0.0, parts.spec.beam_depth]))[0]))


def bar_pieces(parts) -> list:
    """Every piece a shop saws from a stock bar, as :class:`fabricate.export.bars.Piece` sorted by id:
    each beam (its cut list section and grade, its one length :func:`beam_lengths`, to 0.1 mm as the cut
    list writes it) and each hub tube (``CHS D x t``, its cut between the caps), with the nominal kg/m of
    its section (the plates' rectangles, :func:`fabricate.cad.sections.section_rectangles`; a CHS:
    ``pi (D - t) t``)."""
    from fabricate.cad.parts import unit_id
    from fabricate.cad.sections import section_rectangles, section_text

    from .bar_plan import Piece

    spec = parts.spec
    grade = spec.steel_grade
    rho = spec.density("beam") * 1e-6                       # kg/m per mm2 of section
    out = []
    if parts.of_kind("beam"):
        depth = _depth(parts)
        _, length = beam_lengths(parts)
        text = section_text(spec, depth)
        kg = sum((y1 - y0) * (z1 - z0) for y0, y1, z0, z1 in section_rectangles(spec, depth)) * rho
        plate = spec.beam.section == "plate"
        for g in beam_units(parts):
            for i, pid in enumerate(g.ids):  # one piece per beam
                u = unit_id(pid)
                h = float(f"{g.rect[i, 1]:.0f}")
                sec, kgm = (f"plate {spec.beam_width:g} x {h:.0f}", spec.beam_width * h * rho) if plate else (text, kg)
                out.append(Piece(u, sec, grade, float(f"{length[u]:.1f}"), kgm))
    tubes = [g for g in parts.of_kind("node") if g.member == "tube"]
    if tubes:
        piece = hub_section(spec)[1]
        d, t = 2 * spec.hub_radius, spec.node.wall_mm
        for g in tubes:
            out += [Piece(pid, piece, grade, float(f"{L:.1f}"), np.pi * (d - t) * t * rho)
                    for pid, L in zip(g.ids, g.length_mm.tolist())]
    return sorted(out, key=lambda p: p.id)


def write_steel_cut_list(parts, path, bars: dict | None = None) -> dict:
    """Write ``steel_cut_list.csv`` (atomic): one row per beam (its section, its weight) and, for a
    section welded from several plates, one row per plate below it (``<beam>.<k>``, ``member`` naming
    it, ``PL<t>``, its own blank, end cuts and weight); ``bar``: the stock bar of each beam and hub tube
    in the cutting plan on ``bars`` (``outputs.bars``; None: the defaults,
    :func:`fabricate.export.bars.cutting_plan`).  Returns facts: ``file, bytes, rows, seconds``."""
    from fabricate.cad.parts import part_ids, unit_id
    from fabricate.cad.sections import section_text

    from .bar_plan import cutting_plan

    t0 = time.perf_counter()
    path = Path(path)
    flags = _flags(parts)
    spec = parts.spec
    topo = parts.mesh.topology if parts.mesh is not None else None
    plate = spec.beam.section == "plate"
    depth = _depth(parts)
    bar_of = cutting_plan(bar_pieces(parts), bars).bar_of()
    uf = unit_facts(parts) if parts.of_kind("beam") else None
    ids, names, _ = beam_types(parts)
    types = dict(zip(ids, names))
    by_edge: dict[int, list] = {}
    plate_length, beam_length = beam_lengths(parts)
    system = uf["length"] if uf is not None else None           # node axis to node axis: the mesh edge
    if topo is not None and uf is not None:
        ends = parts.mesh.V[topo.edges]
        system = np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    for g in parts.of_kind("beam"):
        a = beam_angles(g)
        weight = g.volume_mm3 * spec.group_density(g) * 1e-9
        for i, pid in enumerate(g.ids):  # the rows, grouped by beam
            by_edge.setdefault(int(g.element[i]), []).append((g, i, pid, a, weight[i], system[g.element[i]]))

    def angles(a, i, mitre=None):
        m = a["mitre"][i] if mitre is None else mitre
        return (f"{m[0]:+.2f}", _num(a["end_bevel"][i, 0], "{:+.2f}"), f"{m[1]:+.2f}",
                _num(a["end_bevel"][i, 1], "{:+.2f}"), _num(a["top_bevel"][i], "{:+.2f}"))

    def rows():
        for e in sorted(by_edge):
            plates = by_edge[e]
            g0, i0, pid0, a0 = plates[0][:4]
            unit = unit_id(pid0)
            panels = sorted({unit_id(n) for p in plates for n in p[0].neighbours[p[1]] if n[0] == "P"})
            nodes = " ".join(part_ids("node", topo.edges[e])) if topo is not None else ""
            two = len(panels) == 2 and np.isfinite(uf["dihedral"][e])
            dihedral = f"{uf['dihedral'][e]:.2f}" if two else ""
            unit_flags = sorted({f for p in plates for f in flags.get(p[2], [])} | set(flags.get(unit, [])))
            if plate:
                g, i, pid, a, w, L = plates[0]
                yield (pid, e, types.get(pid, ""), unit, f"plate {spec.beam_width:g} x {g.rect[i, 1]:.0f}", "",
                       f"{len(plates)}", spec.steel_grade, f"{beam_length[unit]:.1f}", f"{system[e]:.1f}",
                       f"{g.rect[i, 0]:.1f}", f"{g.rect[i, 1]:.1f}",
                       *angles(a, i), dihedral, f"{w:.2f}", " ".join(panels), nodes, "; ".join(unit_flags))
                continue
            cuts = angles(a0, i0, uf["mitre"][e])[:4] + ("",)   # end cuts of the first plate; ridges: per plate
            yield (unit, e, types.get(unit, ""), unit, section_text(spec, depth), "beam", f"{len(plates)}",
                   spec.steel_grade, f"{beam_length[unit]:.1f}", f"{system[e]:.1f}", "", "", *cuts, dihedral,
                   f"{uf['weight_kg'][e]:.2f}", " ".join(panels), nodes, "; ".join(unit_flags))
            for g, i, pid, a, w, L in plates:
                yield (pid, e, types.get(unit, ""), unit, f"PL{g.thickness_mm[i]:g}", g.member, "", spec.steel_grade,
                       f"{plate_length[pid]:.1f}", f"{L:.1f}", f"{g.rect[i, 0]:.1f}", f"{g.rect[i, 1]:.1f}",
                       *angles(a, i), "", f"{w:.2f}",
                       " ".join(unit_id(n) for n in g.neighbours[i] if n[0] == "P"), nodes, "; ".join(flags.get(pid, [])))
    hubs, hub_weight = hub_rows(parts, flags, dict(zip(*node_types(parts)[:2])))

    def every_row():
        for part in (rows(), hubs):  # the bar each beam and hub tube is sawn from, last
            for row in part:
                yield (*row, bar_of.get(row[0], ""))
    n = _write(path, STEEL_COLUMNS, every_row())
    beam_weight = float(uf["weight_kg"].sum()) if uf is not None else 0.0
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "beams": len(by_edge),
            "hubs": len({unit_id(r[0]) for r in hubs}), "section": section_text(spec, depth),
            "hub_section": hubs[0][4] if hubs else "",
            "weight_kg": {"beams": round(beam_weight, 3), "hubs": round(hub_weight, 3),
                          "total": round(beam_weight + hub_weight, 3)},
            "seconds": time.perf_counter() - t0}


def hub_section(spec) -> tuple[str, str]:
    """What a steel shop orders for a hub: ``(hub, piece)`` texts, e.g. ``("tube hub CHS 160 x 8 + 2 caps PL12
    24-gon D160", "CHS 160 x 8")`` (a tube: a circular hollow section, outside diameter x wall, the model
    its inscribed ``node_sides``-gon) or ``("solid hub RD 160", "RD 160")`` (a round bar)."""
    d = 2 * spec.hub_radius
    k = spec.node_sides
    if spec.hub_kind == "tube":
        chs = f"CHS {d:g} x {spec.node.wall_mm:g}"
        return f"tube hub {chs} + 2 caps PL{spec.node.cap_mm:g} {k}-gon D{d:g}", chs
    return f"solid hub RD {d:g} ({k}-gon)", f"RD {d:g}"


def hub_rows(parts, flags: dict, types: dict | None = None) -> tuple[list[tuple], float]:
    """The steel cut list's rows of the hubs and their total weight (kg).

    Per hub: one row (``N0001``, member ``hub``: the hub section, length = hub height between its outer
    faces, weight of all its pieces); for a tube hub then its pieces: the tube (``N0001.1``, ``CHS D x wall``,
    length = the tube cut between the caps) and the two caps (``PL<cap>``, their stock blank).  Weights are
    the model's solids (volume x density, as the BOM): the tube is modelled as its inscribed
    ``node_sides``-gon, so a round CHS of the listed size weighs about ``1 - sin(2 pi/K) K / (2 pi)``
    more (1.1 % for 24 sides)."""
    from fabricate.cad.parts import unit_id

    nodes = parts.of_kind("node")
    if not nodes:
        return [], 0.0
    spec = parts.spec
    hub_text, piece = hub_section(spec)
    n = 1 + max(int(g.element.max()) for g in nodes)
    weight, height = np.zeros(n), np.zeros(n)
    pieces: dict[int, list] = {}
    for g in nodes:
        w = g.volume_mm3 * spec.group_density(g) * 1e-9
        np.add.at(weight, g.element, w)
        np.add.at(height, g.element, g.length_mm)     # tube + caps: the hub's height
        for i, pid in enumerate(g.ids):  # the pieces, grouped by hub
            pieces.setdefault(int(g.element[i]), []).append((g, i, pid, w[i]))
    blank = ("", "", "", "", "", "", "", "")
    types = types or {}
    out = []
    for v in sorted(pieces):
        own = pieces[v]
        uid = unit_id(own[0][2])
        kind = types.get(uid, "")
        unit_flags = sorted({f for p in own for f in flags.get(p[2], [])} | set(flags.get(uid, [])))  # caps: by hub
        out.append((uid, "", kind, uid, hub_text, "hub", f"{len(own)}", spec.steel_grade, f"{height[v]:.1f}", "", *blank,
                    f"{weight[v]:.2f}", "", uid, "; ".join(unit_flags)))
        if len(own) == 1:
            continue
        for g, i, pid, w in own:
            cap = g.member != "tube"
            out.append((pid, "", kind, uid, f"PL{g.thickness_mm[i]:g}" if cap else piece, g.member, "", spec.steel_grade,
                        f"{g.length_mm[i]:.1f}", "", f"{g.rect[i, 0]:.1f}" if cap else "",
                        f"{g.rect[i, 1]:.1f}" if cap else "", "", "", "", "", "", "", f"{w:.2f}", "", uid,
                        "; ".join(flags.get(pid, []))))
    return out, float(weight.sum())


def node_table(parts) -> dict[str, np.ndarray]:
    """Per beam end: ``vertex (2e,)``, ``beam (2e,)`` ids index, ``axis (2e, 3)`` unit (glass toward beams),
    ``direction (2e, 3)`` unit from the node along the beam's glass edge, sorted by vertex."""
    from fabricate.cad.parts import unit_id

    gs = beam_units(parts)
    X = np.concatenate([g.centre_line if g.centre_line is not None else g.vertices[:, :4] for g in gs])
    ids = np.array([unit_id(i) for g in gs for i in g.ids])
    E = parts.mesh.topology.edges[np.concatenate([g.element for g in gs])]
    vert = np.concatenate([E[:, 0], E[:, 1]])
    axis = np.concatenate([X[:, 3] - X[:, 0], X[:, 2] - X[:, 1]])
    direction = np.concatenate([X[:, 1] - X[:, 0], X[:, 0] - X[:, 1]])
    beam = np.concatenate([ids, ids])
    order = np.argsort(vert, kind="stable")
    return {"vertex": vert[order], "beam": beam[order], "axis": _unit(axis[order]),
            "direction": _unit(direction[order])}


def hub_columns(parts, n: int) -> tuple[list[str], np.ndarray, float, np.ndarray]:
    """Per vertex ``(n,)``: the hub text, its height (mm, NaN without a hub), its outside diameter and wall
    (mm, 0 for a solid hub): what the node schedule lists."""
    spec = parts.spec
    height = np.full(n, np.nan)
    for g in parts.of_kind("node"):
        if g.member in ("", "tube"):
            height[g.element] = g.length_mm
        elif g.member in ("top cap", "bottom cap"):
            height[g.element] += g.length_mm
    conn = spec.connection
    if conn != "hub" or not parts.of_kind("node"):
        text = {"mitre": "none (mitred ends)", "none": f"none (square ends {spec.node.gap_mm:g} mm off the axis)"}
        return [text.get(conn, "none")] * n, height, 0.0, np.zeros(n)
    d = 2 * spec.hub_radius
    if spec.hub_kind == "tube":
        wall = spec.node.wall_mm
        texts = [f"tube {spec.node_sides}-gon D{d:g} x {wall:g}, caps {spec.node.cap_mm:g}, h {h:.1f}" for h in height]
        return texts, height, d, np.full(n, wall)
    return [f"solid {spec.node_sides}-gon D{d:g}, h {h:.1f}" for h in height], height, d, np.zeros(n)


def write_node_schedule(parts, path) -> dict:
    """Write ``node_schedule.csv`` (atomic).  Returns facts: ``file, bytes, rows, seconds``."""
    from fabricate.cad.beams import _node_frames
    from fabricate.cad.parts import part_ids

    t0 = time.perf_counter()
    path = Path(path)
    mesh = parts.mesh
    if mesh is None or not parts.of_kind("beam"):
        raise ExportError(f"{path}: no beams or no mesh: nothing to schedule")
    nt = node_table(parts)
    v = nt["vertex"]
    first = np.searchsorted(v, v, side="left")
    axis = nt["axis"][first]                                 # one axis per node (the same line for all)
    fx, fy = _node_frames(axis)
    d = nt["direction"]
    elev = np.degrees(np.arcsin(np.clip(np.einsum("pi,pi->p", d, axis), -1, 1)))
    az = np.degrees(np.arctan2(np.einsum("pi,pi->p", d, fy), np.einsum("pi,pi->p", d, fx)))
    az = (az - az[first]) % 360.0
    order = np.lexsort((az, v))
    v, az, elev, beam, axis = v[order], az[order], elev[order], nt["beam"][order], axis[order]
    starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])
    stops = np.r_[starts[1:], len(v)]
    nid = part_ids("node", np.arange(mesh.n_vertices))
    hub, height, diameter, wall = hub_columns(parts, mesh.n_vertices)
    types = dict(zip(*node_types(parts)[:2]))

    def rows():
        for s, e in zip(starts.tolist(), stops.tolist()):  # one row per node
            i = int(v[s])
            x = mesh.V[i]
            a = axis[s]
            yield (nid[i], i, types.get(nid[i], ""), nid[i], f"{x[0]:.1f}", f"{x[1]:.1f}", f"{x[2]:.1f}",
                   f"{a[0]:.6f}", f"{a[1]:.6f}", f"{a[2]:.6f}", e - s, " ".join(beam[s:e]), _num(az[s:e]),
                   _num(elev[s:e]), hub[i],
                   f"{diameter:g}" if diameter else "", f"{wall[i]:g}" if wall[i] else "",
                   f"{height[i]:.1f}" if np.isfinite(height[i]) else "")
    n = _write(path, NODE_COLUMNS, rows())
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "seconds": time.perf_counter() - t0}


# -- types: how many different parts (fabricate.cad.congruence) ----------------------------------------
TYPE_PREFIX = {"glass": "G", "beam": "BT", "node": "NT"}
"""Type names: ``G007`` (a glass shape; ``G007A`` / ``G007B`` its two hands), ``BT012`` (a beam type),
``NT003`` (a node type): apart from the part ids ``P``, ``B``, ``N``."""


def lever_mm(parts) -> float:
    """The length over which an angle becomes a distance for the type tolerance: the beam depth (an end
    cut or a beam direction off by ``a`` rad misses by ``depth * a`` mm across the section)."""
    layers = parts.report.get("layers_mm") if isinstance(parts.report, dict) else None
    depth = abs(float(np.diff(layers)[0])) if layers and len(layers) > 1 else float(parts.spec.beam_depth)
    return depth if depth > 0 else float(parts.spec.beam_depth)


def glass_types(parts, tol: float | None = None) -> tuple[list[str], list[str], "object"]:
    """``(unit ids, type names, Classes)`` of every glass unit: one type per shape
    (:func:`fabricate.cad.congruence.glass_classes`), ``A`` / ``B`` for the hands of a shape made in both."""
    from fabricate.cad.congruence import TOLERANCE_MM, glass_classes

    ids, c = glass_classes(parts, TOLERANCE_MM if tol is None else tol)
    return ids, c.names(TYPE_PREFIX["glass"]), c


def node_types(parts, tol: float | None = None) -> tuple[list[str], list[str], "object"]:
    """``(node ids, type names, Classes)``: two nodes are of one type when their beam directions, in the
    frame of the node axis, agree within ``tol`` mm at the beam depth (:func:`lever_mm`) for some rotation
    about the axis and relabelling of the beams (same valence); mirror images are the other hand."""
    from fabricate.cad.beams import _node_frames
    from fabricate.cad.congruence import TOLERANCE_MM, empty, merge, ring_classes
    from fabricate.cad.parts import part_ids

    tol = TOLERANCE_MM if tol is None else tol
    if parts.mesh is None or not parts.of_kind("beam"):
        return [], [], empty(tol)
    nt = node_table(parts)
    v = nt["vertex"]
    first = np.searchsorted(v, v, side="left")
    axis = nt["axis"][first]
    fx, fy = _node_frames(axis)
    d = nt["direction"] * lever_mm(parts)
    x, y, z = (np.einsum("pi,pi->p", d, f) for f in (fx, fy, axis))
    order = np.lexsort((np.arctan2(y, x), v))                                  # by node, then around its axis
    v, x, y, z = v[order], x[order], y[order], z[order]
    starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])
    valence = np.diff(np.r_[starts, len(v)])
    nodes = v[starts]
    subsets = []
    for k in np.unique(valence).tolist():  # one batch per valence
        sel = np.flatnonzero(valence == k)
        at = starts[sel][:, None] + np.arange(k)
        X = np.stack([x[at], y[at]], axis=-1)[:, None]                         # (q, 1, k, 2)
        subsets.append((sel, ring_classes(X, tol, F=z[at][:, None, :, None], translate=False)))
    c = merge(subsets, len(nodes))
    return list(part_ids("node", nodes)), c.names(TYPE_PREFIX["node"]), c


def beam_descriptors(parts) -> tuple[list[str], np.ndarray]:
    """``(beam ids, D (e, 4, 9))`` mm: each beam's length, end mitres, end bevels ``[+, -]`` and ridge
    bevels (angles as ``depth * rad``, :func:`lever_mm`), spelt as made (0), turned end for end (1: a
    section symmetric about its web plane is the same piece), and as its mirror image (2, 3)."""
    from fabricate.cad.parts import unit_id

    gs = beam_units(parts)
    if not gs:
        return [], np.zeros((0, 4, 9))
    h = lever_mm(parts)
    ids, rows = [], []
    for g in gs:  # a few groups (sections x members)
        a = beam_angles(g)
        L = np.linalg.norm(g.bevel_ref[:, 1] - g.bevel_ref[:, 0], axis=1)
        m, e, t = (np.radians(a[key]) * h for key in ("mitre", "end_bevel", "top_bevel"))
        made = np.column_stack([L, m[:, 0], m[:, 1], e[:, 0, 0], e[:, 0, 1], e[:, 1, 0], e[:, 1, 1], t[:, 0], t[:, 1]])
        turned = np.column_stack([L, m[:, 1], m[:, 0], e[:, 1, 1], e[:, 1, 0], e[:, 0, 1], e[:, 0, 0], t[:, 1], t[:, 0]])
        mirror = np.column_stack([L, m[:, 0], m[:, 1], e[:, 0, 1], e[:, 0, 0], e[:, 1, 1], e[:, 1, 0], t[:, 1], t[:, 0]])
        mirror_turned = np.column_stack([L, m[:, 1], m[:, 0], e[:, 1, 0], e[:, 1, 1], e[:, 0, 0], e[:, 0, 1],
                                         t[:, 0], t[:, 1]])
        rows.append(np.stack([made, turned, mirror, mirror_turned], axis=1))
        ids += [unit_id(i) for i in g.ids]
    return ids, np.nan_to_num(np.concatenate(rows))


def beam_types(parts, tol: float | None = None) -> tuple[list[str], list[str], "object"]:
    """``(beam ids, type names, Classes)``: two beams are of one type when length, end cuts and ridge
    bevels (:func:`beam_descriptors`) agree within ``tol`` mm, either end first; the mirror image (the
    bevels of the ``+`` and ``-`` sides swapped) is the other hand.  One section per run."""
    from fabricate.cad.congruence import TOLERANCE_MM, vector_classes

    tol = TOLERANCE_MM if tol is None else tol
    ids, D = beam_descriptors(parts)
    c = vector_classes(D, tol, spellings=2)
    return ids, c.names(TYPE_PREFIX["beam"]), c
