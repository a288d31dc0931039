"""The IFC file as a steel shop and a BIM tool read it (#34 items 4, 5): one IfcElementAssembly per
shipping piece welded from several solids (a beam of plates, a tube hub of tube and caps) aggregating
exactly them; the spatial structure down to a storey; the project's property set; every piece's length
the steel cut list's; the standard sections as material profile sets; the header; and the file check
failing on a broken assembly and on a length off the cut list."""
import csv

import numpy as np
import pytest
from cad_fixtures import dome_structure

import ifcopenshell  # noqa: E402 - a declared dependency: missing, the test fails
import ifcopenshell.util.element as eu  # noqa: E402

from fabricate.export import write_bom, write_ifc, write_steel_cut_list
from fabricate.export.bom import read_bom
from fabricate.export.exchange_check import check_ifc
from fabricate.export.ifc import PSET, VIEW

TUBE_HUB = {"connection": "hub", "hub": "tube", "radius_mm": 110.0, "wall_mm": 10.0, "cap_mm": 15.0}
SECTIONS = {
    "rhs": {"section": "rhs", "web_mm": 5.0, "flange_mm": 6.0, "flange_width_mm": 100.0},
    "tee": {"section": "tee", "web_mm": 8.0, "flange_mm": 10.0, "flange_width_mm": 120.0},
    "i": {"section": "i", "web_mm": 8.0, "flange_mm": 10.0, "flange_width_mm": 120.0},
}
PROFILE = {"rhs": "IfcRectangleHollowProfileDef", "tee": "IfcTShapeProfileDef", "i": "IfcIShapeProfileDef"}


def _parts(section: str):
    from fabricate.cad import PartSpec, build_parts

    return build_parts(dome_structure(n_around=4, k=2),
                       PartSpec(beam_width=80.0, beam=SECTIONS[section], node=TUBE_HUB))


@pytest.fixture(scope="module")
def rhs(tmp_path_factory):
    """An RHS dome with tube hubs, its IFC file, BOM and steel cut list in one folder."""
    parts = _parts("rhs")
    folder = tmp_path_factory.mktemp("rhs")
    write_ifc(parts, folder / "model.ifc", author="A. Engineer", organization="Steel & Glass")
    write_bom(parts, folder / "bom.csv")
    write_steel_cut_list(parts, folder / "steel_cut_list.csv")
    return parts, folder


def _cut_list(folder) -> dict[str, dict]:
    with open(folder / "steel_cut_list.csv", newline="") as fh:
        return {r["id"]: r for r in csv.DictReader(fh)}


def test_one_assembly_per_shipping_piece_in_the_storey(rhs):
    parts, folder = rhs
    f = ifcopenshell.open(str(folder / "model.ifc"))
    project, = f.by_type("IfcProject")
    storey, = f.by_type("IfcBuildingStorey")
    assert [eu.get_aggregate(x).is_a() for x in (storey, eu.get_aggregate(storey), f.by_type("IfcSite")[0])] == \
        ["IfcBuilding", "IfcSite", "IfcProject"]
    wall, = f.by_type("IfcCurtainWall")
    assert eu.get_container(wall) == storey
    solids: dict[str, list] = {}
    for g in parts.of_kind("beam") + parts.of_kind("node"):
        for pid, member in zip(g.ids, [g.member] * len(g)):
            solids.setdefault(pid.split(".")[0], []).append((pid, member))
    assemblies = {a.Name: a for a in f.by_type("IfcElementAssembly")}
    assert set(assemblies) == set(solids) and all(len(v) > 1 for v in solids.values())
    for uid, a in assemblies.items():
        assert a.AssemblyPlace == "FACTORY" and a.Tag == uid and a.Representation is None
        assert a.PredefinedType == ("GIRDER" if uid[0] == "B" else "USERDEFINED")
        assert eu.get_aggregate(a) == wall                                  # in the spatial structure
        pieces = {p.Name: p for p in eu.get_decomposition(a)}
        assert sorted(pieces) == sorted(pid for pid, _ in solids[uid])
        for pid, member in solids[uid]:
            piece = pieces[pid]
            assert eu.get_aggregate(piece) == a and piece.Representation is not None
            assert piece.ObjectPlacement.PlacementRelTo == a.ObjectPlacement
            assert piece.is_a() == ("IfcMember" if member == "tube" else "IfcPlate")
            assert eu.get_psets(piece)[PSET]["assembly"] == uid
    every = [e for e in f.by_type("IfcElement") if not e.is_a("IfcCurtainWall")]
    for e in every:   # every element reaches the storey through the wall, in exactly one whole
        assert len(e.Decomposes) == 1 and not e.ContainedInStructure
        whole = e
        while not whole.is_a("IfcCurtainWall"):
            whole = eu.get_aggregate(whole)
    glass_units = {p.id.split(".")[0] for p in parts.panels}
    steel = sum(len(v) for v in solids.values())
    assert len(every) == len({e.Name for e in every}) == len(glass_units) + len(solids) + steel


