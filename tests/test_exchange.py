"""Exchange formats: IFC4 read back by ifcopenshell (schema + express rules, its own geometry kernel),
Rhino .3dm written and read back by rhino3dm, a .3dm quad mesh as input."""
import numpy as np
import pytest
from cad_fixtures import dome_parts, dome_structure

from fabricate.export import write_3dm, write_bom, write_ifc
from fabricate.export.nc1 import write_nc1
from fabricate.export.bom import read_bom
from optimize.errors import MeshError
from optimize.mesh.io import read_mesh

import ifcopenshell  # noqa: E402 - declared dependencies: a missing one fails, never skips
import rhino3dm  # noqa: E402


@pytest.fixture(scope="module")
def parts():
    return dome_parts(6, 3)


@pytest.fixture(scope="module")
def small_parts():
    """A few parts of every kind, for the checks that cost seconds per hundred parts."""
    return dome_parts(4, 2)


@pytest.fixture(scope="module")
def bom(parts, tmp_path_factory):
    path = tmp_path_factory.mktemp("bom") / "bom.csv"
    write_bom(parts, path)
    return read_bom(path)


@pytest.fixture(scope="module")
def ifc_file(parts, tmp_path_factory):
    path = tmp_path_factory.mktemp("ifc") / "model.ifc"
    facts = write_ifc(parts, path)
    return path, facts


def test_ifc_is_valid_ifc4_with_the_express_rules(small_parts, tmp_path):
    import ifcopenshell.validate

    path = tmp_path / "model.ifc"
    facts = write_ifc(small_parts, path)
    assert facts["schema"] == "IFC4" and min(facts["elements"].values()) > 0
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(ifcopenshell.open(str(path)), log, express_rules=True)
    assert log.statements == []
    assert not list(path.parent.glob(".*part"))  # written atomically


def test_ifc_has_one_element_per_bom_row_with_the_step_volume(ifc_file, parts, bom):
    from fabricate.export.ifc import read_ifc

    path, facts = ifc_file
    elements = read_ifc(path)
    assert sorted(elements) == sorted(row["id"] for row in bom)
    for row in bom:
        el = elements[row["id"]]
        assert el["tag"] == row["id"]
        assert el["class"] == {"panel": "IfcPlate", "beam": "IfcMember", "node": "IfcMember"}[row["kind"]]
        assert el["volume_mm3"] == pytest.approx(float(row["volume_mm3"]), rel=1e-6)
    assert facts["elements"] == {"panel": len(parts.panels), "beam": len(parts.beams), "node": len(parts.nodes)}


def test_ifc_hierarchy_materials_quantities_and_fabrication_figures(ifc_file, parts):
    import ifcopenshell.util.element as eu

    from fabricate.export.schedules import beam_lengths

    f = ifcopenshell.open(str(ifc_file[0]))
    project, = f.by_type("IfcProject")
    site, = f.by_type("IfcSite")
    building, = f.by_type("IfcBuilding")
    storey, = f.by_type("IfcBuildingStorey")
    wall, = f.by_type("IfcCurtainWall")
    assert eu.get_aggregate(site) == project and eu.get_aggregate(building) == site
    assert eu.get_aggregate(storey) == building and eu.get_container(wall) == storey
    assert {e.Name for e in eu.get_decomposition(wall)} == {p.id for p in parts}
    unit, = [u for u in f.by_type("IfcSIUnit") if u.UnitType == "LENGTHUNIT"]
    assert (unit.Prefix, unit.Name) == ("MILLI", "METRE")
    panel = parts.panels[0]
    plate = next(e for e in f.by_type("IfcPlate") if e.Name == panel.id)
    assert plate.PredefinedType == "CURTAIN_PANEL"
    layers = eu.get_material(plate)
    assert layers.is_a("IfcMaterialLayerSet")
    assert sum(lay.LayerThickness for lay in layers.MaterialLayers) == pytest.approx(parts.spec.glass_thickness)
    psets = eu.get_psets(plate)
    assert psets["Qto_PlateBaseQuantities"]["NetArea"] == pytest.approx(panel.area_mm2 * 1e-6)
    assert psets["Qto_PlateBaseQuantities"]["NetWeight"] == pytest.approx(
        panel.volume_mm3 * 1e-9 * parts.spec.density_glass)
    assert psets["ConicalFab_Fabrication"]["planarity_mm"] == pytest.approx(panel.planarity_mm)
    beam = parts.beams[0]
    member = next(e for e in f.by_type("IfcMember") if e.Name == beam.id)
    assert member.PredefinedType == "MULLION"     # a plate beam: one member, its section's profile set
    profile, = eu.get_material(member).MaterialProfiles
    assert profile.Material.Name == "S355J2" and profile.Profile.is_a("IfcRectangleProfileDef")
    q = eu.get_psets(member)
    assert q["ConicalFab_Fabrication"]["twist_mm"] == pytest.approx(beam.planarity_mm)
    length = beam_lengths(parts)[1][beam.id]                   # one length: the cut list's, the NC1's
    assert q["Qto_MemberBaseQuantities"]["Length"] == q["ConicalFab_Fabrication"]["length_mm"] == length


