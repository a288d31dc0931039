"""The weld schedule (``weld_schedule.csv``): every shop weld of the steel, per joint, with totals.

Joints, found from the solids (every steel part is a planar-faced solid, :mod:`fabricate.cad.parts`):

- ``seam``: two plates of one beam welded along it (a tee's, I's or RHS's plates,
  :mod:`fabricate.cad.sections`): two faces of the two plates in one plane, facing each other, that
  overlap (found on the solids, not assumed: :func:`plate_contacts`).  The weld runs along the beam over
  the length both faces share (``length_mm``).
- ``end a`` / ``end b``: a beam's end on its hub (``parts.node.connection: hub``): all round the
  section's outline (the nominal one of :func:`fabricate.cad.sections.section_rectangles`: a plate
  ``2 (w + h)``, a tee or I its outline, an RHS its outside ``2 (b + h)``; the ends are square to the
  beam).  Mitred and square-ended nodes (``mitre`` / ``none``) have no hub: their site joints are
  not scheduled.
- ``cap``: a tube hub's cap plate on the tube end, all round the tube's outside (its ``K``-gon).

Weld type, by the joint's geometry (EN ISO 2553 symbols named in words):

- the edge of one plate on the edge of the other (an RHS's flange halves on the beam plane): a
  butt joint, ``single-V butt weld`` (symbol V), full penetration: throat = the thinner plate;
- the edge of one plate on the face of the other (T joint; a plate's faces are its outline and
  bevel faces, every other face an edge): in an open section (plate, tee, I) a ``fillet weld``
  (symbol: triangle) on the one re-entrant side (the other side is flush: the glass bearing, the
  flange's outside); in a closed one (RHS, and a tube on its cap) the re-entrant side is inside the
  box, so a ``single-bevel butt weld`` (symbol: HV, bevel on the abutting plate) from the outside,
  full penetration: throat = the abutting plate's thickness;
- a beam end on its hub: a ``fillet weld`` all round (symbol: triangle with the weld-all-round circle).

Fillet throat ``a`` (mm): the rule of thumb ``a >= 0.7 t_min`` (``t_min`` the thinner part at the
joint), rounded up to 0.5 mm, at least 3 mm (EN 1993-1-8 4.5.2); :func:`write_weld_schedule`'s
``fillet_throat_mm`` sets every fillet's instead (a calculation's result).

Rows: one per joint (``joint`` ``B0001-W1``, the ``assembly`` it is made in: the shipping piece,
the unit id of :func:`fabricate.cad.parts.unit_id`; ``parts`` the solids it joins), then one row
``<assembly> total`` per assembly and a last row ``roof total``: ``length_mm`` the sum of the rows
above (a joint's ``length_mm`` is the weld's run, all sides together).
"""
from __future__ import annotations

import csv
import math
import time
from pathlib import Path

import numpy as np

from optimize.errors import ExportError

COLUMNS = ("joint", "assembly", "where", "parts", "joint_type", "weld", "symbol", "sides", "throat_mm", "length_mm")
TOUCH_MM = 0.01
"""Two faces touch when their planes are this close (the parts are built on shared planes: round-off)."""
OVERLAP_MM = 0.1
"""...and they overlap by more than this in both directions of the plane."""
WELDS = {"fillet": ("fillet weld", "triangle"), "V": ("single-V butt weld", "V, full penetration"),
         "HV": ("single-bevel butt weld", "HV (bevel on the abutting plate), full penetration"),
         "fillet all round": ("fillet weld", "triangle with the weld-all-round circle")}


