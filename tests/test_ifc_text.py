"""The IFC4 text writer (:mod:`fabricate.export.ifc_text`) against the former writer, which created
every entity through ifcopenshell (kept here as the reference): both files opened with ifcopenshell
and compared element by element (class, predefined and object type, description, tag, placement,
every face set's exact coordinates and face indices, every property and quantity with its type,
materials and layer sets, the spatial and aggregation relations), entity counts per class, valid
and unique GlobalIds, ``ifcopenshell.validate`` on the new file, strings with quotes, backslashes
and non-ASCII characters read back as written."""
import dataclasses
import time
from pathlib import Path

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.export.ifc import CLASS, PSET, _faces, _skeleton, ifc_units, write_ifc
from fabricate.export.ifc_text import new_guids, point_lists, real, string
from optimize.atomic import atomic_open
from optimize.errors import ExportError

import ifcopenshell  # noqa: E402 - a declared dependency: missing, the test fails
import ifcopenshell.guid  # noqa: E402

RHS_HUB_INSULATED = {  # benchmarks/bench_cad.py SECTIONS["rhs"] and GLASS_INSULATED
    "beam": {"section": "rhs", "web_mm": 5.0, "flange_mm": 5.0, "flange_width_mm": 100.0},
    "node": {"connection": "hub", "hub": "tube", "radius_mm": 110.0, "wall_mm": 10.0, "cap_mm": 15.0},
    "glass": {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10.0}, "cavity_mm": 16.0,
              "inner": {"type": "laminated", "plies_mm": [6.0, 6.0], "interlayer": "PVB", "interlayer_mm": 1.52}}}


# the former writer, the reference ------------------------------------------------------

class _Writer:
    """Entity factory over one ``ifcopenshell.file`` (direct creation: thousands of parts in seconds)."""

    def __init__(self, f, refs: dict):
        self.f, self.refs = f, refs
        self.guid = ifcopenshell.guid.new
        self.origin, self.body = f.by_id(refs["origin"]), f.by_id(refs["body"])

    def placement(self, parent=None):
        return self.f.createIfcLocalPlacement(parent, self.origin)

    def aggregate(self, whole, parts) -> None:
        self.f.createIfcRelAggregates(self.guid(), None, None, None, whole, list(parts))

    def solid(self, V: np.ndarray, faces) -> object:
        """A closed ``IfcPolygonalFaceSet`` of one polyhedron: V (nv, 3) mm, faces outward vertex-index
        tuples (0-based; IFC counts from 1), or, for a face with holes, its loops (the outer one, then
        each hole: an ``IfcIndexedPolygonalFaceWithVoids``).  Every face is a planar polygon, so the set
        is the solid."""
        f = self.f
        points = f.createIfcCartesianPointList3D(V.tolist())
        polys = [f.createIfcIndexedPolygonalFace([i + 1 for i in face]) if not isinstance(face[0], tuple)
                 else f.createIfcIndexedPolygonalFaceWithVoids([i + 1 for i in face[0]],
                                                             [[i + 1 for i in hole] for hole in face[1:]])
                 for face in faces]
        return f.createIfcPolygonalFaceSet(points, True, polys, None)

    def shape(self, items) -> object:
        rep = self.f.createIfcShapeRepresentation(self.body, "Body", "Tessellation", list(items))
        return self.f.createIfcProductDefinitionShape(None, None, [rep])

    def props(self, obj, name: str, values: dict) -> None:
        """A property set of single values (str, float, int) on ``obj``."""
        f = self.f
        singles = []
        for key, value in values.items():
            if isinstance(value, str):
                v = f.createIfcLabel(value) if len(value) <= 255 else f.createIfcText(value)
            elif isinstance(value, (int, np.integer)):
                v = f.createIfcInteger(int(value))
            else:
                v = f.createIfcReal(float(value))
            singles.append(f.createIfcPropertySingleValue(key, None, v, None))
        pset = f.createIfcPropertySet(self.guid(), None, name, None, singles)
        f.createIfcRelDefinesByProperties(self.guid(), None, None, None, [obj], pset)

    def quantities(self, obj, name: str, values: dict) -> None:
        """``values``: key -> (kind, number), kind one of length, area, volume, weight."""
        f = self.f
        make = {"length": f.createIfcQuantityLength, "area": f.createIfcQuantityArea,
                "volume": f.createIfcQuantityVolume, "weight": f.createIfcQuantityWeight}
        qs = [make[kind](key, None, None, float(v), None) for key, (kind, v) in values.items()]
        qto = f.createIfcElementQuantity(self.guid(), None, name, None, None, qs)
        f.createIfcRelDefinesByProperties(self.guid(), None, None, None, [obj], qto)


CLASSES = {"IFCPLATE": "IfcPlate", "IFCMEMBER": "IfcMember", "IFCELEMENTASSEMBLY": "IfcElementAssembly"}