def test_3dm_layers_names_user_strings_and_exact_vertices(parts, bom, tmp_path):
    from fabricate.export.rhino import read_3dm_parts

    structure = dome_structure(n_around=6, k=3)
    path = tmp_path / "model.3dm"
    facts = write_3dm(parts, path, structure=structure)
    objects = read_3dm_parts(path)
    counts = {}
    for item in objects.values():
        counts[item["layer"]] = counts.get(item["layer"], 0) + 1
    assert counts == {k: v for k, v in facts["objects"].items() if v}
    assert counts["glass"] == len(parts.panels) and counts["steel"] == len(parts.beams)
    assert counts["nodes"] == len(parts.nodes) and counts["offset layers"] == len(structure.distances)
    assert counts["design mesh"] == 1 and counts["node axes"] == parts.mesh.n_vertices
    for row in bom:
        item = objects[row["id"]]
        for key in ("kind", "element", "volume_mm3", "weight_kg", "neighbours"):
            assert item["strings"][key] == row[key], (row["id"], key)
        assert str(item["units"]).endswith("Millimeters")
        V = parts.by_id[row["id"]].vertices
        np.testing.assert_allclose(item["vertices"], V, rtol=0, atol=1e-6)


def _write_rhino_mesh(path, meshes=(), breps=0):
    model = rhino3dm.File3dm()
    for layer_name in ("Default", "Roof::Glass"):
        layer = rhino3dm.Layer()
        layer.Name = layer_name.split("::")[-1]
        model.Layers.Add(layer)
    for name, layer, V, F in meshes:
        m = rhino3dm.Mesh()
        m.Vertices.UseDoublePrecisionVertices = True
        m.Vertices.SetCount(len(V))
        for j, p in enumerate(V.tolist()):
            m.Vertices.SetPoint3dAt(j, rhino3dm.Point3d(*p))
        for f in F.tolist():
            m.Faces.AddFace(*[i for i in f if i >= 0])
        a = rhino3dm.ObjectAttributes()
        a.Name, a.LayerIndex = name, layer
        model.Objects.AddMesh(m, a)
    for _ in range(breps):
        model.Objects.AddBrep(rhino3dm.Brep.CreateFromBox(rhino3dm.Box(rhino3dm.BoundingBox(0, 0, 0, 1, 1, 1))))
    assert model.Write(str(path), 7)


