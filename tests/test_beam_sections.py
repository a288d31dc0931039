"""Beam sections welded from plates (parts.beam): geometry, volumes, schedules, structure, config errors."""
import csv
import functools

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.beams import beam_planes
from fabricate.cad.sections import MEMBERS, section_rectangles
from fabricate.export.meshes import group_triangles, manifold_of
from fabricate.offset import offset_structure
from optimize.modelling import shapes
from optimize.errors import ConfigError

SECTIONS = {"tee": dict(section="tee", web_mm=10, flange_mm=12, flange_width_mm=140),
            "i": dict(section="i", web_mm=10, flange_mm=12, flange_width_mm=140),
            "rhs": dict(section="rhs", web_mm=6, flange_mm=8, flange_width_mm=120)}
CONNECTIONS = {"mitre": dict(connection="mitre"), "hub": dict(connection="hub", radius_mm=90, wall_mm=8, cap_mm=12),
               "none": dict(connection="none", gap_mm=25)}


@functools.lru_cache(maxsize=None)
def built(section: str, connection: str, structure: str = "dome"):
    s = dome_structure(n_around=6, k=3) if structure == "dome" else _grid()
    return build_parts(s, PartSpec(beam=SECTIONS[section], node=CONNECTIONS[connection]))


@functools.lru_cache(maxsize=None)
def _grid():
    return offset_structure(shapes.grid(4, 3, size=(4000.0, 3000.0)), (0.0, -200.0))


def _overlap(groups) -> tuple[float, float]:
    """(sum of the solids' volumes, the volume they share): manifold3d intersection of every pair of
    solids whose bounding boxes meet (touching solids share faces, which a union of all would smear)."""
    ms, total = [], 0.0
    for g in groups:
        X, T = group_triangles(g, np.zeros(3))
        ms += [manifold_of(X[i:i + 1], T) for i in range(len(g))]
        total += float(g.volume_mm3.sum())
    box = np.array([m.bounding_box() for m in ms])            # (s, 6) min xyz, max xyz
    lo, hi = box[:, :3] - 1e-6, box[:, 3:] + 1e-6
    meet = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
    i, j = np.nonzero(np.triu(meet, 1))
    shared = sum((ms[a] ^ ms[b]).volume() for a, b in zip(i.tolist(), j.tolist()))
    return total, shared


@pytest.mark.parametrize("connection", sorted(CONNECTIONS))
@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_plates_of_every_beam_their_neighbours_hubs_and_glass_do_not_overlap(section, connection):
    parts = built(section, connection)
    beams = parts.of_kind("beam")
    assert [g.member for g in beams] == list(MEMBERS[section])
    assert beams[0].ids[0] == "B0001.1" and all(len(g) == len(beams[0]) for g in beams)
    total, shared = _overlap(parts.groups)
    assert shared < 1e-9 * total + 1e-3, (section, connection, shared)


def test_the_overlap_measure_sees_an_overlap():
    g = built("tee", "mitre").of_kind("beam")[0]
    import dataclasses

    moved = dataclasses.replace(g, ids=tuple(i + "x" for i in g.ids), vertices=g.vertices + [0.0, 0.0, 5.0])
    total, shared = _overlap([g, moved])
    assert shared > 0.01 * g.volume_mm3.sum()


@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_webs_lie_in_the_beam_plane_and_flange_tops_in_the_panel_planes(section):
    parts = built(section, "mitre")
    bp = beam_planes(dome_structure(n_around=6, k=3))
    n, off = bp["normal"], bp["offset"]
    groups = {g.member: g for g in parts.of_kind("beam")}
    if section == "rhs":  # two webs parallel to the beam plane, symmetric about it
        for s, sign in (("+", 1), ("-", -1)):
            g = groups["web " + s]
            np.testing.assert_allclose(g.normals[:, 0], sign * n, atol=1e-12)
            h = np.einsum("pvi,pi->pv", g.vertices[:, :4], n) - off[:, None]
            np.testing.assert_allclose(h, sign * 60.0, atol=1e-9)
    else:
        g = groups["web"]
        np.testing.assert_allclose(g.normals[:, 0], n, atol=1e-12)      # F+ and F- are the beam plane +- web / 2
        np.testing.assert_allclose(g.normals[:, 1], -n, atol=1e-12)
        h = np.einsum("pvi,pi->pv", g.vertices[:, 4:8], n) - off[:, None]
        np.testing.assert_allclose(h, 5.0, atol=1e-9)
    assert bp["planarity_mm"].max() < 1e-9                               # torsion-free: the quads are planar
    panels = {p.id: p for p in parts.panels}
    for s in "+-":
        g = groups["top flange " + s]
        for i in range(len(g)):
            pid = [q for q in g.neighbours[i] if q[0] == "P"]
            assert len(pid) <= 1
            if not pid:
                continue
            p = panels[pid[0]]
            bearing = p.vertices[list(p.group.faces[p.group.outline_face])]
            m = g.normals[i, 0]
            d = bearing @ m - g.vertices[i, 0] @ m                     # the panel's face in the flange's top plane
            assert np.abs(d).max() < 1e-6
            assert abs(abs(p.normals[p.group.outline_face] @ m) - 1) < 1e-12