def reference_write_ifc(parts, path, *, grade: str | None = None, project: str = "conical-fab") -> dict:
    """The former ``write_ifc``: every entity created through ifcopenshell, then ``to_string``; the
    skeleton and the figures of every element (:func:`ifc_units`) are the package's (what is compared is
    how each writer puts them in the file).  Returns facts: ``file, bytes, elements`` per kind,
    ``assemblies``, ``seconds``."""
    t0 = time.perf_counter()
    grade = grade or getattr(parts.spec, "steel_grade", "S355")
    path = Path(path)
    f, refs = _skeleton(project, grade, parts, path.name)
    units = ifc_units(parts, grade, refs)
    w = _Writer(f, refs)
    groups = list(parts.groups)
    materials: dict[str, list] = {}

    def element(u, parent):
        place = w.placement(parent)
        shape = w.shape([w.solid(groups[gi].vertices[i], _faces(groups[gi])) for gi, i in u.solids]) if u.solids else None
        extra = {"AssemblyPlace": "FACTORY"} if u.cls == "IFCELEMENTASSEMBLY" else {}
        el = f.create_entity(CLASSES[u.cls], GlobalId=w.guid(), Name=u.uid, Description=u.description,
                             ObjectType=u.object_type, ObjectPlacement=place, Representation=shape, Tag=u.uid,
                             PredefinedType=u.predefined, **extra)
        materials.setdefault(u.material, []).append(el)
        w.quantities(el, u.qto_name, u.quantities)
        w.props(el, PSET, u.props)
        kids = [element(p, place) for p in u.parts]
        if kids:
            w.aggregate(el, kids)
        return el
    wall = f.by_id(refs["wall"])
    top = [element(u, wall.ObjectPlacement) for u in units]
    if top:
        w.aggregate(wall, top)
    for key, els in materials.items():
        f.createIfcRelAssociatesMaterial(w.guid(), None, None, None, els, f.by_id(refs[key]))
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            fh.write(f.to_string())
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the IFC file ({exc.strerror or exc})") from None
    return {"file": path.name, "bytes": path.stat().st_size, "schema": "IFC4",
            "elements": {k: sum(u.kind == k for u in units) for k in CLASS},
            "assemblies": sum(bool(u.parts) for u in units), "seconds": time.perf_counter() - t0}


# the comparison ------------------------------------------------------------------------------------

def _parts(spec: dict, n_around: int = 6, k: int = 3):
    from fabricate.cad import PartSpec, build_parts

    return build_parts(dome_structure(n_around=n_around, k=k), PartSpec(beam_width=80.0, **spec))


@pytest.fixture(scope="module")
def plate_parts():
    return _parts({"node_radius": 40.0})   # plate beams, solid hubs, monolithic glass


@pytest.fixture(scope="module")
def hub_parts():
    return _parts(RHS_HUB_INSULATED)


def _placement(p) -> list:
    out = []
    while p is not None:
        rel = p.RelativePlacement
        out.append((rel.Location.Coordinates, rel.Axis and rel.Axis.DirectionRatios,
                    rel.RefDirection and rel.RefDirection.DirectionRatios))
        p = p.PlacementRelTo
    return out


def _material(m):
    if m.is_a("IfcMaterialProfileSet"):
        return ("profiles", m.Name, m.Description, tuple(
            (p.Name, _material(p.Material), p.Profile.is_a(), tuple(p.Profile)) for p in m.MaterialProfiles))
    props = sorted((p.Name, tuple((v.Name, v.NominalValue.is_a(), v.NominalValue.wrappedValue) for v in p.Properties))
                   for p in (m.HasProperties or ()))
    return (m.Name, m.Description, m.Category, tuple(props))


def _associated(el) -> list:
    out = []
    for rel in el.HasAssociations:
        m = rel.RelatingMaterial
        if m.is_a("IfcMaterialLayerSet"):
            out.append(("layers", m.LayerSetName, m.Description, tuple(
                (_material(ly.Material), ly.LayerThickness, ly.IsVentilated, ly.Name, ly.Description, ly.Category,
                 ly.Priority) for ly in m.MaterialLayers)))
        else:
            out.append(("material", _material(m)))
    return sorted(out, key=repr)


def _definitions(el) -> dict:
    out = {}
    for rel in el.IsDefinedBy:
        d = rel.RelatingPropertyDefinition
        if d.is_a("IfcPropertySet"):
            out[("pset", d.Name)] = [(p.is_a(), p.Name, p.Description, p.NominalValue.is_a(), p.NominalValue.wrappedValue,
                                      p.Unit) for p in d.HasProperties]
        else:
            out[("qto", d.Name)] = [(q.is_a(), q.Name, q.Description, q.Unit, q[3], q.Formula) for q in d.Quantities]
        assert list(rel.RelatedObjects) == [el]
    return out


