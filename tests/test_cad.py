"""CAD stage: panels, beams and nodes as data (geometry, volumes, contacts, invariance, errors)."""
import dataclasses

import numpy as np
import pytest
from cad_fixtures import dome_mesh, dome_structure, rigid
from scipy.spatial import ConvexHull

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.geometry import polygon_area_2d, volumes
from fabricate.export.verify import Solid, intersections
from fabricate.offset import offset_structure
from optimize.modelling import shapes
from fabricate.cad.errors import PartError
from optimize.errors import ConfigError, MeshError
from optimize.mesh.measures import face_areas


@pytest.fixture(scope="module")
def dome():
    return dome_structure()


@pytest.fixture(scope="module")
def parts(dome):
    return build_parts(dome, PartSpec())


def _solids(parts):
    return [Solid(p.id, p.vertices, np.array([(f[0], f[j], f[j + 1]) for f in p.faces
                                               for j in range(1, len(f) - 1)])) for p in parts]


def test_one_part_per_element_with_stable_ids(dome, parts):
    mesh = dome.mesh
    assert len(parts.panels) == mesh.n_faces and len(parts.beams) == len(mesh.topology.edges)
    assert parts.nodes == []
    assert parts.panels[0].id == "P0001" and parts.beams[-1].id == f"B{len(parts.beams):04d}"
    assert [p.element for p in parts.panels] == sorted(p.element for p in parts.panels)
    with_nodes = build_parts(dome, PartSpec(node_radius=40.0))
    assert len(with_nodes.nodes) == mesh.n_vertices
    assert [p.id for p in with_nodes.panels + with_nodes.beams] == [p.id for p in parts.panels + parts.beams]


def test_conical_mesh_gets_axis_edges_and_planar_sources(dome, parts):
    assert dome.is_conical and parts.edge_mode == "axis"
    assert parts.report["panels"]["planarity_mm_max"] < 1e-9
    assert parts.report["beams"]["planarity_mm_max"] < 1e-9
    assert max(g.residual_mm.max() for g in parts.groups) < 1e-8


def test_volumes_equal_convex_hull_for_convex_panels(parts):
    for p in parts.panels:
        hull = ConvexHull(p.vertices)
        assert p.volume_mm3 == pytest.approx(hull.volume, rel=1e-9)


def test_perpendicular_panel_without_gap_is_the_face_times_thickness(dome):
    spec = PartSpec(edge="perpendicular", joint_gap=0.0, glass_thickness=12.0)
    parts = build_parts(dome, spec)
    area = face_areas(dome.mesh)
    for p in parts.panels:
        assert p.area_mm2 == pytest.approx(area[p.element], rel=1e-12)
        assert p.volume_mm3 == pytest.approx(12.0 * area[p.element], rel=1e-12)


def test_axis_edges_make_neighbouring_panel_sides_parallel_and_a_gap_apart(dome, parts):
    gap = parts.spec.joint_gap
    topo = dome.mesh.topology
    side = {}
    for p in parts.panels:
        k = len(p.faces) - 2
        n = p.normals[2:]
        for j, e in enumerate(p.neighbours[:k]):
            side[(p.element, e)] = (n[j], p.vertices[list(p.faces[2 + j])])
    for e, (f0, f1) in enumerate(topo.edge_faces):
        if f1 < 0:
            continue
        bid = parts.beams[e].id
        (n0, X0), (n1, X1) = side[(f0, bid)], side[(f1, bid)]
        assert np.dot(n0, n1) == pytest.approx(-1.0, abs=1e-12)
        assert np.dot(X1 - X0[0], n0).mean() == pytest.approx(gap, abs=1e-9)


def test_panels_bear_on_their_beams(parts):
    """Every panel's bearing face lies in a top face plane of each of its beams, over the beam."""
    by_id = parts.by_id
    for p in parts.panels:
        bearing = p.vertices[list(p.faces[p.group.outline_face])]
        for bid in p.neighbours:
            b = by_id[bid]
            tops = [2, 3]  # T0+ and T0-
            d = [np.abs((bearing - b.vertices[b.faces[t][0]]) @ b.normals[t]).max() for t in tops]
            t = tops[int(np.argmin(d))]
            assert min(d) < 1e-9
            assert np.dot(b.normals[t], p.normals[p.group.outline_face]) == pytest.approx(-1.0, abs=1e-12)


def test_no_two_parts_overlap_and_beams_meet_in_planes(parts):
    result = intersections(_solids(parts), 1e-3)
    assert result["pass"], result["failures"]
    assert result["box_pairs"] > 0 and result["cleared_by_plane"] + result["boolean_pairs"] == result["box_pairs"]
    assert result["max_volume_mm3"] < 1e-6


def test_overlap_is_detected(parts):
    b = parts.groups[-1]
    moved = b.vertices.copy()
    moved[0] += 25.0 * b.normals[0, 0]  # push beam B0001 halfway into its neighbours' space
    bad = dataclasses.replace(parts, groups=parts.groups[:-1] + (dataclasses.replace(b, vertices=moved),))
    result = intersections(_solids(bad), 1e-3)
    assert not result["pass"] and any("B0001" in f["pair"] for f in result["failures"])


