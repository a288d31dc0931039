"""``fabricate check`` of the exchange files against the bill of materials.

- ``ifc``: ifcopenshell opens ``model.ifc``; one element per BOM row with the
  same id (Name and Tag), one per glass unit (``P0001`` for the rows ``P0001.1 ...``, volumes summed), one
  ``IfcElementAssembly`` per steel unit of several solids aggregating exactly them (every solid in one
  assembly), every steel cut list row's length (``Length`` quantity and ``length_mm``) within 0.05 mm of
  the list's; full mode also validates the file against the IFC4
  schema and its express rules' attribute types (``ifcopenshell.validate`` for every instance but the
  face sets, their faces and point lists, whose rules :func:`read_face_sets` checks at once)
  and compares every element's volume, from ifcopenshell's own geometry
  kernel, with the BOM's within ``tol.file_volume`` (``1e-6``) relative.
- ``3dm``: rhino3dm reads ``model.3dm``; one named object per BOM row on the
  layer of its kind, the BOM row in its user strings, units mm.
- ``nc1``: one file per beam row and per hub tube row, read by the reader written apart from the
  writer (:mod:`.nc1_read`): piece id, profile code (``B`` plate, ``RO`` tube), plate thickness
  or tube wall, weight within 1e-3; a tube's length (its cut between the caps) within 2e-3 mm,
  its flange thickness the wall and its profile ``RO<height>x<wall>``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from optimize.tolerances import DEFAULT, Tolerances

KIND_LAYER = {"panel": "glass", "beam": "steel", "node": "nodes"}


def _ids_result(expected: set, found: set, extra: dict) -> dict:
    missing, unknown = sorted(expected - found), sorted(found - expected)
    return {"pass": not missing and not unknown and all(v == [] for k, v in extra.items() if k.startswith("bad")),
            "elements": len(found), "missing": missing[:20], "unknown": unknown[:20], **extra}


def _without_faces(f):
    """``f`` (the same parsed file) iterated without its face sets, their faces and point lists
    (:data:`GEOMETRY`), for ``ifcopenshell.validate`` (which checks each instance's attributes in
    Python, each coordinate and each face reference one at a time: the geometry is four fifths of the
    instances and most of the attributes, and its rules are checked at once by :func:`read_face_sets`)."""
    import ifcopenshell

    class _Rest(ifcopenshell.file):
        def __iter__(self):
            return iter(self[i] for i in self.entity_names() if i not in self.skip)

    view = _Rest.__new__(_Rest)
    view.__dict__.update(f.__dict__)
    view.skip = {x.id() for t in GEOMETRY for x in f.by_type(t) if x.is_a() in GEOMETRY}
    return view


FACES = ("IfcIndexedPolygonalFace", "IfcIndexedPolygonalFaceWithVoids")
GEOMETRY = FACES + ("IfcPolygonalFaceSet", "IfcCartesianPointList3D")
"""The entities :func:`read_face_sets` checks in place of ``ifcopenshell.validate``."""


def _point_list_errors(pl) -> tuple[np.ndarray | None, list[str]]:
    """``(P (n, 3) or None, rule errors)`` of an ``IfcCartesianPointList3D``: ``CoordList`` a list of
    one or more lists of exactly 3 ``IfcLengthMeasure`` (reals; ifcopenshell reads an integer there as
    a real), finite."""
    cl = pl.CoordList
    what = f"#{pl.id()} IfcCartesianPointList3D CoordList"
    try:
        P = np.asarray(cl, dtype=float)
    except (TypeError, ValueError):
        P = None
    if P is None or P.ndim != 2 or P.shape[1:] != (3,) or not len(P):
        return None, [f"{what}: expected a list of 1 or more lists of 3 reals"]
    if not np.isfinite(P).all():
        return None, [f"{what}: a coordinate is not a finite number"]
    return P, []


def _bad_index(idx, n: int, least: int = 3) -> bool:
    return (not isinstance(idx, tuple) or len(idx) < least or not all(isinstance(i, int) for i in idx)
            or min(idx) < 1 or max(idx) > n)


def read_face_sets(f) -> tuple[dict[str, float], list[str]]:
    """``(volumes, rule errors)`` of the face sets as ifcopenshell parses them, in one pass over their faces.

    volumes : element name -> volume (mm3) of its closed ``IfcPolygonalFaceSet`` s, from the
    coordinates and face indices (divergence theorem over fan triangles; a hole's loop turns the
    other way, so its triangles take its share off): the file's content, without the writer's
    arrays and without a geometry kernel; NaN for a set whose indices are not its points'.
    rule errors : the IFC4 rules of the :data:`GEOMETRY` entities (what ``ifcopenshell.validate``
    checks on one): every ``IfcCartesianPointList3D`` (:func:`_point_list_errors`); every
    ``IfcPolygonalFaceSet``'s ``Coordinates`` one, ``Closed`` a boolean or unset, ``Faces`` a set of
    one or more ``IfcIndexedPolygonalFace`` (or ``...WithVoids``), ``PnIndex`` unset or a list of
    positive integers within its points; every face's ``CoordIndex`` (and each of
    ``InnerCoordIndices``, a list of one or more) a list of 3 or more positive integers, the face
    used by a face set (inverse ``ToFaceSet [1:?]``); and each index within its face set's points."""
    errors: list[str] = []
    used: set[int] = set()
    set_volume: dict[int, float] = {}
    points: dict[int, np.ndarray | None] = {}
    for pl in f.by_type("IfcCartesianPointList3D"):
        if pl.is_a() == "IfcCartesianPointList3D":
            points[pl.id()], bad = _point_list_errors(pl)
            errors += bad
    for s in f.by_type("IfcPolygonalFaceSet"):
        coords, faces, pn = s.Coordinates, s.Faces, s.PnIndex
        P = points.get(coords.id()) if coords is not None else None      # None: not a valid point list
        ok = P is not None
        if coords is None or coords.id() not in points:
            errors.append(f"#{s.id()} IfcPolygonalFaceSet Coordinates: expected an IfcCartesianPointList3D")
        if s.Closed not in (True, False, None):
            errors.append(f"#{s.id()} IfcPolygonalFaceSet Closed {s.Closed!r}: expected a boolean or unset")
        if not isinstance(faces, tuple) or not faces or not all(
                hasattr(x, "is_a") and x.is_a() in FACES for x in faces):
            errors.append(f"#{s.id()} IfcPolygonalFaceSet Faces: expected a set of 1 or more IfcIndexedPolygonalFace")
            faces, ok = (), False
        if pn is not None:
            if ok and not _bad_index(pn, len(P), least=1):
                P = P[np.asarray(pn, dtype=np.int64) - 1]           # the faces index the points through PnIndex
            else:
                errors.append(f"#{s.id()} IfcPolygonalFaceSet PnIndex: expected positive integers within its points")
                ok = False
        if P is None:
            P = np.zeros((0, 3))
        n, tri = len(P), []
        for face in faces:
            used.add(face.id())
            loops = [face.CoordIndex]
            if face.is_a() == "IfcIndexedPolygonalFaceWithVoids":
                inner = face.InnerCoordIndices
                loops += list(inner) if isinstance(inner, tuple) and inner else [None]
            for idx in loops:
                if _bad_index(idx, n):
                    ok = False
                    errors.append(f"#{face.id()} {face.is_a()} indices {idx!r}: expected 3 or more indices "
                                  f"1..{n} of its face set #{s.id()}'s points")
                    continue
                tri += [(idx[0] - 1, idx[j] - 1, idx[j + 1] - 1) for j in range(1, len(idx) - 1)]
        T = np.asarray(tri, dtype=np.int64).reshape(-1, 3)
        if not ok or len(T) == 0:                                  # no shape: a NaN volume fails the check
            set_volume[s.id()] = float("nan")
            continue
        a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
        set_volume[s.id()] = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6.0
    for face in f.by_type("IfcIndexedPolygonalFace"):
        if face.id() not in used:
            errors.append(f"#{face.id()} IfcIndexedPolygonalFace: used by no IfcPolygonalFaceSet (ToFaceSet [1:?])")
    volumes: dict[str, float] = {}
    for el in f.by_type("IfcElement"):
        if el.is_a("IfcCurtainWall") or el.Representation is None:
            continue
        volumes[el.Name] = sum(set_volume[item.id()] for rep in el.Representation.Representations
                               for item in rep.Items if item.is_a("IfcPolygonalFaceSet"))
    return volumes, errors