def test_3dm_quad_mesh_reads_back_exactly_and_is_picked_by_layer_or_name(tmp_path, perturbed_revolution):
    m = perturbed_revolution
    tri = np.array([[0, 1, 2, -1]])
    path = tmp_path / "roof.3dm"
    _write_rhino_mesh(path, [("roof", 1, m.V, m.F), ("scrap", 0, m.V[:3], tri)])
    with pytest.raises(MeshError, match=r"2 mesh objects match.*'roof'.*'scrap'"):
        read_mesh(path)
    got = read_mesh(path, name="roof")
    np.testing.assert_array_equal(got.V, m.V)
    np.testing.assert_array_equal(got.F, m.F)
    assert read_mesh(path, layer="Glass").n_faces == m.n_faces
    assert read_mesh(path, layer="Default").n_faces == 1  # a triangle stays a triangle
    with pytest.raises(MeshError, match=r"input.layer 'Steel': no mesh on that layer.*'Default'.*'Glass'"):
        read_mesh(path, layer="Steel")
    with pytest.raises(MeshError, match=r"input.object 'roof2'.*'roof'"):
        read_mesh(path, name="roof2")


def test_3dm_with_only_surfaces_says_how_to_mesh_them(tmp_path):
    path = tmp_path / "nurbs.3dm"
    _write_rhino_mesh(path, breps=2)
    with pytest.raises(MeshError, match=r"nurbs.3dm: no mesh object in the file \(2 Brep\).*_Mesh"):
        read_mesh(path)
    (tmp_path / "junk.3dm").write_bytes(b"not rhino")
    with pytest.raises(MeshError, match="not a readable Rhino .3dm file"):
        read_mesh(tmp_path / "junk.3dm")


def test_a_3dm_quad_mesh_runs_through_fabricate_run_to_cut_files(tmp_path):
    """A Rhino user's roof: a quad mesh on a layer of a .3dm file in metres, picked by layer and name,
    goes to cut files, IFC and .3dm (exit 0), every part in both exchange files."""
    from fabricate.app.cli import main
    from fabricate.export.ifc import read_ifc
    from fabricate.export.rhino import read_3dm_parts
    from optimize.modelling import shapes

    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(6.0, 2.0, 3), 8), 0.02, seed=5)
    _write_rhino_mesh(tmp_path / "roof.3dm", [("canopy", 1, m.V, m.F), ("other", 0, m.V[:3], np.array([[0, 1, 2]]))])
    (tmp_path / "r.yaml").write_text(
        "input: {mesh: roof.3dm, layer: Glass, object: canopy}\nunits: m\noptimize: {target: conical}\n"
        "outputs: {stl: false, 3mf: false, svg: false, pictures: false, html: false}\n")
    code = main(["run", str(tmp_path / "r.yaml"), "--out", str(tmp_path / "out"), "-q"])
    out = tmp_path / "out" / "r"
    assert code == 0
    ids = {row["id"] for row in read_bom(out / "bom.csv")}
    assert (out / "outlines.dxf").exists() and set(read_ifc(out / "model.ifc")) == ids
    assert ids <= set(read_3dm_parts(out / "model.3dm"))
    (tmp_path / "bad.yaml").write_text("input: {mesh: roof.3dm, layer: Steel}\n")
    assert main(["run", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "out"), "-q"]) == 2


def _rigid_equal(A, B, tol):
    """Outlines ``A``, ``B (k, 2)`` equal up to where they are put on the sheet: same corners in order,
    up to a rotation by a multiple of 90 degrees, a translation and the starting corner."""
    for turn in range(4):
        R = np.linalg.matrix_power(np.array([[0.0, -1.0], [1.0, 0.0]]), turn)
        C = B @ R.T
        C = C - C.min(axis=0)
        for shift in range(len(A)):
            if np.abs(np.roll(A - A.min(axis=0), shift, axis=0) - C).max() <= tol:
                return True
    return False


