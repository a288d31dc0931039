"""Glass schedule, steel cut list, node schedule and shop limits: what the shops order from."""
import csv

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import write_bom, write_glass_schedule, write_node_schedule, write_steel_cut_list


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def parts():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec())


@pytest.fixture(scope="module")
def files(parts, tmp_path_factory):
    out = tmp_path_factory.mktemp("sched")
    for name, fn in (("glass.csv", write_glass_schedule), ("steel.csv", write_steel_cut_list),
                     ("nodes.csv", write_node_schedule), ("bom.csv", write_bom)):
        fn(parts, out / name)
    return {k: _rows(out / f"{k}.csv") for k in ("glass", "steel", "nodes", "bom")}


def test_glass_schedule_edges_corners_and_neighbours(parts, files):
    rows = {r["id"]: r for r in files["glass"]}
    assert sorted(rows) == sorted(p.id for p in parts.panels)
    for p in parts.panels:
        r = rows[p.id]
        edges = np.array(r["edge_lengths_mm"].split(), dtype=float)
        corners = np.array(r["corner_angles_deg"].split(), dtype=float)
        P = p.vertices[list(p.group.ring)]
        np.testing.assert_allclose(edges, np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1), atol=0.06)
        assert corners.sum() == pytest.approx(180.0 * (len(corners) - 2), abs=0.2)
        beams = r["beams"].split()
        assert sorted(beams) == sorted(n for n in p.neighbours if n[0] == "B")
        for b, across in zip(beams, r["neighbours"].split()):  # the panel across each edge shares its beam
            panels = [n for n in parts.by_id[b].neighbours if n[0] == "P"]
            assert across == ("-" if len(panels) == 1 else next(q for q in panels if q != p.id))
        assert float(r["weight_kg"]) == pytest.approx(p.volume_mm3 * 2500e-9, abs=0.06)
        assert float(r["warp_mm"]) < 1e-6  # the dome is PQ by construction


def test_steel_cut_list_lengths_fit_their_stock_and_dihedrals_are_the_panels(parts, files):
    mesh = parts.mesh
    from optimize.mesh.measures import face_normals

    N = face_normals(mesh)
    bom = {r["id"]: r for r in files["bom"]}
    for r in files["steel"]:
        b = parts.by_id[r["id"]]
        assert float(r["blank_w_mm"]) >= float(r["length_mm"]) - 0.05
        assert float(bom[r["id"]]["rect_w_mm"]) >= float(bom[r["id"]]["length_mm"]) - 1e-3  # the BOM defect
        panels = r["panels"].split()
        if len(panels) == 2:
            f1, f2 = (parts.by_id[q].element for q in panels)
            expected = 180.0 - np.degrees(np.arccos(np.clip(abs(N[f1] @ N[f2]), -1, 1)))
            assert float(r["dihedral_deg"]) == pytest.approx(expected, abs=0.01)
        else:
            assert r["dihedral_deg"] == ""
        assert r["grade"] == "S355J2" and r["section"].startswith("plate 60 x ")
        assert len(r["end_a_bevel_deg"].split()) == 2 and len(r["nodes"].split()) == 2
        del b


def test_node_schedule_lists_every_beam_once_per_end(parts, files):
    rows = files["nodes"]
    assert len(rows) == parts.mesh.n_vertices
    assert sum(int(r["valence"]) for r in rows) == 2 * len(parts.beams)
    for r in rows:
        a = np.array([r["axis_x"], r["axis_y"], r["axis_z"]], dtype=float)
        assert np.linalg.norm(a) == pytest.approx(1.0, abs=1e-5)
        az = np.array(r["azimuth_deg"].split(), dtype=float)
        assert az[0] == 0.0 and np.all(np.diff(az) > 0) and len(az) == int(r["valence"])


def test_limits_flag_the_parts_that_break_them_by_id():
    structure = dome_structure(n_around=6, k=3)
    loose = build_parts(structure, PartSpec(limits={"min_corner_deg": 0.0, "min_edge_mm": 0.0,
                                                    "sheet_mm": (1e5, 1e5), "max_panel_kg": 1e6})).report["limits"]
    assert all(v["count"] == 0 for k, v in loose.items() if k != "overhead")  # monolithic overhead: no limit knob
    tight = build_parts(structure, PartSpec(limits={"min_corner_deg": 80.0, "min_edge_mm": 2000.0,
                                                    "sheet_mm": (2000.0, 1000.0), "max_panel_kg": 50.0}))
    lim = tight.report["limits"]
    from fabricate.cad.limits import corner_angles_deg, edge_lengths

    for g in tight.of_kind("panel"):
        low = [i for i, a in zip(g.ids, corner_angles_deg(g.bevel_ref).min(axis=1)) if a < 80.0]
        assert low and set(low) <= set(lim["corner"]["ids"])
        heavy = [i for i, v in zip(g.ids, g.volume_mm3) if v * 2500e-9 > 50.0]
        assert set(heavy) == set(lim["weight"]["ids"])
    short = [i for g in tight.groups if g.kind in ("panel", "beam")
             for i, e in zip(g.ids, edge_lengths(g.bevel_ref).min(axis=1)) if e < 2000.0]
    assert set(short) == set(lim["edge"]["ids"]) and lim["edge"]["worst"] < 2000.0
    assert lim["sheet"]["count"] > 0 and lim["sheet"]["limit"] == "within 2000 x 1000 mm"