def _centroid_length(g, i, y, z, end_faces, n, origin, up):
    """Length of the line ``origin + y n + z up + s t`` between the plate's two end planes (mm)."""
    C = g.centre_line[i]
    t = (C[1] - C[0]) / np.linalg.norm(C[1] - C[0])
    p = origin + y * n + z * up
    s = []
    for f in end_faces:
        nu = g.normals[i, f]
        o = nu @ g.vertices[i, g.faces[f][0]]
        s.append((o - nu @ p) / (nu @ t))
    return abs(s[1] - s[0])


@pytest.mark.parametrize("connection", ["mitre", "none"])
@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_volumes_are_section_area_times_length_of_the_plate_centroid_lines(section, connection):
    """A flat grid (every dihedral 180 deg): each plate is a prism of its nominal rectangle cut by its end
    planes, so its volume is the rectangle's area times the length of its centroid line (mitred ends
    included); with square ends the beam's volume is the section area times its length."""
    parts = built(section, connection, "grid")
    spec = parts.spec
    rects = section_rectangles(spec, 200.0)
    bp = beam_planes(_grid())
    up = np.array([0.0, 0.0, -1.0])   # z from the glass down into the beam
    area = sum((y1 - y0) * (z1 - z0) for y0, y1, z0, z1 in rects)
    total = np.zeros(len(bp["normal"]))
    for g, (y0, y1, z0, z1) in zip(parts.of_kind("beam"), rects):
        for i in range(len(g)):
            n, origin = bp["normal"][i], g.centre_line[i, 0]
            if len(g.faces) == 10:  # the plate web: its + and - halves end in their own planes
                halves = [(y1 / 2, (0.0, y1), (6, 8)), (y0 / 2, (y0, 0.0), (7, 9))]
                expected = sum((hi - lo) * (z1 - z0) * _centroid_length(g, i, yc, (z0 + z1) / 2, f, n, origin, up)
                               for yc, (lo, hi), f in halves)
            else:
                expected = (y1 - y0) * (z1 - z0) * _centroid_length(g, i, (y0 + y1) / 2, (z0 + z1) / 2, (5, 4),
                                                                    n, origin, up)
            assert g.volume_mm3[i] == pytest.approx(expected, rel=1e-9)
        total[g.element] += g.volume_mm3
    if connection == "none":
        C = parts.of_kind("beam")[0].centre_line
        length = np.linalg.norm(C[:, 1] - C[:, 0], axis=1)
        np.testing.assert_allclose(total, area * length, rtol=1e-9)