def test_nc1_per_beam_reads_back_to_the_dxf_contour_and_the_bom(parts, bom, tmp_path):
    from fabricate.export import write_dxf
    from fabricate.export.dxf import read_outlines
    from fabricate.export.nc1_read import read_nc1

    facts = write_nc1(parts, tmp_path / "nc1", order="dome")
    write_dxf(parts, tmp_path / "outlines.dxf")
    outlines, _ = read_outlines(tmp_path / "outlines.dxf")
    rows = {row["id"]: row for row in bom if row["kind"] == "beam"}
    files = sorted((tmp_path / "nc1").glob("*.nc1"))
    assert facts["files"] == len(files) == len(rows)
    for path in files:
        nc = read_nc1(path)
        h, row = nc["header"], rows[path.stem]
        assert h["piece"] == path.stem and h["code"] == "B" and h["grade"] == "S355J2" and h["quantity"] == 1
        (face, pts), = nc["contours"]
        assert face == "v" and np.abs(pts[0] - pts[-1]).max() == 0  # closed
        assert _rigid_equal(pts[:-1], outlines[path.stem], 0.01), path.stem
        extent = np.sort(np.ptp(outlines[path.stem], axis=0))
        assert (h["height"], h["length"]) == pytest.approx(tuple(extent), abs=0.01)
        # the stock rectangle of the BOM also holds the bevel face
        assert h["height"] <= float(row["rect_h_mm"]) + 0.01 and h["length"] <= float(row["rect_w_mm"]) + 0.01
        assert h["web_thickness"] == pytest.approx(float(row["thickness_mm"]), abs=1e-3)
        assert h["weight_per_m"] * h["length"] * 1e-3 == pytest.approx(float(row["weight_kg"]), rel=1e-3)
        for key in ("web_start_cut", "web_end_cut", "flange_start_cut", "flange_end_cut"):
            assert -90.0 < h[key] < 90.0


def test_nc1_length_and_angles_equal_the_steel_cut_list(parts, tmp_path):
    """Every NC1 header against the steel cut list written from the same parts: grade, blank length
    and width, both end cuts (mitre in the plate plane, bevel across it)."""
    import csv

    from fabricate.export import write_steel_cut_list
    from fabricate.export.nc1_read import read_nc1

    write_nc1(parts, tmp_path / "nc1")
    write_steel_cut_list(parts, tmp_path / "steel.csv")
    rows = list(csv.DictReader(open(tmp_path / "steel.csv", newline="")))
    hubs = [r for r in rows if r["member"] == "hub"]                # the solid hubs: bars, no NC1 of their own
    assert len(hubs) == len(parts.nodes) and all(r["section"].startswith("solid hub RD ") for r in hubs)
    rows = [r for r in rows if r["id"][0] == "B"]
    assert len(rows) == len(parts.beams)

    def larger(text):
        values = [float(v) for v in text.split()]
        return max(values, key=abs)

    for row in rows:
        h = read_nc1(tmp_path / "nc1" / f"{row['id']}.nc1")["header"]
        assert h["grade"] == row["grade"] == parts.spec.steel_grade
        assert h["length"] == pytest.approx(float(row["blank_w_mm"]), abs=0.06)
        assert h["height"] == pytest.approx(float(row["blank_h_mm"]), abs=0.06)
        assert h["web_start_cut"] == pytest.approx(float(row["end_a_mitre_deg"]), abs=0.006)
        assert h["web_end_cut"] == pytest.approx(float(row["end_b_mitre_deg"]), abs=0.006)
        assert h["flange_start_cut"] == pytest.approx(larger(row["end_a_bevel_deg"]), abs=0.006)
        assert h["flange_end_cut"] == pytest.approx(larger(row["end_b_bevel_deg"]), abs=0.006)