def _face_sets(el) -> list:
    if el.Representation is None:   # an assembly: its parts have the bodies
        return []
    rep, = el.Representation.Representations
    assert el.Representation.Name is None and el.Representation.Description is None
    out = [(rep.RepresentationIdentifier, rep.RepresentationType, rep.ContextOfItems.ContextIdentifier,
            rep.ContextOfItems.ContextType, rep.ContextOfItems.TargetView)]
    for item in rep.Items:
        faces = [(fc.is_a(), fc.CoordIndex, fc.InnerCoordIndices if fc.is_a("IfcIndexedPolygonalFaceWithVoids") else None)
                 for fc in item.Faces]
        out.append((item.is_a(), item.Closed, item.PnIndex, item.Coordinates.is_a(), item.Coordinates.CoordList, faces))
    return out


def _model(path) -> dict:
    """Everything a reader sees in the file, without ids and GlobalIds."""
    f = ifcopenshell.open(str(path))
    project, = f.by_type("IfcProject")
    site, = f.by_type("IfcSite")
    building, = f.by_type("IfcBuilding")
    storey, = f.by_type("IfcBuildingStorey")
    wall, = f.by_type("IfcCurtainWall")

    def plain(v):
        return not isinstance(v, ifcopenshell.entity_instance) and (not isinstance(v, tuple) or all(map(plain, v)))

    def attrs(e):  # its own values (references compared where they matter)
        return tuple(v for k, v in e.get_info(recursive=False).items() if k not in ("id", "type", "GlobalId")
                     and plain(v))
    elements = {}
    for el in f.by_type("IfcElement"):
        if el.is_a("IfcCurtainWall"):
            continue
        assert el.Name not in elements
        whole, = el.Decomposes
        elements[el.Name] = {
            "class": el.is_a(), "predefined": el.PredefinedType, "object_type": el.ObjectType,
            "description": el.Description, "tag": el.Tag, "owner": el.OwnerHistory,
            "placement": _placement(el.ObjectPlacement), "shape": _face_sets(el),
            "definitions": _definitions(el), "materials": _associated(el),
            "in": (whole.RelatingObject.is_a(), whole.RelatingObject.Name), "contained": el.ContainedInStructure}
    aggregates = sorted((r.RelatingObject.is_a(), r.RelatingObject.Name, len(r.RelatedObjects))
                        for r in f.by_type("IfcRelAggregates"))
    contained = [(r.RelatingStructure.Name, [e.Name for e in r.RelatedElements])
                 for r in f.by_type("IfcRelContainedInSpatialStructure")]
    sub, = f.by_type("IfcGeometricRepresentationSubContext")
    context = [c for c in f.by_type("IfcGeometricRepresentationContext") if not c.is_a("IfcGeometricRepresentationSubContext")]
    guids = [e.GlobalId for e in f.by_type("IfcRoot")]
    counts = {}
    for e in f:
        counts[e.is_a()] = counts.get(e.is_a(), 0) + 1
    return {"elements": elements, "aggregates": aggregates, "contained": contained, "counts": counts,
            "spatial": [attrs(e) + (_placement(e.ObjectPlacement),) for e in (site, building, storey, wall)],
            "project": attrs(project), "units": sorted(attrs(u) for u in project.UnitsInContext.Units),
            "contexts": [attrs(c) for c in context] + [attrs(sub)], "schema": f.schema,
            "materials": sorted(_material(m) for m in f.by_type("IfcMaterial")), "guids": guids}


def _guids_valid(guids) -> None:
    assert len(set(guids)) == len(guids)
    for g in guids:
        assert len(g) == 22 and g[0] in "0123" and ifcopenshell.guid.compress(ifcopenshell.guid.expand(g)) == g