def test_the_quickstart_hubs_are_in_the_steel_cut_list_as_chs_and_caps(tmp_path):
    """The quickstart config's parts (T beams, tube hubs D160 x 8 with 12 mm caps) on a small dome: one row
    per hub, its tube a CHS a shop can order (length = the tube between the caps; hub row: the height), its
    caps PL12 with their blank; every weight is the BOM's and the total holds beams, tubes and caps."""
    from pathlib import Path

    from fabricate.app.config import load_config
    from fabricate.app.stages import part_spec

    cfg = load_config(Path(__file__).resolve().parents[1] / "configs" / "quickstart.yaml")
    parts = build_parts(dome_structure(n_around=6, k=3), part_spec(cfg))
    facts = write_steel_cut_list(parts, tmp_path / "steel.csv")
    write_bom(parts, tmp_path / "bom.csv")
    rows = {r["id"]: r for r in _rows(tmp_path / "steel.csv")}
    bom = {r["id"]: r for r in _rows(tmp_path / "bom.csv")}
    n = parts.mesh.n_vertices
    assert facts["hubs"] == n and [r["member"] for r in rows.values()].count("hub") == n
    for v in range(n):
        nid = f"N{v + 1:04d}"
        hub, tube, top, bottom = rows[nid], rows[nid + ".1"], rows[nid + ".2"], rows[nid + ".3"]
        assert hub["section"] == "tube hub CHS 160 x 8 + 2 caps PL12 24-gon D160" and hub["plates"] == "3"
        assert tube["section"] == "CHS 160 x 8" and tube["member"] == "tube" and tube["grade"] == "S355J2"
        assert top["section"] == bottom["section"] == "PL12" and top["member"] == "top cap"
        assert float(tube["length_mm"]) == pytest.approx(float(bom[nid + ".1"]["length_mm"]), abs=0.05)
        assert float(hub["length_mm"]) == pytest.approx(float(tube["length_mm"]) + 24.0, abs=0.1)
        assert float(top["blank_w_mm"]) == pytest.approx(2 * 80 * np.cos(np.pi / 24), abs=0.1)  # 24-gon, flat to flat
        pieces = [float(bom[nid + s]["weight_kg"]) for s in (".1", ".2", ".3")]
        for r, w in zip((tube, top, bottom), pieces):
            assert float(r["weight_kg"]) == pytest.approx(w, abs=0.006)
        assert float(hub["weight_kg"]) == pytest.approx(sum(pieces), abs=0.01)
    # a round CHS 160 x 8 of that length would weigh pi (D - t) t L rho: the 24-gon is 1.1 % lighter
    L = float(rows["N0001.1"]["length_mm"])
    assert float(rows["N0001.1"]["weight_kg"]) == pytest.approx(np.pi * 152 * 8 * L * 7850e-9, rel=0.02)
    steel = sum(float(r["volume_mm3"]) for r in bom.values() if r["material"] == "steel") * 7850e-9
    w = facts["weight_kg"]
    assert w["total"] == pytest.approx(steel, rel=1e-6) and w["hubs"] > 0 and w["beams"] > w["hubs"]
    assert w["total"] == pytest.approx(w["beams"] + w["hubs"], abs=1e-3)


def test_the_glass_blank_holds_every_ply(tmp_path):
    """Issue 36: the unit's blank was its largest ply's (by area); on a flipped insulated dome the other
    plies are wider or taller than it by up to 0.58 mm, so a blank cut to the schedule was short."""
    from cad_fixtures import dome_structure

    glass = {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10}, "cavity_mm": 16,
             "inner": {"type": "laminated", "plies_mm": [6, 6], "interlayer_mm": 1.52}, "edge_seal_mm": 14}
    parts = build_parts(dome_structure(n_around=5, k=2, flip=True), PartSpec(glass=glass, edge="auto"))
    write_glass_schedule(parts, tmp_path / "glass.csv")
    rows = {r["id"]: r for r in _rows(tmp_path / "glass.csv")}
    short = 0
    for g in parts.of_kind("panel"):
        if g.material:
            continue
        for pid, (w, h) in zip(g.ids, g.rect):
            r = rows[pid.split(".")[0]]
            assert float(r["blank_w_mm"]) >= float(r["blank_h_mm"])
            short += float(r["blank_w_mm"]) < w - 0.05 or float(r["blank_h_mm"]) < h - 0.05
    assert short == 0


def test_every_schedule_names_the_type_of_its_parts(parts, files):
    """Issue 37: a type column in every schedule; the 6-fold dome has one glass
    shape per ring of faces, one node type per ring of vertices, one beam type per ring of edges."""
    mesh = parts.mesh
    n_around = 6
    glass = {r["id"]: r["type"] for r in files["glass"]}
    assert len(set(glass.values())) == mesh.n_faces // n_around
    nodes = {r["id"]: r["type"] for r in files["nodes"]}
    assert len(set(nodes.values())) == mesh.n_vertices // n_around
    beams = {r["id"]: r["type"] for r in files["steel"] if r["member"] in ("", "beam")}
    assert len(set(beams.values())) == len(mesh.topology.edges) // n_around
    # congruent by a rotation about the dome's axis: faces of one ring are one type
    ring = {}
    for r in files["glass"]:
        c = mesh.V[mesh.F[int(r["face"])]].mean(axis=0)
        ring.setdefault(round(float(c[2])), set()).add(r["type"])
    assert all(len(t) == 1 for t in ring.values())
