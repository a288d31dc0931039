"""Node connections (parts.node): tube hubs with cap plates, solid hubs, mitres, square ends; their files."""
import csv
import functools
import json

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export.meshes import group_triangles, manifold_of

TUBE = dict(connection="hub", hub="tube", radius_mm=90.0, wall_mm=8.0, cap_mm=12.0)


@functools.lru_cache(maxsize=None)
def built(node: tuple, section: str = "plate"):
    beam = {"plate": {}, "rhs": dict(section="rhs", web_mm=6, flange_mm=8, flange_width_mm=120)}[section]
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node=dict(node), beam=beam))


def _ngon_area(r, k):
    return 0.5 * k * r * r * np.sin(2 * np.pi / k)


def test_tube_hub_is_a_tube_and_two_caps_of_the_right_volume():
    parts = built(tuple(TUBE.items()))
    nodes = {g.member: g for g in parts.of_kind("node")}
    assert list(nodes) == ["tube", "top cap", "bottom cap"]
    assert nodes["tube"].ids[:2] == ("N0001.1", "N0002.1") and nodes["top cap"].ids[0] == "N0001.2"
    k, r, wall, cap = 24, 90.0, 8.0, 12.0
    r_in = r - wall / np.cos(np.pi / k)
    np.testing.assert_allclose(nodes["tube"].volume_mm3,
                               (_ngon_area(r, k) - _ngon_area(r_in, k)) * nodes["tube"].length_mm, rtol=1e-9)
    for name in ("top cap", "bottom cap"):
        np.testing.assert_allclose(nodes[name].volume_mm3, _ngon_area(r, k) * cap, rtol=1e-9)
    # the hub's height comes from the layers: tube + caps = the solid hub between the recessed caps
    solid = built((("connection", "hub"), ("hub", "solid"), ("radius_mm", 90.0)))
    s = solid.of_kind("node")[0]
    assert s.member == "" and s.ids[0] == "N0001"
    np.testing.assert_allclose(nodes["tube"].length_mm + 2 * cap, s.length_mm, rtol=1e-12)
    assert s.length_mm.max() < 200.0                                    # recessed inside the 200 mm layers


def test_tube_is_one_closed_surface_with_one_hole_and_its_brep_has_annular_ends():
    from fabricate.export.brep import group_solids, solid_facts

    g = built(tuple(TUBE.items())).of_kind("node")[0]
    X, T = group_triangles(g, np.zeros(3))
    m = manifold_of(X[:1], T)
    assert m.status().name == "NoError" and m.genus() == 1
    solids = group_solids(g)[:3]
    for i, shape in enumerate(solids):   # built by build123d: outside + inside + one annulus per end
        f = solid_facts(shape)
        assert f["valid"] and f["faces"] == 2 * 24 + 2
        assert f["volume_mm3"] == pytest.approx(g.volume_mm3[i], rel=1e-9)


