"""Exchange formats: IFC4 read back by ifcopenshell (schema + express rules, its own geometry kernel),
Rhino .3dm written and read back by rhino3dm, a .3dm quad mesh as input."""
import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import write_3dm, write_bom, write_ifc
from fabricate.export.bom import read_bom
from optimize.errors import MeshError
from optimize.io import read_mesh

ifcopenshell = pytest.importorskip("ifcopenshell", reason="ifcopenshell is a declared dependency")
rhino3dm = pytest.importorskip("rhino3dm", reason="rhino3dm is a declared dependency")


@pytest.fixture(scope="module")
def parts():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node_radius=40.0))


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


def test_ifc_is_valid_ifc4_with_the_express_rules(ifc_file):
    import ifcopenshell.validate

    path, facts = ifc_file
    assert facts["schema"] == "IFC4"
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

    f = ifcopenshell.open(str(ifc_file[0]))
    project, = f.by_type("IfcProject")
    site, = f.by_type("IfcSite")
    building, = f.by_type("IfcBuilding")
    wall, = f.by_type("IfcCurtainWall")
    assert eu.get_aggregate(site) == project and eu.get_aggregate(building) == site
    assert eu.get_container(wall) == building
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
    assert psets["Pset_ConicalFabFabrication"]["Planarity_mm"] == pytest.approx(panel.planarity_mm)
    beam = parts.beams[0]
    member = next(e for e in f.by_type("IfcMember") if e.Name == beam.id)
    assert member.PredefinedType == "MULLION" and eu.get_material(member).Name == "S355"
    q = eu.get_psets(member)
    assert q["Qto_MemberBaseQuantities"]["Length"] == pytest.approx(beam.length_mm)
    assert q["Pset_ConicalFabFabrication"]["Twist_mm"] == pytest.approx(beam.planarity_mm)


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
    from fabricate.cli import main
    from fabricate.export.ifc import read_ifc
    from fabricate.export.rhino import read_3dm_parts
    from optimize import shapes

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