def face_rule_errors(f) -> list[str]:
    """The face rules of :func:`read_face_sets`."""
    return read_face_sets(f)[1]


def face_set_volumes(f) -> dict[str, float]:
    """The element volumes of :func:`read_face_sets`."""
    return read_face_sets(f)[0]


CUT_LIST = "steel_cut_list.csv"
LENGTH_TOL_MM = 0.05
"""How far an IFC length may be from the steel cut list's (which writes 0.1 mm)."""


def check_ifc(path: Path, bom, *, full: bool = True, kernel: bool = False, tol: Tolerances = DEFAULT,
              cut_list: Path | None = None) -> dict:
    """``full``: schema validation and volumes (``kernel``: ifcopenshell's geometry kernel, else the
    face sets' own coordinates as parsed, about 20x faster).  Always: the shop assemblies
    (:func:`_assembly_errors`) and, when the run wrote ``cut_list`` (default: ``steel_cut_list.csv``
    beside the IFC file), every piece's length against it (:func:`_length_errors`).  The whole check
    holds ifcopenshell (:func:`fabricate.export.ifc.ifcopenshell_alone`): two runs' checks in threads of
    one process take turns."""
    from .ifc import ifcopenshell_alone

    with ifcopenshell_alone():
        return _check_ifc(path, bom, full, kernel, tol, cut_list)