@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_steel_cut_list_one_row_per_beam_then_its_plates(section, tmp_path):
    from fabricate.export import write_steel_cut_list

    parts = built(section, "hub")
    write_steel_cut_list(parts, tmp_path / "steel.csv")
    with open(tmp_path / "steel.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    hubs = [r for r in rows if r["id"][0] == "N"]                # after the beams: the hubs and their pieces
    n_nodes, pieces = parts.mesh.n_vertices, sum(len(g) for g in parts.of_kind("node"))
    assert rows[-len(hubs):] == hubs and len(hubs) == n_nodes + (pieces if pieces > n_nodes else 0)
    rows = rows[:-len(hubs)]
    members = MEMBERS[section]
    units = [r for r in rows if r["member"] == "beam"]
    n_beams = len(parts.of_kind("beam")[0])
    assert len(units) == n_beams and len(rows) == n_beams * (1 + len(members))
    text = {"tee": "T 200x140x10/12", "i": "I 200x140x10/12", "rhs": "RHS 200x120x6/8"}[section]
    by_id = parts.by_id
    for r in units:
        assert r["section"] == text and int(r["plates"]) == len(members)
        plates = [q for q in rows if q["id"].startswith(r["id"] + ".")]
        assert [q["member"] for q in plates] == list(members)
        mass = sum(by_id[q["id"]].volume_mm3 for q in plates) * 7850e-9
        assert float(r["weight_kg"]) == pytest.approx(mass, abs=0.01)
        assert sum(float(q["weight_kg"]) for q in plates) == pytest.approx(mass, abs=0.01 * len(plates))
        for q in plates:
            assert q["section"] == f"PL{by_id[q['id']].thickness_mm:g}"
            assert float(q["blank_w_mm"]) >= float(q["length_mm"]) - 0.05


@pytest.mark.parametrize("section", sorted(SECTIONS))
def test_masses_per_metre_are_the_section_area(section):
    """Square ends on a flat grid: steel mass per metre of beam = section area x density."""
    from fabricate.structure.sections import built_section

    parts = built(section, "none", "grid")
    sec = built_section(parts.spec, 200.0)
    C = parts.of_kind("beam")[0].centre_line
    length = np.linalg.norm(C[:, 1] - C[:, 0], axis=1).sum()
    mass = sum(g.volume_mm3.sum() for g in parts.of_kind("beam")) * 7850e-9
    assert mass == pytest.approx(sec.mass_per_m() * length * 1e-3, rel=1e-9)


def test_built_section_properties_equal_the_closed_forms():
    from fabricate.structure.sections import built_section, i_section, rhs, tee

    for shape, ref in (("rhs", rhs(200, 100, 8)), ("tee", tee(200, 120, 10, 12)), ("i", i_section(200, 120, 10, 12))):
        dims = dict(section=shape, web_mm=ref.tw, flange_mm=ref.tf, flange_width_mm=ref.b)
        sec = built_section(PartSpec(beam=dims), 200.0)
        for key in ("A", "Iy", "Iz", "centroid"):
            assert getattr(sec, key) == pytest.approx(getattr(ref, key), rel=1e-12), (shape, key)
        assert sec.J == pytest.approx(ref.J, rel=0.05)   # thin-walled: plates vs the rolled-shape series


def test_structure_check_uses_the_built_section():
    from fabricate.structure.options import StructureOptions
    from fabricate.structure.check import configured_section

    structure = dome_structure(n_around=6, k=3)
    spec = PartSpec(beam=SECTIONS["rhs"])
    sec = configured_section(StructureOptions(), spec, structure)
    assert sec.shape == "rhs" and sec.name == "rhs 200x120x6x8"
    assert sec.A == pytest.approx(2 * 6 * (200 - 16) + 2 * 8 * 120)
    plate = configured_section(StructureOptions(), PartSpec(), structure)
    assert plate.name == "plate 60x200"


@pytest.mark.parametrize("beam, node, words", [
    ({"section": "box"}, {}, ["parts.beam.section", "'box'", "plate, rhs, tee, i"]),
    ({"section": "tee", "web_mm": 20, "flange_width_mm": 15}, {}, ["parts.beam.flange_width_mm", "15", "web"]),
    ({"section": "rhs", "web_mm": 10, "flange_width_mm": 20}, {}, ["parts.beam.flange_width_mm", "two webs"]),
    ({"section": "i", "flange_mm": -1}, {}, ["parts.beam.flange_mm", "-1"]),
    ({}, {"connection": "hub", "radius_mm": 50, "wall_mm": 60}, ["parts.node.wall_mm", "60", "50"]),
    ({}, {"connection": "weld"}, ["parts.node.connection", "'weld'", "hub, mitre, none"]),
])
def test_bad_sections_and_connections_name_the_key_and_value(beam, node, words):
    with pytest.raises(ConfigError) as err:
        PartSpec(beam=beam, node=node)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_config_file_errors_name_the_line(tmp_path):
    from fabricate.app.config import load_config

    path = tmp_path / "job.yaml"
    path.write_text("name: job\ninput: {shape: {name: dome}}\nparts:\n  beam:\n    section: tee\n"
                    "    web_mm: 30\n    flange_width_mm: 20\n")
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert "job.yaml:" in str(err.value) and "parts.beam.flange_width_mm" in str(err.value)
    path.write_text("name: job\ninput: {shape: {name: dome}}\nparts:\n  joint_gap: 10\n  beam:\n    section: tee\n"
                    "    flange_width_mm: 8\n    web_mm: 4\n")
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert "parts.beam.flange_width_mm" in str(err.value) and "joint_gap" in str(err.value)