def fillet_throat(t_min, given: float | None = None):
    """Fillet throat ``a`` (mm) for the thinner part ``t_min`` (mm, scalar or array): ``given`` when set,
    else ``0.7 t_min`` rounded up to 0.5 mm and at least 3 mm."""
    if given is not None:
        return np.full(np.shape(t_min), float(given)) if np.ndim(t_min) else float(given)
    a = np.maximum(3.0, np.ceil(0.7 * np.asarray(t_min, dtype=float) * 2.0 - 1e-9) / 2.0)
    return a if np.ndim(a) else float(a)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def _extent(P: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)`` (p,) of points ``P (p, k, 3)`` along directions ``d (p, 3)``."""
    s = np.einsum("pki,pi->pk", P, d)
    return s.min(axis=1), s.max(axis=1)


def plate_contacts(ga, gb) -> list[dict]:
    """Faces of plates of two beam groups (two members of one section) that touch, per beam.

    Returns ``[{"a": (q,) rows of ga, "b": (q,) rows of gb, "length": (q,) mm along the beam, "width": (q,)
    mm across it, "main_a", "main_b": whether the face is a plate face (outline or bevel face), else an
    edge}]``, one entry per pair of faces that touch in some beam (loops over the faces of the two
    templates, arrays over the beams)."""
    common, ia, ib = np.intersect1d(ga.element, gb.element, return_indices=True)
    if not len(common):
        return []
    VA, VB = ga.vertices[ia], gb.vertices[ib]
    NA, NB = ga.normals[ia], gb.normals[ib]
    C = ga.centre_line[ia] if ga.centre_line is not None else VA[:, :4]
    t = _unit(C[:, 1] - C[:, 0])
    out = []
    for fa, face_a in enumerate(ga.faces):  # the template's faces (a few): arrays over the beams
        na = NA[:, fa]
        da = np.einsum("pi,pi->p", na, VA[:, face_a[0]])
        u = _unit(t - np.einsum("pi,pi->p", t, na)[:, None] * na)         # along the beam, in the plane
        w = np.cross(na, u)
        Pa = VA[:, list(face_a)]
        a_lo, a_hi = _extent(Pa, u)
        aw_lo, aw_hi = _extent(Pa, w)
        for fb, face_b in enumerate(gb.faces):
            nb = NB[:, fb]
            db = np.einsum("pi,pi->p", nb, VB[:, face_b[0]])
            facing = (np.einsum("pi,pi->p", na, nb) < -1.0 + 1e-9) & (np.abs(da + db) < TOUCH_MM)
            if not facing.any():
                continue
            Pb = VB[:, list(face_b)]
            b_lo, b_hi = _extent(Pb, u)
            bw_lo, bw_hi = _extent(Pb, w)
            length = np.minimum(a_hi, b_hi) - np.maximum(a_lo, b_lo)
            width = np.minimum(aw_hi, bw_hi) - np.maximum(aw_lo, bw_lo)
            hit = facing & (length > OVERLAP_MM) & (width > OVERLAP_MM)
            if hit.any():
                out.append({"a": ia[hit], "b": ib[hit], "length": length[hit], "width": width[hit],
                            "main_a": fa in (ga.outline_face, ga.bevel_face),
                            "main_b": fb in (gb.outline_face, gb.bevel_face)})
    return out


def outline_mm(spec, depth: float) -> float:
    """The length of the weld all round a beam's square end (mm): the outline of its nominal section
    (:func:`fabricate.cad.sections.section_rectangles`; an RHS's outside only: its inside is closed)."""
    from fabricate.cad.sections import section_rectangles

    R = np.asarray(section_rectangles(spec, depth), dtype=float)        # (r, 4) y0 y1 z0 z1
    if spec.beam.section == "rhs":
        return 2.0 * (float(np.ptp(R[:, :2])) + float(np.ptp(R[:, 2:])))
    total = float(2.0 * ((R[:, 1] - R[:, 0]) + (R[:, 3] - R[:, 2])).sum())
    for i in range(len(R)):          # a few rectangles: the edges two of them share are inside the outline
        for j in range(i + 1, len(R)):
            a, b = R[i], R[j]
            for lo, hi, c0, c1 in ((0, 1, 2, 3), (2, 3, 0, 1)):
                if min(abs(a[hi] - b[lo]), abs(b[hi] - a[lo])) < 1e-9:
                    total -= 2.0 * max(0.0, min(a[c1], b[c1]) - max(a[c0], b[c0]))
    return total


def weld_joints(parts, *, fillet_throat_mm: float | None = None) -> list[dict]:
    """Every shop weld of ``parts`` (see the module): ``[{"joint", "assembly", "where", "parts",
    "joint_type", "weld", "sides", "throat_mm", "length_mm"}]`` ordered by assembly."""
    from fabricate.cad.parts import part_ids, unit_id

    spec = parts.spec
    closed = spec.beam.section == "rhs"
    beams = parts.of_kind("beam")
    joints: dict[str, list[dict]] = {}

    def add(assembly, **row):
        joints.setdefault(assembly, []).append(dict(assembly=assembly, **row))

    for i, ga in enumerate(beams):                      # seams: every pair of member groups of a section
        for gb in beams[i + 1:]:
            if ga.member == gb.member:
                continue
            for c in plate_contacts(ga, gb):
                ta, tb = ga.thickness_mm[c["a"]], gb.thickness_mm[c["b"]]
                if not c["main_a"] and not c["main_b"]:
                    kind, jt, throat = "V", "butt", np.minimum(ta, tb)
                elif c["main_a"] != c["main_b"]:
                    t_edge = tb if c["main_a"] else ta
                    if closed:
                        kind, jt, throat = "HV", "corner", t_edge
                    else:
                        kind, jt, throat = "fillet", "T", fillet_throat(np.minimum(ta, tb), fillet_throat_mm)
                else:
                    kind, jt, throat = "fillet", "lap", fillet_throat(np.minimum(ta, tb), fillet_throat_mm)
                for ra, rb, L, a in zip(c["a"].tolist(), c["b"].tolist(), c["length"].tolist(),
                                        np.broadcast_to(throat, c["a"].shape).tolist()):
                    pa, pb = ga.ids[ra], gb.ids[rb]
                    add(unit_id(pa), where="seam", parts=sorted([pa, pb], key=_part_key), joint_type=jt, weld=kind,
                        sides=1, throat_mm=float(a), length_mm=float(L))
    nodes = parts.of_kind("node")
    tubes = [g for g in nodes if g.member == "tube"]            # one group per hub type (sides)
    mesh = parts.mesh
    if spec.connection == "hub" and nodes and beams and mesh is not None:
        from .schedules import beam_units

        depth = abs(np.diff(parts.report.get("layers_mm", [0.0, spec.beam_depth]))[0])
        run = outline_mm(spec, depth)
        tube = tubes[0] if tubes else None
        hub_ids = set(parts.by_id)
        t_plate = {}
        for g in beams:
            for pid, t in zip(g.ids, g.thickness_mm.tolist()):
                u = unit_id(pid)
                t_plate[u] = min(t, t_plate.get(u, np.inf))
        members = {}
        for g in beams:
            for pid in g.ids:
                members.setdefault(unit_id(pid), []).append(pid)
        for g in beam_units(parts):
            E = mesh.topology.edges[g.element]
            for end, col in (("end a", 0), ("end b", 1)):
                hub = part_ids("node", E[:, col])
                for pid, h in zip(g.ids, hub):
                    u = unit_id(pid)
                    hid = f"{h}.1" if tube is not None else h
                    if hid not in hub_ids:
                        continue
                    wall = float(spec.node.wall_mm) if tube is not None else np.inf
                    add(u, where=end, parts=sorted(members[u], key=_part_key) + [hid], joint_type="T",
                        weld="fillet all round", sides=1,
                        throat_mm=float(fillet_throat(min(t_plate[u], wall), fillet_throat_mm)), length_mm=float(run))
    tube_at: dict[int, tuple] = {}                         # caps on the tube ends: all round its outside
    for g in tubes:
        k = g.vertices.shape[1] // 4
        ring = g.vertices[:, :k]
        perimeter = np.linalg.norm(np.roll(ring, -1, axis=1) - ring, axis=2).sum(axis=1)
        for j, e in enumerate(g.element.tolist()):  # per hub: by its vertex
            tube_at[e] = (g.ids[j], float(g.thickness_mm[j]), float(perimeter[j]))
    for cap in (g for g in nodes if g.member in ("top cap", "bottom cap")):
        for r, (pid, e) in enumerate(zip(cap.ids, cap.element.tolist())):
            if e not in tube_at:
                continue
            tid, wall, run = tube_at[e]
            add(unit_id(pid), where="cap", parts=[tid, pid], joint_type="corner", weld="HV", sides=1,
                throat_mm=min(wall, float(cap.thickness_mm[r])), length_mm=run)
    out = []
    for assembly in sorted(joints, key=_part_key):
        rows = sorted(joints[assembly], key=lambda r: (_WHERE.index(r["where"]), [_part_key(p) for p in r["parts"]]))
        for n, row in enumerate(rows):
            out.append(dict(row, joint=f"{assembly}-W{n + 1}"))
    return out


_WHERE = ("seam", "end a", "end b", "cap")


def _part_key(pid: str) -> tuple:
    """Sort key of an id: ``B0002.10`` after ``B0002.9``."""
    head, _, tail = pid.partition(".")
    return (head[0], int(head[1:]) if head[1:].isdigit() else 0, int(tail) if tail.isdigit() else 0, pid)


def write_weld_schedule(parts, path, *, fillet_throat_mm: float | None = None) -> dict:
    """Write ``weld_schedule.csv`` (atomic): one row per joint, one total per assembly, the roof's total.

    Returns facts: ``file, bytes, rows, joints, assemblies, length_m`` (by where and weld, and ``total``),
    ``seconds``."""
    from .schedules import _write

    t0 = time.perf_counter()
    path = Path(path)
    joints = weld_joints(parts, fillet_throat_mm=fillet_throat_mm)
    by_assembly: dict[str, float] = {}
    for j in joints:
        by_assembly[j["assembly"]] = by_assembly.get(j["assembly"], 0.0) + j["length_mm"]

    def rows():
        last = None
        for j in joints:
            if last is not None and j["assembly"] != last:
                yield _total(last, by_assembly[last])
            last = j["assembly"]
            name, symbol = WELDS[j["weld"]]
            yield (j["joint"], j["assembly"], j["where"], " ".join(j["parts"]), j["joint_type"], name,
                   symbol, j["sides"], f"{j['throat_mm']:g}", f"{j['length_mm']:.1f}")
        if last is not None:
            yield _total(last, by_assembly[last])
        yield ("roof total", "", "total", "", "", "", "", "", "", f"{sum(by_assembly.values()):.1f}")
    n = _write(path, COLUMNS, rows())
    length: dict[str, float] = {}
    for j in joints:
        for key in (j["where"].split()[0], WELDS[j["weld"]][0]):
            length[key] = length.get(key, 0.0) + j["length_mm"] * 1e-3
    length = {k: round(float(v), 3) for k, v in length.items()}
    length["total"] = round(float(sum(by_assembly.values())) * 1e-3, 3)
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n, "joints": len(joints),
            "assemblies": len(by_assembly), "length_m": length, "seconds": time.perf_counter() - t0}