def ifc_rows(bom) -> tuple[dict[str, dict], dict[str, set[str]]]:
    """``(rows, assemblies)`` the IFC file must hold for the BOM: ``rows`` element name -> BOM row (a glass
    unit of several solids (``P0001.1 ...``) one element, its volumes summed; every steel solid its own
    element), ``assemblies`` every steel unit of several solids (a beam welded from plates, a tube hub)
    -> the ids of its solids (one ``IfcElementAssembly`` each)."""
    from fabricate.cad.parts import unit_id

    rows: dict[str, dict] = {}
    units: dict[str, set[str]] = {}
    for r in bom:
        u = unit_id(r["id"])
        if r["kind"] != "panel":
            rows[r["id"]] = r
            units.setdefault(u, set()).add(r["id"])
        elif u in rows:
            rows[u] = dict(rows[u], volume_mm3=repr(float(rows[u]["volume_mm3"]) + float(r["volume_mm3"])))
        else:
            rows[u] = r
    return rows, {u: ids for u, ids in units.items() if ids != {u}}


def _assembly_errors(f, elements: dict, assemblies: dict[str, set[str]]) -> list[str]:
    """Every shop assembly an ``IfcElementAssembly`` aggregating exactly its solids, and every solid of an
    assembly in exactly one (``"<id>: why"``)."""
    bad = []
    held: dict[str, int] = {}
    for a in f.by_type("IfcElementAssembly"):
        own = [p.Name for rel in a.IsDecomposedBy for p in rel.RelatedObjects]
        for p in own:
            held[p] = held.get(p, 0) + 1
        want = assemblies.get(a.Name)
        if want is None:
            bad.append(f"{a.Name}: an IfcElementAssembly of no BOM unit of several solids")
        elif set(own) != want or len(own) != len(want):
            bad.append(f"{a.Name}: parts {' '.join(sorted(own)) or 'none'}, expected {' '.join(sorted(want))}")
    for u, ids in sorted(assemblies.items()):
        if u not in elements or not elements[u].is_a("IfcElementAssembly"):
            bad.append(f"{u}: expected an IfcElementAssembly of {' '.join(sorted(ids))}")
        bad += [f"{pid}: in {held.get(pid, 0)} assemblies, expected 1 ({u})" for pid in sorted(ids)
                if held.get(pid, 0) != 1]
    return bad