@pytest.mark.parametrize("engine", ["direct", "occ"])
def test_step_ap242_reads_back_with_the_same_solids(small_parts, tmp_path, engine):
    from fabricate.export import write_step
    from fabricate.export.brep import solid_facts
    from fabricate.export.step_read import read_step

    path = tmp_path / "model.step"
    parts = small_parts
    facts = write_step(parts, path, schema="AP242", engine=engine)
    assert facts["schema"].startswith("AP242")
    head = path.read_text()[:3000]
    assert "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING" in head and "AUTOMOTIVE_DESIGN" not in head
    solids, _ = read_step(path)
    volumes = {p.id: p.volume_mm3 for p in parts}
    assert sorted(n for n, _ in solids) == sorted(volumes)
    for name, shape in solids:
        f = solid_facts(shape)
        assert f["valid"] and f["volume_mm3"] == pytest.approx(volumes[name], rel=1e-9)


def test_parts_gltf_has_one_node_per_part_named_by_id(parts, tmp_path):
    """Read with pygltflib (not the project's reader): names, and each node's volume in metres."""
    import pygltflib

    from fabricate.export import write_parts_gltf

    path = tmp_path / "parts.glb"
    facts = write_parts_gltf(parts, path)
    doc = pygltflib.GLTF2().load(str(path))
    blob = doc.binary_blob()
    assert [n.name for n in doc.nodes] == [p.id for p in parts] and facts["nodes"] == len(parts)
    for node in doc.nodes:
        prim = doc.meshes[node.mesh].primitives[0]
        acc = doc.accessors[prim.attributes.POSITION]
        view = doc.bufferViews[acc.bufferView]
        P = np.frombuffer(blob, np.float32, acc.count * 3, view.byteOffset).reshape(-1, 3).astype(float)
        acc = doc.accessors[prim.indices]
        view = doc.bufferViews[acc.bufferView]
        T = np.frombuffer(blob, np.uint32, acc.count, view.byteOffset).reshape(-1, 3)
        a, b, c = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
        volume_m3 = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
        assert volume_m3 * 1e9 == pytest.approx(parts.by_id[node.name].volume_mm3, rel=1e-4)


def test_exchange_checks_pass_on_good_files_and_fail_on_a_wrong_one(parts, bom, ifc_file, tmp_path):
    from fabricate.export.exchange_check import check_3dm, check_ifc, check_nc1

    assert check_ifc(ifc_file[0], bom)["pass"]
    write_3dm(parts, tmp_path / "model.3dm")
    write_nc1(parts, tmp_path / "nc1")
    assert check_3dm(tmp_path / "model.3dm", bom)["pass"] and check_nc1(tmp_path / "nc1", bom)["pass"]
    wrong = [dict(r) for r in bom]
    wrong[0]["volume_mm3"] = repr(float(wrong[0]["volume_mm3"]) * (1 + 1e-5))
    result = check_ifc(ifc_file[0], wrong)
    assert not result["pass"] and result["bad_volume"] == [wrong[0]["id"]]
    assert not check_3dm(tmp_path / "model.3dm", wrong)["pass"]
    (tmp_path / "nc1" / f"{parts.beams[0].id}.nc1").unlink()
    result = check_nc1(tmp_path / "nc1", bom)
    assert not result["pass"] and result["missing"] == [parts.beams[0].id]


def test_ifc_face_set_volumes_agree_with_the_geometry_kernel(ifc_file):
    """The run's check reads volumes from the parsed face sets; ifcopenshell's kernel agrees."""
    from fabricate.export.exchange_check import face_set_volumes
    from fabricate.export.ifc import read_ifc

    f = ifcopenshell.open(str(ifc_file[0]))
    fast = face_set_volumes(f)
    kernel = read_ifc(ifc_file[0])
    assert set(fast) == set(kernel)
    for pid, item in kernel.items():
        assert fast[pid] == pytest.approx(item["volume_mm3"], rel=1e-9)