@pytest.mark.parametrize("which", ["plate", "hub"])
def test_text_writer_writes_what_the_ifcopenshell_writer_wrote(which, plate_parts, hub_parts, tmp_path):
    parts = plate_parts if which == "plate" else hub_parts
    facts = write_ifc(parts, tmp_path / "new.ifc")
    ref = reference_write_ifc(parts, tmp_path / "ref.ifc")
    assert {k: v for k, v in facts.items() if k not in ("file", "seconds", "bytes")} == \
        {k: v for k, v in ref.items() if k not in ("file", "seconds", "bytes")}   # bytes: reals written shortest
    new, old = _model(tmp_path / "new.ifc"), _model(tmp_path / "ref.ifc")
    _guids_valid(new["guids"])
    assert len(new["guids"]) == len(old["guids"])
    for key in old:
        if key not in ("elements", "guids"):
            assert new[key] == old[key], key
    ids = [(g.kind, pid) for g in parts.groups for pid in g.ids]   # a glass unit one element, steel: every solid
    assert set(new["elements"]) == set(old["elements"]) == ({pid.split(".")[0] for _, pid in ids}
                                                            | {pid for kind, pid in ids if kind != "panel"})
    for name, el in old["elements"].items():
        assert new["elements"][name] == el, name
    if which == "hub":  # the cases this test is for: multi-solid units, faces with voids, every value type
        voids = [s for el in new["elements"].values() for s in el["shape"][1:]
                 if any(fc[0] == "IfcIndexedPolygonalFaceWithVoids" for fc in s[5])]
        assert voids and max(len(el["shape"]) for el in new["elements"].values()) > 2
        assert new["counts"]["IfcMaterialLayer"] == 5
    # the coordinates are the parts' own vertices, exactly
    group = parts.groups[-1]
    el = new["elements"].get(group.ids[0]) or new["elements"][group.ids[0].split(".")[0]]
    assert any(np.array_equal(np.array(s[4]), group.vertices[0]) for s in el["shape"][1:])


def test_the_new_file_is_valid_ifc4_with_the_express_rules_and_passes_the_file_check(tmp_path):
    """On a smaller dome of RHS beams, tube hubs and insulated glass (the express rules are checked
    entity by entity in Python: seconds per thousand)."""
    import ifcopenshell.validate

    hub_parts = _parts(RHS_HUB_INSULATED, n_around=4, k=2)

    from fabricate.export import write_bom
    from fabricate.export.bom import read_bom
    from fabricate.export.exchange_check import check_ifc

    path = tmp_path / "model.ifc"
    write_ifc(hub_parts, path)
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(ifcopenshell.open(str(path)), log, express_rules=True)
    assert log.statements == []
    write_bom(hub_parts, tmp_path / "bom.csv")
    result = check_ifc(path, read_bom(tmp_path / "bom.csv"), full=True)
    assert result["pass"] and result["bad_schema"] == [], result


ODD = "B'0001\\ Ü€😀"


def _renamed(parts, old: str, new: str):
    def name(pid):
        unit, dot, k = pid.partition(".")
        return (new if unit == old else unit) + dot + k
    groups = tuple(dataclasses.replace(g, ids=tuple(map(name, g.ids)),
                                       neighbours=tuple(tuple(map(name, n)) for n in g.neighbours))
                   for g in parts.groups)
    return dataclasses.replace(parts, groups=groups)


def test_quotes_backslashes_and_non_ascii_read_back_as_written(hub_parts, tmp_path):
    parts = _renamed(hub_parts, "B0001", ODD)
    project = "Bahnhof d'Été \\ 東京"
    write_ifc(parts, tmp_path / "new.ifc", project=project, grade="S355 'J2'")
    reference_write_ifc(parts, tmp_path / "ref.ifc", project=project, grade="S355 'J2'")
    assert (tmp_path / "new.ifc").read_bytes().isascii()
    new, old = _model(tmp_path / "new.ifc"), _model(tmp_path / "ref.ifc")
    assert new["elements"][ODD] == old["elements"][ODD]
    assert new["elements"][ODD]["definitions"][("pset", PSET)][0][4] == ODD
    assert new["project"] == old["project"] and project in new["project"]
    assert new["materials"] == old["materials"]
    for s in ("", "'", "''", "\\", "a\\X2\\b", "\x07\t\n", "é😀€", "x" * 300):
        f = ifcopenshell.file.from_string(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\n"
            f"FILE_SCHEMA(('IFC4'));\nENDSEC;\nDATA;\n#1=IFCMATERIAL({string(s)},$,$);\nENDSEC;\nEND-ISO-10303-21;\n")
        assert f.by_id(1).Name == s


def test_reals_and_guids():
    values = np.array([[[0.0, -0.0, 1.0], [1e-5, 1e20, -1e-300], [0.1, 1 / 3, 123456789.123456789],
                        [5e-324, 1.7976931348623157e308, 2.5e16]]])
    text, = point_lists(values)
    assert "e" not in text and " " not in text
    back = [float(x) for x in text.replace("(", "").replace(")", "").split(",")]
    assert back == values.ravel().tolist()
    for v in values.ravel():
        r = real(v)
        assert float(r) == v and "." in r and "e" not in r
    assert real(1.0) == "1." and real(1e-5) == "1.E-05"
    guids = new_guids(10000)
    _guids_valid(guids)
    assert all(ifcopenshell.guid.expand(g)[12] == "4" for g in guids[:100])       # version 4 UUIDs


def test_a_write_error_is_an_export_error(plate_parts, tmp_path):
    with pytest.raises(ExportError, match="cannot write the IFC file"):
        (tmp_path / "a_file").write_text("")
        write_ifc(plate_parts, tmp_path / "a_file" / "model.ifc")