def ifc_lengths(f) -> dict[str, dict[str, float]]:
    """Element name -> its lengths as written: ``quantity`` (an ``IfcQuantityLength`` ``Length`` of its
    quantity sets) and ``length_mm`` (the project's property set :data:`fabricate.export.ifc.PSET`), in one
    pass over the property relations."""
    from .ifc import PSET

    out: dict[str, dict[str, float]] = {}
    for rel in f.by_type("IfcRelDefinesByProperties"):
        d = rel.RelatingPropertyDefinition
        if d.is_a("IfcElementQuantity"):
            found = [("quantity", q.LengthValue) for q in d.Quantities
                     if q.is_a("IfcQuantityLength") and q.Name == "Length"]
        elif d.is_a("IfcPropertySet") and d.Name == PSET:
            found = [("length_mm", p.NominalValue.wrappedValue) for p in d.HasProperties
                     if p.Name == "length_mm" and p.is_a("IfcPropertySingleValue") and p.NominalValue is not None]
        else:
            continue
        for o in rel.RelatedObjects:
            out.setdefault(o.Name, {}).update(found)
    return out


def _length_errors(f, cut_list: Path) -> list[str]:
    """Every row of the steel cut list (a beam, a plate, a hub, its tube and caps): its element in the
    file, whose ``length_mm`` and ``Length`` quantity (where it has one) are the row's ``length_mm``
    within :data:`LENGTH_TOL_MM` (``"<id>: why"``)."""
    import csv

    lengths = ifc_lengths(f)
    bad = []
    with open(cut_list, newline="", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            pid, want = row["id"], float(row["length_mm"])
            have = lengths.get(pid)
            if not have or "length_mm" not in have:
                bad.append(f"{pid}: no length_mm in the IFC file, the cut list says {row['length_mm']} mm")
                continue
            for key, v in sorted(have.items()):
                if not abs(float(v) - want) <= LENGTH_TOL_MM:
                    bad.append(f"{pid}: IFC {key} {float(v):.2f} mm, cut list length_mm {row['length_mm']}")
    return bad


def _check_ifc(path: Path, bom, full: bool, kernel: bool, tol: Tolerances, cut_list: Path | None) -> dict:
    import ifcopenshell

    from .ifc import open_ifc

    f = open_ifc(path)
    elements = {e.Name: e for e in f.by_type("IfcElement") if not e.is_a("IfcCurtainWall")}
    rows, assemblies = ifc_rows(bom)
    bad_tag = sorted(n for n, e in elements.items() if e.Tag != n)[:20]
    extra: dict = {"bad_tag": bad_tag, "assemblies": len(assemblies),
                   "bad_assembly": _assembly_errors(f, elements, assemblies)[:20]}
    cut_list = Path(path).with_name(CUT_LIST) if cut_list is None else Path(cut_list)
    if cut_list.is_file():
        extra["lengths_from"] = cut_list.name
        extra["bad_length"] = _length_errors(f, cut_list)[:20]
    if full:
        import ifcopenshell.validate

        from .ifc import read_ifc

        log = ifcopenshell.validate.json_logger()
        ifcopenshell.validate.validate(_without_faces(f), log)
        parsed, face_errors = read_face_sets(f)
        extra["bad_schema"] = ([str(s.get("message", s))[:200] for s in log.statements[:10]] + face_errors[:10])[:10]
        volumes = {pid: item["volume_mm3"] for pid, item in read_ifc(path).items()} if kernel else parsed
        errors = {pid: abs(v / float(rows[pid]["volume_mm3"]) - 1.0) for pid, v in volumes.items() if pid in rows}
        extra["volumes_from"] = "ifcopenshell geometry kernel" if kernel else "face sets as parsed"
        extra["volume_rel_error_max"] = max(errors.values(), default=0.0)
        # no shape (NaN) is as bad as a wrong volume
        extra["bad_volume"] = sorted(pid for pid, e in errors.items() if not e <= tol.file_volume)[:20]
    return _ids_result(set(rows) | set(assemblies), set(elements), extra)


def check_3dm(path: Path, bom) -> dict:
    from .rhino import read_3dm_parts

    objects = read_3dm_parts(path)
    rows = {r["id"]: r for r in bom}
    found = {n for n, o in objects.items() if o["layer"] in KIND_LAYER.values()}
    bad_layer = sorted(n for n in found & set(rows) if objects[n]["layer"] != KIND_LAYER[rows[n]["kind"]])[:20]
    bad_strings = sorted(n for n in found & set(rows)
                         if objects[n]["strings"].get("volume_mm3") != rows[n]["volume_mm3"])[:20]
    bad_units = sorted(n for n in found if not str(objects[n].get("units", "")).endswith("Millimeters"))[:20]
    return _ids_result(set(rows), found, {"bad_layer": bad_layer, "bad_strings": bad_strings,
                                          "bad_units": bad_units})


def nc1_expected(bom) -> dict[str, dict]:
    """The BOM rows that have an NC1 file: every beam plate and every hub tube (``member`` ``tube``)."""
    return {r["id"]: r for r in bom if r["kind"] == "beam" or (r["kind"] == "node" and r.get("member") == "tube")}


def _nc1_bad(h: dict, row: dict) -> str:
    """Why an NC1 header disagrees with its BOM row ('' when it agrees)."""
    weight = h["weight_per_m"] * h["length"] * 1e-3
    tube = row["kind"] == "node"
    why = []
    if h["code"] != ("RO" if tube else "B"):
        why.append(f"profile code {h['code']!r}, expected {'RO' if tube else 'B'}")
    if abs(h["web_thickness"] - float(row["thickness_mm"])) > 1e-3:
        why.append(f"web thickness {h['web_thickness']:g} mm, BOM thickness_mm {row['thickness_mm']}")
    if abs(weight - float(row["weight_kg"])) > 1e-3 * max(float(row["weight_kg"]), 1.0):
        why.append(f"weight {weight:.3f} kg, BOM weight_kg {row['weight_kg']}")
    if tube:
        if abs(h["length"] - float(row["length_mm"])) > 2e-3:
            why.append(f"length {h['length']:g} mm, BOM length_mm {row['length_mm']}")
        if h["flange_thickness"] != h["web_thickness"]:
            why.append(f"flange thickness {h['flange_thickness']:g} mm is not the wall {h['web_thickness']:g} mm")
        if h["profile"] != f"RO{h['height']:g}x{h['web_thickness']:g}":
            why.append(f"profile {h['profile']!r}, expected RO{h['height']:g}x{h['web_thickness']:g}")
    return "; ".join(why)


def check_nc1(folder: Path, bom) -> dict:
    """One NC1 file per :func:`nc1_expected` row, its header held to the row (``bad_files``:
    ``"<id>: why"``)."""
    from .nc1_read import read_nc1

    rows = nc1_expected(bom)
    found, bad = set(), []
    for path in sorted(Path(folder).glob("*.nc1")):
        try:
            h = read_nc1(path)["header"]
        except ValueError as exc:
            bad.append(f"{path.name}: {exc}")
            continue
        found.add(path.stem)
        row = rows.get(path.stem)
        if row is None:
            continue
        why = f"piece {h['piece']!r} in file {path.name}" if h["piece"] != path.stem else _nc1_bad(h, row)
        if why:
            bad.append(f"{path.stem}: {why}")
    return _ids_result(set(rows), found, {"bad_files": bad[:20]})