def test_the_ifc_lengths_are_the_cut_lists(rhs):
    """Read back with ifcopenshell: every cut list row's element carries the row's length_mm (the
    assembly's, its plates', the hub's height, its tube's and caps') as its Length quantity (a member or
    an assembly) and in the project's property set with the cut list's system_length_mm."""
    parts, folder = rhs
    f = ifcopenshell.open(str(folder / "model.ifc"))
    by_name = {e.Name: e for e in f.by_type("IfcElement")}
    rows = _cut_list(folder)
    assert {pid for pid in rows if pid[0] == "B"} == {pid for pid in by_name if pid[0] == "B"}
    for pid, row in rows.items():
        psets = eu.get_psets(by_name[pid])
        fab = psets[PSET]
        assert fab["part_id"] == pid and fab["type"] == row["type"] and fab["assembly"] == row["assembly"]
        assert fab["grade"] == row["grade"] == "S355J2"
        assert f"{fab['length_mm']:.1f}" == row["length_mm"], pid
        if row["system_length_mm"]:
            assert f"{fab['system_length_mm']:.1f}" == row["system_length_mm"], pid
        quantity = [q["Length"] for name, q in psets.items() if name != PSET and "Length" in q]
        assert quantity == ([] if by_name[pid].is_a("IfcPlate") else [fab["length_mm"]]), pid
    beam = by_name["B0001"]
    length, system = eu.get_psets(beam)[PSET]["length_mm"], eu.get_psets(beam)[PSET]["system_length_mm"]
    assert length < system                      # plates cut short of the node axes at the hubs
    assert rows["B0001"]["section"] == eu.get_psets(beam)[PSET]["section"] == "RHS 200x100x5/6"


@pytest.mark.parametrize("section", ["rhs", "tee", "i"])
def test_the_sections_are_material_profile_sets(section, rhs, tmp_path):
    if section == "rhs":
        parts, path = rhs[0], rhs[1] / "model.ifc"
    else:
        parts, path = _parts(section), tmp_path / "model.ifc"
        write_ifc(parts, path)
    f = ifcopenshell.open(str(path))
    s = SECTIONS[section]
    depth = float(abs(np.diff(parts.report["layers_mm"])[0]))
    beam = next(a for a in f.by_type("IfcElementAssembly") if a.Name == "B0001")
    profiles = eu.get_material(beam)
    assert profiles.is_a("IfcMaterialProfileSet")
    mp, = profiles.MaterialProfiles
    p = mp.Profile
    assert p.is_a() == PROFILE[section] and mp.Material.Name == "S355J2" and p.ProfileType == "AREA"
    if section == "rhs":
        assert (p.XDim, p.YDim, p.WallThickness) == (s["flange_width_mm"], depth, s["web_mm"])
    elif section == "tee":
        assert (p.Depth, p.FlangeWidth, p.WebThickness, p.FlangeThickness) == \
            (depth, s["flange_width_mm"], s["web_mm"], s["flange_mm"])
    else:
        assert (p.OverallDepth, p.OverallWidth, p.WebThickness, p.FlangeThickness) == \
            (depth, s["flange_width_mm"], s["web_mm"], s["flange_mm"])
    tube = next(m for m in f.by_type("IfcMember") if m.Name == "N0001.1")
    chs = eu.get_material(tube).MaterialProfiles[0].Profile
    assert chs.is_a("IfcCircleHollowProfileDef") and (chs.Radius, chs.WallThickness) == (110.0, 10.0)
    assert all(eu.get_material(p).is_a("IfcMaterial") for p in f.by_type("IfcPlate") if p.PredefinedType == "SHEET")
    for piece in eu.get_decomposition(beam):          # the geometry stays the exact faceted solids
        item, = piece.Representation.Representations[0].Items
        assert item.is_a("IfcPolygonalFaceSet")