def _total(assembly: str, length: float) -> tuple:
    return (f"{assembly} total", assembly, "total", "", "", "", "", "", "", f"{length:.1f}")


ROUND_MM = 0.051
"""Allowance for the CSV's 0.1 mm lengths (one per row summed)."""


def check_weld_schedule(path, bom: list[dict]) -> dict:
    """Hold ``weld_schedule.csv`` to the bill of materials: every part a row names exists; a joint's
    parts belong to its assembly (a beam end: its beam's plates and one hub solid; a cap: its hub);
    every beam welded from several plates has its plates joined (its seams connect them all); every
    assembly's total and the roof's are the sums of their rows.  Returns ``{"pass", "joints",
    "assemblies", "length_m", "problems"}``."""
    from fabricate.cad.parts import unit_id

    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ExportError(f"{path}: cannot read the weld schedule ({exc})") from None
    if rows and set(COLUMNS) - set(rows[0]):
        return {"pass": False, "problems": [f"{path.name}: columns {sorted(set(COLUMNS) - set(rows[0]))} missing"]}
    ids = {r["id"] for r in bom}
    units: dict[str, list[str]] = {}
    for r in bom:
        if r["kind"] == "beam":
            units.setdefault(r["unit"], []).append(r["id"])
    problems: list[str] = []
    sums: dict[str, float] = {}
    totals: dict[str, float] = {}
    seams: dict[str, list[tuple[str, str]]] = {}
    roof = None
    for line, r in enumerate(rows, start=2):
        try:
            length = float(r["length_mm"])
        except ValueError:
            problems.append(f"{path.name} line {line}: length_mm {r['length_mm']!r}: expected a number")
            continue
        if not math.isfinite(length) or length < 0:
            problems.append(f"{path.name} line {line}: length_mm {r['length_mm']!r}: expected a finite length")
            continue
        if r["where"] == "total":
            if r["joint"] == "roof total":
                roof = length
            else:
                totals[r["assembly"]] = length
            continue
        named = r["parts"].split()
        unknown = [p for p in named if p not in ids]
        if unknown:
            problems.append(f"{path.name} line {line}: joint {r['joint']}: parts {unknown} not in the BOM")
        a = r["assembly"]
        sums[a] = sums.get(a, 0.0) + length
        own = [p for p in named if unit_id(p) == a]
        other = [p for p in named if unit_id(p) != a]
        if r["where"] == "seam":
            if len(own) != 2 or other:
                problems.append(f"{path.name} line {line}: seam {r['joint']}: expected two plates of {a}, "
                                f"found {r['parts']!r}")
            else:
                seams.setdefault(a, []).append((own[0], own[1]))
        elif r["where"] in ("end a", "end b"):
            if sorted(own) != sorted(units.get(a, [a])) or len(other) != 1 or other[0][0] != "N":
                problems.append(f"{path.name} line {line}: {r['where']} {r['joint']}: expected every solid of "
                                f"{a} and one hub, found {r['parts']!r}")
        elif len(own) != 2 or other:
            problems.append(f"{path.name} line {line}: cap {r['joint']}: expected a tube and a cap of {a}, "
                            f"found {r['parts']!r}")
    for a, plates in units.items():     # a beam of several plates: its seams join them all
        if len(plates) < 2:
            continue
        reach, edges = {plates[0]}, seams.get(a, [])
        grew = True
        while grew:
            grew = False
            for p, q in edges:
                if (p in reach) != (q in reach):
                    reach |= {p, q}
                    grew = True
        if reach != set(plates):
            problems.append(f"{path.name}: beam {a}: plates {sorted(set(plates) - reach)} not welded to the others")
    for a in sorted(set(sums) | set(totals)):
        if abs(sums.get(a, 0.0) - totals.get(a, -1.0)) > ROUND_MM * (1 + sum(r["assembly"] == a for r in rows)):
            problems.append(f"{path.name}: {a} total {totals.get(a)} mm, its joints sum to {sums.get(a, 0.0):.1f} mm")
    total = sum(totals.values())
    if roof is None or abs(roof - total) > ROUND_MM * (1 + len(totals)):
        problems.append(f"{path.name}: roof total {roof} mm, the assemblies sum to {total:.1f} mm")
    return {"pass": not problems, "joints": sum(r["where"] != "total" for r in rows), "assemblies": len(totals),
            "length_m": round(total * 1e-3, 3), "problems": problems[:20]}