def test_flat_outlines_keep_edge_lengths_and_area(parts):
    """The bevel reference line is the bearing face (panels) or the beam quad (beams, planar here)
    moved rigidly into the sheet; the cut outline (``flat``) holds it and has the BOM's area."""
    for g in parts.groups:
        P = g.vertices[:, list(g.ring)]
        e3 = np.linalg.norm(np.roll(P, -1, axis=1) - P, axis=2)
        e2 = np.linalg.norm(np.roll(g.bevel_ref, -1, axis=1) - g.bevel_ref, axis=2)
        np.testing.assert_allclose(e2, e3, rtol=0, atol=1e-9)
        np.testing.assert_allclose(polygon_area_2d(g.flat), g.area_mm2, rtol=1e-12)
        assert np.all(g.flat.min(axis=1) > -1e-9) and np.all(g.flat.max(axis=1) <= g.rect + 1e-9)


def test_rigid_motion_changes_no_dimension(dome, parts):
    moved = offset_structure(dome.mesh.with_vertices(rigid(dome.mesh.V)), dome.distances)
    other = build_parts(moved, PartSpec())
    for a, b in zip(parts.groups, other.groups):
        np.testing.assert_allclose(b.volume_mm3, a.volume_mm3, rtol=1e-9)
        np.testing.assert_allclose(b.rect, a.rect, rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(b.length_mm, a.length_mm, rtol=1e-9)


def test_build_is_pure(dome):
    before = [np.array(x, copy=True) for x in (dome.mesh.V, dome.beam_quads, dome.axes, dome.layers[0])]
    build_parts(dome, PartSpec(node_radius=30.0))
    for x, y in zip(before, (dome.mesh.V, dome.beam_quads, dome.axes, dome.layers[0])):
        np.testing.assert_array_equal(x, y)


def test_nodes_are_prisms_the_beams_keep_clear_of(dome):
    r = 45.0
    parts = build_parts(dome, PartSpec(node_radius=r))
    K = parts.spec.node_sides
    cap = 0.5 * K * r * r * np.sin(2 * np.pi / K)
    for n in parts.nodes:
        assert n.volume_mm3 == pytest.approx(cap * n.length_mm, rel=1e-12)
    axes, P0 = dome.axes, dome.layers[0]
    E = dome.mesh.topology.edges
    for b in parts.beams:
        for v in E[b.element]:
            X = b.vertices - P0[v]
            dist = np.linalg.norm(X - np.outer(X @ axes[v], axes[v]), axis=1)
            assert dist.min() >= r - 1e-9
    result = intersections(_solids(parts), 1e-3)
    assert result["pass"], result["failures"]


def test_open_mesh_with_boundary_and_flipped_normals_build_valid_parts():
    for structure in (dome_structure(sweep=np.pi), dome_structure(flip=True)):
        parts = build_parts(structure, PartSpec())
        for g in parts.groups:
            assert np.all(g.volume_mm3 > 0)
            np.testing.assert_allclose(volumes(g.vertices, g.faces), g.volume_mm3)
        assert intersections(_solids(parts), 1e-3)["pass"]


def test_pq_mesh_that_is_not_conical_builds_with_twisted_beams_reported():
    a = np.stack([np.linspace(0, 6000, 5), np.zeros(5), 400 * np.sin(np.linspace(0, 2, 5))], axis=1)
    b = np.stack([np.zeros(4), np.linspace(0, 4500, 4), 300 * np.cos(np.linspace(0, 2, 4))], axis=1)
    mesh = shapes.translational(a, b)
    structure = offset_structure(mesh, (0.0, -200.0))
    assert not structure.is_conical
    parts = build_parts(structure, PartSpec())
    assert parts.edge_mode == "perpendicular"
    assert parts.report["beams"]["planarity_mm_max"] > 1e-3
    assert max(g.residual_mm.max() for g in parts.groups) < 1e-8
    assert all(np.all(g.volume_mm3 > 0) for g in parts.groups)


def _twisted_structure():
    """A translational net (PQ exactly, not conical): the interior beams twist by up to ~5 mm."""
    a = np.stack([np.linspace(0, 6000, 5), np.zeros(5), 2000 * np.sin(np.linspace(0, 2, 5))], axis=1)
    b = np.stack([np.zeros(4), np.linspace(0, 4500, 4), 2000 * np.cos(np.linspace(0, 2, 4))], axis=1)
    return offset_structure(shapes.translational(a, b), (0.0, -200.0))


@pytest.mark.parametrize("edge", ["perpendicular", "axis"])
def test_twisted_beams_are_flat_plates_hinged_on_the_node_axes(edge):
    """Beams of a PQ mesh that is not conical twist; each is a flat plate whose ends turn about the
    node axes, so neighbouring beams share their end plane exactly and nothing overlaps."""
    structure = _twisted_structure()
    parts = build_parts(structure, PartSpec(edge=edge))
    assert parts.report["beams"]["planarity_mm_max"] > 1.0  # mm: really twisted
    assert max(g.residual_mm.max() for g in parts.groups) < 1e-8  # and still exactly planar faces
    assert intersections(_solids(parts), 1e-3)["pass"]
    P0, axes = structure.layers[0], structure.axes
    E = structure.mesh.topology.edges
    ends = {}  # node -> normals of the end faces of its beams
    for b in parts.beams:
        for end, faces in ((0, (6, 7)), (1, (8, 9))):
            v = int(E[b.element][end])
            for fi in faces:
                n = b.normals[fi]
                np.testing.assert_allclose((b.vertices[list(b.faces[fi])] - P0[v]) @ n, 0.0, atol=1e-8)
                assert abs(n @ axes[v]) < 1e-12  # the end plane holds the node axis
                ends.setdefault(v, []).append(n)
    interior = ~structure.mesh.topology.is_boundary_vertex
    for v in np.nonzero(interior)[0].tolist():  # every end plane at an inner node has its twin
        N = np.array(ends[v])
        np.testing.assert_allclose((N @ N.T).min(axis=1), -1.0, atol=1e-12)


def test_twisted_beams_carry_their_panels():
    structure = _twisted_structure()
    parts = build_parts(structure, PartSpec())
    by_id = parts.by_id
    for p in parts.panels:
        bearing = p.vertices[list(p.faces[p.group.outline_face])]
        for bid in p.neighbours:
            b = by_id[bid]
            d = min(np.abs((bearing - b.vertices[b.faces[t][0]]) @ b.normals[t]).max() for t in (2, 3))
            assert d < 1e-6  # the glass lies on a top face of every beam under it


def test_a_plate_thinner_than_its_twist_is_refused_naming_the_twist():
    with pytest.raises(PartError, match=r"beam B\d{4} .*quad twists: corners up to 1.5 mm off"):
        build_parts(_twisted_structure(), PartSpec(beam_width=2.0, joint_gap=1.0))


def test_a_panel_too_narrow_for_the_joint_names_the_gap_that_works():
    x = np.array([0.0, 1500.0, 1508.0, 3000.0])  # the middle column of quads is 8 mm wide
    a = np.stack([x, np.zeros(4), 1e-4 * (x - 1500.0) ** 2], axis=1)
    b = np.stack([np.zeros(3), [0.0, 1200.0, 2400.0], np.zeros(3)], axis=1)
    structure = offset_structure(shapes.translational(a, b), (0.0, -200.0))
    with pytest.raises(PartError) as info:
        build_parts(structure, PartSpec(joint_gap=10.0))
    msg = str(info.value)
    assert isinstance(info.value, MeshError) and (info.value.part, info.value.element) == ("P0003", 2)
    assert msg.startswith("panel P0003 (face 2)") and "2 panels fail (P0003, P0004)" in msg
    assert "width 8.0 mm" in msg
    fits = float(msg.split("parts.joint_gap <= ")[1].split(" mm")[0])
    assert 5.0 < fits < 8.0  # the tilted sides (edge axis) of the 10 mm glass narrow it further
    parts = build_parts(structure, PartSpec(joint_gap=fits, beam_width=fits + 0.5))  # the gap it names builds
    assert all(np.all(g.volume_mm3 > 0) for g in parts.groups)
    with pytest.raises(PartError, match="panel P0003"):
        build_parts(structure, PartSpec(joint_gap=fits + 0.2, beam_width=fits + 0.7))
    # 60 mm beams on an 8 mm quad: no
    with pytest.raises(PartError, match=r"beam B\d{4} .*mitred ends cross within the beam \(its edge is 8 mm long\)"):
        build_parts(structure, PartSpec(joint_gap=fits))


def test_a_folded_mesh_face_is_named_as_such():
    """A dart-shaped (non-convex) face: no part setting helps, the message says the mesh is at fault."""
    mesh = shapes.grid(4, 4, size=(3000.0, 3000.0))
    V = mesh.V.copy()
    V[5, :2] = [1800.0, 1800.0]  # inside the triangle of the opposite corners of face 4
    with pytest.raises(PartError, match=r"panel P0005 \(face 4\): the mesh face itself is folded"):
        build_parts(offset_structure(mesh.with_vertices(V), (0.0, -200.0)), PartSpec())


def test_a_joint_gap_that_swallows_a_panel_is_refused(dome):
    with pytest.raises(PartError, match=r"panel P\d{4} .*joint_gap"):
        build_parts(dome, PartSpec(joint_gap=3000.0, beam_width=4000.0))


def test_beams_shorter_than_their_trims_are_refused():
    mesh = dome_mesh(n_around=40, k=3)
    with pytest.raises(PartError, match=r"beam B\d{4}"):
        build_parts(offset_structure(mesh, (0.0, -200.0)), PartSpec(beam_width=900.0))


@pytest.mark.parametrize("key,value", [("glass_thickness", -1.0), ("edge", "round"), ("joint_gap", 70.0),
                                       ("node_radius", float("nan")), ("node_sides", 3)])
def test_spec_refuses_bad_values_naming_the_key(key, value):
    with pytest.raises(ConfigError, match=f"parts.{key}"):
        PartSpec(**{key: value})