def test_the_header_names_the_view_and_the_writer(rhs):
    from fabricate import __version__

    f = ifcopenshell.open(str(rhs[1] / "model.ifc"))
    assert f.header.file_description.description == (VIEW,) == ("ViewDefinition [ReferenceView_V1.2]",)
    fn = f.header.file_name
    assert fn.name == "model.ifc" and fn.author == ("A. Engineer",) and fn.organization == ("Steel & Glass",)
    assert fn.preprocessor_version == f"conical-fab {__version__}"
    assert fn.originating_system.startswith(f"conical-fab {__version__}") and fn.authorization == "none"


def test_the_file_check_holds_the_assemblies_and_the_lengths(rhs, tmp_path):
    parts, folder = rhs
    bom = read_bom(folder / "bom.csv")
    good = check_ifc(folder / "model.ifc", bom, full=False)
    assert good["pass"] and good["bad_assembly"] == [] and good["bad_length"] == [], good
    units = {pid.split(".")[0] for g in parts.groups if g.kind != "panel" for pid in g.ids}
    assert good["lengths_from"] == "steel_cut_list.csv" and good["assemblies"] == len(units)
    text = (folder / "model.ifc").read_text()
    # one plate of B0001 out of its assembly: the aggregation of B0001 loses its first part
    a_id = next(line.split("=")[0] for line in text.splitlines() if "IFCELEMENTASSEMBLY(" in line and "'B0001'" in line)
    rel = next(line for line in text.splitlines() if line.startswith("#") and "IFCRELAGGREGATES(" in line
               and f",{a_id},(" in line)
    head, kids = rel.rsplit(",(", 1)
    dropped = head + ",(" + kids.split(",", 1)[1]
    (tmp_path / "model.ifc").write_text(text.replace(rel, dropped))
    rows = _cut_list(folder)
    with open(tmp_path / "steel_cut_list.csv", "w", newline="") as fh:   # one beam 0.1 mm longer in the cut list
        w = csv.DictWriter(fh, fieldnames=list(next(iter(rows.values()))))
        w.writeheader()
        for pid, row in rows.items():
            w.writerow(dict(row, length_mm=f"{float(row['length_mm']) + 0.1:.1f}") if pid == "B0002" else row)
    bad = check_ifc(tmp_path / "model.ifc", bom, full=False)
    assert not bad["pass"]
    assert any(e.startswith("B0001:") for e in bad["bad_assembly"]) and \
        any(e.startswith("B0001.1: in 0 assemblies") for e in bad["bad_assembly"]), bad["bad_assembly"]
    assert [e.split(":")[0] for e in bad["bad_length"]] == ["B0002", "B0002"], bad["bad_length"]


def test_one_beam_one_length_in_the_ifc_the_cut_list_and_the_nc1(rhs, tmp_path):
    """Every plate's NC1 length is its IFC length_mm (and the cut list's, above): one length per piece."""
    from fabricate.export.nc1 import write_nc1
    from fabricate.export.nc1_read import read_nc1

    parts, folder = rhs
    write_nc1(parts, tmp_path / "nc1")
    f = ifcopenshell.open(str(folder / "model.ifc"))
    plates = {e.Name: eu.get_psets(e)[PSET]["length_mm"] for e in f.by_type("IfcPlate") if e.Name[0] == "B"}
    nc1 = {p.stem: read_nc1(p)["header"]["length"] for p in (tmp_path / "nc1").glob("B*.nc1")}
    assert set(nc1) == set(plates) and len(nc1) == 6 * len({k.split(".")[0] for k in nc1})
    for pid, length in plates.items():
        assert nc1[pid] == pytest.approx(length, abs=0.05), pid
    beam = next(a for a in f.by_type("IfcElementAssembly") if a.Name == "B0001")
    length = eu.get_psets(beam)[PSET]["length_mm"]              # end cut to end cut of the whole as welded
    assert f"{length:.1f}" == _cut_list(folder)["B0001"]["length_mm"]
    assert all(length >= v - 1e-9 for k, v in plates.items() if k.startswith("B0001."))