def test_ifc_check_validates_the_faces_it_leaves_out_of_ifcopenshell_validate(ifc_file, tmp_path):
    """ifcopenshell.validate runs on every instance but the IfcIndexedPolygonalFace s; their rules are
    checked by face_rule_errors: a face of two indices, an index past its points and a face no face set
    uses each fail the full IFC check, and the file as written passes it."""
    import re

    from fabricate.export.exchange_check import GEOMETRY, _without_faces, check_ifc, face_rule_errors

    path = ifc_file[0]
    f = ifcopenshell.open(str(path))
    faces = f.by_type("IfcIndexedPolygonalFace")
    rest = list(_without_faces(f))
    geometry = [x for t in GEOMETRY for x in f.by_type(t) if x.is_a() == t]
    assert faces and len(rest) == len(list(f)) - len(geometry) and not any(x.is_a() in GEOMETRY for x in rest)
    assert face_rule_errors(f) == []
    bom = [{"id": x.Name, "volume_mm3": "1", "kind": "panel"} for x in f.by_type("IfcElement")
           if not x.is_a("IfcCurtainWall")]
    assert check_ifc(path, bom, full=True)["bad_schema"] == []
    text = path.read_text()
    first = re.search(r"IFCINDEXEDPOLYGONALFACE\(\(([\d,]+)\)\)", text)
    two = ",".join(first.group(1).split(",")[:2])
    edits = {"two indices": text.replace(first.group(0), f"IFCINDEXEDPOLYGONALFACE(({two}))", 1),
             "past its points": text.replace(first.group(0), "IFCINDEXEDPOLYGONALFACE((1,2,99999))", 1),
             "used by no": text.replace("ENDSEC;\nEND-ISO", "#999999=IFCINDEXEDPOLYGONALFACE((1,2,3));\nENDSEC;\nEND-ISO", 1)}
    for what, broken in edits.items():
        assert broken != text, what
        bad = tmp_path / "bad.ifc"
        bad.write_text(broken)
        errors = check_ifc(bad, bom, full=True)["bad_schema"]
        assert errors, what
        if what != "two indices":   # ifcopenshell may refuse a too short list itself
            assert any(("used by no" in e) == (what == "used by no") for e in errors), (what, errors)


def test_ifc_check_holds_the_face_sets_and_point_lists_to_their_rules(ifc_file, tmp_path):
    """The face sets and point lists are left out of ifcopenshell.validate too; a point of two
    coordinates, a face set whose faces are not faces, one whose Closed is not a boolean: each fails the
    full IFC check, and ifcopenshell.validate over every instance says so too."""
    import re

    import ifcopenshell.validate

    from fabricate.export.exchange_check import check_ifc

    path = ifc_file[0]
    f = ifcopenshell.open(str(path))
    bom = [{"id": x.Name, "volume_mm3": "1", "kind": "panel"} for x in f.by_type("IfcElement")
           if not x.is_a("IfcCurtainWall")]
    text = path.read_text()
    point = re.search(r"IFCCARTESIANPOINTLIST3D\(\(\(([^,()]+),([^,()]+),([^,()]+)\)", text)
    face_set = re.search(r"IFCPOLYGONALFACESET\((#\d+),\.T\.,\((#\d+)", text)
    edits = {"lists of 3 reals": text.replace(point.group(0), point.group(0)[:-1].rsplit(",", 1)[0] + ")", 1),
             "Faces: expected": text.replace(face_set.group(0), face_set.group(0).replace(
                 face_set.group(2), face_set.group(1)), 1),
             "Closed": text.replace(face_set.group(0), face_set.group(0).replace(".T.", "'yes'"), 1)}
    for what, broken in edits.items():
        assert broken != text, what
        bad = tmp_path / "bad.ifc"
        bad.write_text(broken)
        errors = check_ifc(bad, bom, full=True)["bad_schema"]
        assert any(what in e for e in errors), (what, errors)
        log = ifcopenshell.validate.json_logger()
        ifcopenshell.validate.validate(ifcopenshell.open(str(bad)), log)
        assert log.statements, what     # the schema validator over every instance refuses it as well