def test_beams_stop_at_the_hub_and_do_not_enter_it():
    parts = built(tuple(TUBE.items()), "rhs")
    beams = parts.of_kind("beam")
    hubs = parts.of_kind("node")
    ms_h = []
    for g in hubs:
        X, T = group_triangles(g, np.zeros(3))
        ms_h += [manifold_of(X[i:i + 1], T) for i in range(len(g))]
    worst = 0.0
    for g in beams:
        X, T = group_triangles(g, np.zeros(3))
        for i in range(len(g)):
            b = manifold_of(X[i:i + 1], T)
            for v in parts.mesh.topology.edges[g.element[i]].tolist():
                for h in (ms_h[v], ms_h[len(ms_h) // 3 + v], ms_h[2 * len(ms_h) // 3 + v]):
                    worst = max(worst, (b ^ h).volume())
    assert worst < 1e-6
    sb = parts.report["beams"]["end_setback_mm"]
    assert sb["min"] >= 90.0 and parts.report["beams"]["connection"] == "hub"


def test_mitre_none_and_the_old_node_radius():
    mitre = built((("connection", "mitre"),))
    assert not mitre.of_kind("node") and mitre.report["beams"]["end_setback_mm"]["max"] == 0.0
    none = built((("connection", "none"), ("gap_mm", 25.0)))
    assert not none.of_kind("node") and none.report["beams"]["end_setback_mm"]["min"] >= 25.0
    old = build_parts(dome_structure(n_around=6, k=3), PartSpec(node_radius=40.0))   # today's configs
    g = old.of_kind("node")
    assert len(g) == 1 and g[0].member == "" and old.spec.connection == "hub" and old.spec.hub_kind == "solid"


def test_node_schedule_lists_the_hub_per_node(tmp_path):
    from fabricate.export import write_node_schedule

    parts = built(tuple(TUBE.items()))
    write_node_schedule(parts, tmp_path / "nodes.csv")
    with open(tmp_path / "nodes.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    tube = {i: g for g in parts.of_kind("node") for i in [g.member]}["tube"]
    assert len(rows) == parts.mesh.n_vertices
    for r in rows:
        v = int(r["vertex"])
        assert float(r["hub_diameter_mm"]) == 180.0 and float(r["hub_wall_mm"]) == 8.0
        assert float(r["hub_height_mm"]) == pytest.approx(tube.length_mm[v] + 24.0, abs=0.06)
        assert r["hub"].startswith("tube 24-gon D180 x 8, caps 12")
    write_node_schedule(built((("connection", "mitre"),)), tmp_path / "mitre.csv")
    with open(tmp_path / "mitre.csv", newline="") as fh:
        assert all(r["hub"] == "none (mitred ends)" and r["hub_height_mm"] == "" for r in csv.DictReader(fh))


def test_to_build123d_labels_the_tube_parts():
    a = built(tuple(TUBE.items())).to_build123d(kinds=("node",))
    nodes = a.children[0]
    assert nodes.label == "nodes" and nodes.children[0].label == "N0001.1"
    assert len(nodes.children[0].faces()) == 50


def test_a_run_with_rhs_beams_and_tube_hubs_passes_its_checks(tmp_path):
    """The files of a small run: STEP reads back with every plate and hub id, the full check (STEP, 3MF,
    STL, IFC, flat data, NC1, bearing, clashes) passes, the cut files hold each plate thickness, the IFC
    has one member per beam and per hub."""
    from _pipeline_fixtures import tiny_config

    from fabricate.check import check_outputs
    from fabricate.app.pipeline import run_pipeline

    outputs = {"step": True, "stl": True, "3mf": True, "dxf": True, "svg": False, "bom": True, "pictures": False,
               "html": False, "ifc": True, "3dm": False, "nc1": True, "gltf": False, "check": "off"}
    cfg = tiny_config(tmp_path, "rhs_hubs", outputs=outputs,
                      parts={"beam": dict(section="rhs", web_mm=6, flange_mm=8, flange_width_mm=120),
                             "node": dict(TUBE)})
    run_pipeline(cfg, tmp_path / "out")
    out = tmp_path / "out" / "rhs_hubs"
    res = check_outputs(out)
    failed = {k: v.get("why") for k, v in res["checks"].items() if v.get("pass") is False}
    assert res["pass"], failed
    assert res["checks"]["flat"]["pass"] and res["checks"]["step"]["pass"] and res["checks"]["ifc"]["pass"]
    import ifcopenshell

    import ifcopenshell.util.element as eu

    f = ifcopenshell.open(str(out / "model.ifc"))
    assemblies = {e.Name: e for e in f.by_type("IfcElementAssembly")}          # one shop assembly per piece
    assert sorted(p.Name for p in eu.get_decomposition(assemblies["B0001"])) == [f"B0001.{k}" for k in range(1, 7)]
    assert sorted(p.Name for p in eu.get_decomposition(assemblies["N0001"])) == ["N0001.1", "N0001.2", "N0001.3"]
    tube = next(e for e in f.by_type("IfcMember") if e.Name == "N0001.1").Representation.Representations[0].Items[0]
    # the tube's annular ends: faces with a hole
    assert [x.is_a() for x in tube.Faces].count("IfcIndexedPolygonalFaceWithVoids") == 2 and len(tube.Faces) == 2 * 24 + 2
    from fabricate.export.step_text import read_step_text

    solids, _ = read_step_text(out / "model.step")
    assert {"B0001.1", "B0001.6", "N0001.1", "N0001.3"} <= set(solids)
    assert (out / "cut_steel_6mm.dxf").exists() and (out / "cut_steel_8mm.dxf").exists()
    assert len(list((out / "nc1").glob("B0001.*.nc1"))) == 6
    facts = json.loads((out / "report.json").read_text())
    assert facts["parts"]["cad_report"]["beams"]["section"] == "rhs"
    beams = facts["parts"]["beams"]
    assert beams["count"] == 6 * beams["units"] and facts["parts"]["nodes"]["count"] == 3 * facts["parts"]["nodes"]["units"]


def test_bom_thickness_of_a_hub_tube_is_its_wall(tmp_path):
    """A steel shop reads ``thickness_mm`` as the wall or plate: the tube row carries the wall (8), the caps
    their plate (12), a solid hub (a round bar) its diameter; the cut files group plates by that thickness
    and never take the tube (no 8 mm steel file from a T 10/12 beam on 8 mm tubes)."""
    from fabricate.app.config import NestingSection
    from fabricate.export import write_bom, write_cut_files
    from fabricate.export.bom import read_bom

    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec(
        beam={"section": "tee", "web_mm": 10, "flange_mm": 12, "flange_width_mm": 100}, node=dict(TUBE)))
    write_bom(parts, tmp_path / "bom.csv")
    rows = [r for r in read_bom(tmp_path / "bom.csv") if r["kind"] == "node"]
    by_member = {}
    for r in rows:
        by_member.setdefault(r["member"], set()).add(float(r["thickness_mm"]))
    assert by_member == {"tube": {8.0}, "top cap": {12.0}, "bottom cap": {12.0}}
    files = write_cut_files(parts, tmp_path, NestingSection().model_dump())
    assert sorted(f for f in files if f.startswith("cut_steel") and f.endswith(".dxf")) == [
        "cut_steel_10mm.dxf", "cut_steel_12mm.dxf"]
    solid = built((("connection", "hub"), ("hub", "solid"), ("radius_mm", 90.0)))
    write_bom(solid, tmp_path / "solid.csv")
    assert {float(r["thickness_mm"]) for r in read_bom(tmp_path / "solid.csv") if r["kind"] == "node"} == {180.0}


def test_nc1_per_hub_tube_reads_back_to_its_bom_row_and_the_check_holds_it(tmp_path):
    """One DSTV file per hub tube beside the beam plates' (``RO``: a round tube cut square to length),
    read back by the reader written apart from the writer: piece id, profile ``RO180x8``, diameter, wall,
    the length between the caps, the weight per metre of the BOM row; ``check_nc1`` expects beams and
    tubes and catches a wrong length, a plate code on a tube and a missing file."""
    from fabricate.export import write_bom
    from fabricate.export.bom import read_bom
    from fabricate.export.exchange_check import check_nc1
    from fabricate.export.nc1 import write_nc1
    from fabricate.export.nc1_read import HEADER, read_nc1

    parts = built(tuple(TUBE.items()))
    facts = write_nc1(parts, tmp_path / "nc1", order="dome")
    write_bom(parts, tmp_path / "bom.csv")
    bom = read_bom(tmp_path / "bom.csv")
    tubes = {r["id"]: r for r in bom if r["member"] == "tube"}
    tube = next(g for g in parts.of_kind("node") if g.member == "tube")
    n_beams = sum(len(g) for g in parts.of_kind("beam"))
    assert facts["tubes"] == len(tubes) == parts.mesh.n_vertices and facts["files"] == n_beams + len(tubes)
    k, r, wall = 24, 90.0, 8.0
    section = _ngon_area(r, k) - _ngon_area(r - wall / np.cos(np.pi / k), k)    # mm2, the model's 24-gon tube
    for i, pid in enumerate(tube.ids):
        nc = read_nc1(tmp_path / "nc1" / f"{pid}.nc1")
        h, row = nc["header"], tubes[pid]
        assert (h["piece"], h["code"], h["profile"], h["grade"], h["quantity"]) == (pid, "RO", "RO180x8", "S355J2", 1)
        assert h["height"] == pytest.approx(180.0, abs=1e-3)
        assert h["web_thickness"] == h["flange_thickness"] == float(row["thickness_mm"]) == wall
        assert h["length"] == pytest.approx(float(row["length_mm"]), abs=2e-3)
        assert h["length"] == pytest.approx(tube.length_mm[i], abs=1e-3)
        assert h["weight_per_m"] == pytest.approx(section * 1e-6 * 7850.0, rel=1e-5)     # kg/m, independent of L
        assert h["weight_per_m"] * h["length"] * 1e-3 == pytest.approx(float(row["weight_kg"]), rel=1e-3)
        assert [h[key] for key in HEADER[16:20]] == [0.0] * 4 and nc["contours"] == []   # square ends
    assert check_nc1(tmp_path / "nc1", bom)["pass"]
    first, second, third = sorted(tubes)[:3]
    path = tmp_path / "nc1" / f"{first}.nc1"
    lines = path.read_bytes().decode("ascii").split("\r\n")
    assert lines[2 + HEADER.index("length")].strip() == f"{float(tubes[first]['length_mm']):.3f}"
    lines[2 + HEADER.index("length")] = "  999.000"
    path.write_bytes("\r\n".join(lines).encode("ascii"))
    path = tmp_path / "nc1" / f"{second}.nc1"
    path.write_bytes(path.read_bytes().replace(b"\r\n  RO\r\n", b"\r\n  B\r\n", 1))
    (tmp_path / "nc1" / f"{third}.nc1").unlink()
    result = check_nc1(tmp_path / "nc1", bom)
    assert not result["pass"] and result["missing"] == [third]
    bad = dict(b.split(": ", 1) for b in result["bad_files"])
    assert set(bad) == {first, second} and "length 999" in bad[first] and "profile code 'B'" in bad[second]


def test_min_widths_of_regular_polygons_and_a_rectangle():
    from fabricate.cad.limits import min_widths

    r = 80.0
    for k, expected in ((24, 2 * r * np.cos(np.pi / 24)), (7, r * (1 + np.cos(np.pi / 7))), (6, 2 * r * np.cos(np.pi / 6))):
        phi = 2 * np.pi * np.arange(k) / k + 0.3
        Q = r * np.stack([np.cos(phi), np.sin(phi)], axis=1) + [500.0, -20.0]
        assert min_widths(Q[None])[0] == pytest.approx(expected, rel=1e-12)
    rect = np.array([[[0.0, 0.0], [100.0, 0.0], [100.0, 30.0], [0.0, 30.0]]])
    assert min_widths(rect)[0] == pytest.approx(30.0)


def test_shop_limits_flag_the_hub_cap_plates_by_hub_id(tmp_path):
    """A cap plate is held to the corner limit by its corners (165 deg for a 24-gon) and to the edge limit
    by its width across flats (178.5 mm for D180; its facets of 23.5 mm are a round plate's, not short
    edges): flagged by its hub's id in report limits, the headline and the hub row of the steel cut list."""
    from fabricate.export import write_steel_cut_list
    from fabricate.report.measures import warnings

    structure = dome_structure(n_around=6, k=3)
    hubs = {f"N{v + 1:04d}" for v in range(structure.mesh.n_vertices)}
    across = 180.0 * np.cos(np.pi / 24)
    loose = build_parts(structure, PartSpec(node=dict(TUBE), limits={
        "min_corner_deg": 164.0, "min_edge_mm": across - 0.1, "sheet_mm": (1e5, 1e5), "max_panel_kg": 1e6}))
    assert not any(i[0] == "N" for v in loose.report["limits"].values() for i in v["ids"])
    tight = build_parts(structure, PartSpec(node=dict(TUBE), limits={
        "min_corner_deg": 166.0, "min_edge_mm": across + 0.1, "sheet_mm": (1e5, 1e5), "max_panel_kg": 1e6}))
    lim = tight.report["limits"]
    for key in ("corner", "edge"):
        assert {i for i in lim[key]["ids"] if i[0] == "N"} == hubs
    assert not any(i[0] == "N" for key in ("sheet", "weight") for i in lim[key]["ids"])
    assert any("N0001" in w and "edge" in w for w in warnings({}, lim))
    write_steel_cut_list(tight, tmp_path / "steel.csv")
    with open(tmp_path / "steel.csv", newline="") as fh:
        rows = {r["id"]: r for r in csv.DictReader(fh)}
    for h in hubs:
        assert f"edge >= {across + 0.1:g} mm" in rows[h]["flags"] and "corner >= 166 deg" in rows[h]["flags"]
        assert rows[h + ".1"]["flags"] == ""                        # the tube is a section: not held to them


# -- hubs sized from the sharpest beam angle (#30 item 4) -------------------------------------------------
from fabricate.offset import offset_structure  # noqa: E402
def test_a_hub_without_a_radius_is_the_smallest_stock_tube_every_beam_end_meets():
    from cad_fixtures import dome_mesh
    from fabricate.cad.beams import angular_neighbours, beam_planes
    from fabricate.cad.build import span_positions
    from fabricate.cad.hubsize import CLEARANCE_MM, STOCK_CHS_MM, sharpest_gaps

    s = offset_structure(dome_mesh(8, 4, radius_m=4, rise_m=1.6), (0.0, -200.0))
    parts = build_parts(s, PartSpec(beam_width=60.0, node={"connection": "hub", "hub": "tube"}))
    r = parts.spec.hub_radius
    sizing = parts.report["nodes"]["sizing"]
    assert sizing["sized"] and 2 * r in STOCK_CHS_MM and r == sizing["radius_mm"]
    _, P0, _ = span_positions(s)
    normal = beam_planes(s)["normal"]
    gaps = angular_neighbours(s, P0, normal)["gap"]
    need = (30.0 + CLEARANCE_MM) / np.tan(np.minimum(gaps, np.pi) / 2)
    assert need.max() <= r < min(D for D in STOCK_CHS_MM if D / 2 >= need.max()) / 2 + 1e-9  # the smallest
    assert sizing["needed_radius_mm"] == pytest.approx(need.max())
    assert sharpest_gaps(s, P0, normal).min() == pytest.approx(gaps.min())
    assert parts.report["limits"]["hub"]["count"] == 0  # every beam end meets the hub
    nodes = [g for g in parts.of_kind("node")]
    assert nodes and all(g.ids[0].startswith("N") for g in nodes)


def test_a_hub_radius_given_below_what_the_angles_need_names_the_nodes_and_the_size():
    from cad_fixtures import dome_mesh

    s = offset_structure(dome_mesh(8, 4, radius_m=4, rise_m=1.6), (0.0, -200.0))
    parts = build_parts(s, PartSpec(beam_width=60.0, node={"connection": "hub", "hub": "tube", "radius_mm": 40.0,
                                                           "wall_mm": 5.0}))
    hub = parts.report["limits"]["hub"]
    assert parts.spec.hub_radius == 40.0 and hub["count"] > 0 and hub["worst_id"] in hub["ids"]
    assert f"the beam angles need up to {np.ceil(hub['worst']):.0f} mm" in hub["limit"]
    from fabricate.app.requirements import warnings

    line = next(w for w in warnings({}, parts.report["limits"]) if "hub limit" in w)
    assert hub["worst_id"] in line or hub["ids"][0] in line


def test_a_hub_no_stock_tube_can_clear_is_refused_naming_the_node_and_angle():
    from fabricate.cad.hubsize import size_hubs

    from cad_fixtures import dome_mesh
    from fabricate.cad.beams import beam_planes
    from fabricate.cad.build import span_positions
    from fabricate.cad.errors import PartError

    s = offset_structure(dome_mesh(8, 4, radius_m=4, rise_m=1.6), (0.0, -200.0))
    _, P0, _ = span_positions(s)
    spec = PartSpec(beam_width=60.0, beam={"section": "tee", "flange_width_mm": 1500.0, "web_mm": 10.0},
                    node={"connection": "hub", "hub": "tube"})
    with pytest.raises(PartError, match=r"node N\d{4}: two of its beams are [\d.]+ deg apart .* hub of radius \d+ mm"):
        size_hubs(s, spec, P0, beam_planes(s)["normal"])
