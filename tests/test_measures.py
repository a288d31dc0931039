"""Measures: hand-computed values, zero defect by construction, invariance, the real meshes."""
import json

import numpy as np
import pytest

from optimize import Mesh, MeshError
from optimize.modelling import shapes
from optimize.mesh import measures as M
from optimize.mesh.io import read_mesh


def _planar_star(directions_deg):
    """Four planar parallelograms around vertex 0 with the given edge directions (z = 0)."""
    a = np.radians(directions_deg)
    n = np.stack([np.cos(a), np.sin(a), 0 * a], axis=1)
    V = np.vstack([[[0, 0, 0]], n, n + np.roll(n, -1, axis=0)])
    F = [[0, 1 + i, 5 + i, 1 + (i + 1) % 4] for i in range(4)]
    return Mesh(V, F, name="star")


# -- hand-computed values -----------------------------------------------------------
@pytest.mark.parametrize("h", [1e-4, 0.1, 1.0])
def test_nonplanar_quad_diagonal_distance(h):
    m = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, h], [0, 1, 0]], [[0, 1, 2, 3]])
    # diagonals (0,0,0)-(1,1,h) and (1,0,0)-(0,1,0): n = (-h, -h, 2), distance h / |n|
    dist = h / np.sqrt(2 * h * h + 4)
    mean_diag = 0.5 * (np.sqrt(2 + h * h) + np.sqrt(2))
    assert M.planarity(m)[0] == pytest.approx(dist / mean_diag, rel=1e-12)


def test_zigzag_hexagon_planarity():
    # regular hexagon of radius r, z alternating +-h: the fitted plane is z = 0
    r, h = 2.0, 0.1
    a = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    V = np.stack([r * np.cos(a), r * np.sin(a), h * (-1.0) ** np.arange(6)], axis=1)
    m = Mesh(V, [list(range(6))])
    assert M.planarity(m)[0] == pytest.approx(h / np.sqrt(r * r + 4 * h * h), rel=1e-12)


def test_planar_faces_have_zero_planarity(quad, grid3x3):
    assert M.planarity(quad)[0] == 0.0
    assert np.all(M.planarity(grid3x3) == 0.0)


def test_conical_defect_of_planar_star():
    m = _planar_star([0, 80, 170, 260])  # corner angles 80, 90, 90, 100 degrees
    assert m.topology.interior_valence4.tolist() == [0]
    assert M.conical_defect(m)[0] == pytest.approx(np.radians(abs(80 + 90 - 90 - 100)), rel=1e-12)
    assert M.conical_defect(_planar_star([0, 90, 180, 270]))[0] == pytest.approx(0, abs=1e-15)


def test_circular_defect_parallelogram_and_trapezoid():
    s = np.sqrt(3) / 2
    para = Mesh([[0, 0, 0], [2, 0, 0], [2.5, s, 0], [0.5, s, 0]], [[0, 1, 2, 3]])  # 60/120 deg
    assert M.circular_defect(para)[0] == pytest.approx(np.pi / 3, rel=1e-12)
    trap = Mesh([[0, 0, 0], [4, 0, 0], [3, 1.5, 0], [1, 1.5, 0]], [[0, 1, 2, 3]])  # isosceles
    assert M.circular_defect(trap)[0] == pytest.approx(0, abs=1e-15)


def test_corner_angles_sum_per_face(cylinder_path):
    m = read_mesh(cylinder_path)
    ang = M.corner_angles(m)
    per_face = np.bincount(m.topology.corner_face, weights=ang)
    assert np.allclose(per_face, (m.face_sizes - 2) * np.pi, atol=1e-12)


def test_areas_lengths_fairness_of_grid(grid3x3):
    assert np.allclose(M.face_areas(grid3x3), 1.0)
    assert np.allclose(M.edge_lengths(grid3x3), 1.0)
    assert np.all(M.fairness(grid3x3) == 0.0)
    V = grid3x3.V.copy()
    V[5, 2] = 0.5  # lift one interior vertex: |a - 2v + b| = 1 along both polylines through it
    bent = grid3x3.with_vertices(V)
    f = M.fairness(bent)
    assert f.max() == pytest.approx(1.0 / M.edge_lengths(bent).mean(), rel=1e-12)
    # two triples through vertex 5 see 1, and one triple each at interior neighbours 6 and 9
    # sees 0.5 (the boundary neighbours 1 and 4 only continue along the boundary)
    h = M.edge_lengths(bent).mean()
    assert sorted(f[f > 0] * h) == pytest.approx([0.5, 0.5, 1.0, 1.0], rel=1e-12)


# -- zero defect by construction, non-zero after noise -------------------------------------
def test_revolution_is_planar_conical_circular(revolution):
    assert M.planarity(revolution).max() < 1e-12
    assert M.conical_defect(revolution).max() < 1e-12
    assert M.circular_defect(revolution).max() < 1e-12
    assert M.conical_defect(revolution).size == 16 * 5  # every interior vertex is checked


def test_hyperbolic_revolution_is_planar_conical_circular():
    profile = np.array([[2.0, -1.0], [1.3, -0.5], [1.0, 0.0], [1.4, 0.6], [2.2, 1.0]])
    m = shapes.revolution(profile, 11)
    assert M.planarity(m).max() < 1e-12
    assert M.conical_defect(m).max() < 1e-12
    assert M.circular_defect(m).max() < 1e-12
    assert np.all(M.vertex_types(m) == "hyperbolic")


def test_translational_surface_is_planar():
    a = np.array([[0, 0, 0], [1, 0, 0.3], [2, 0, 0.2], [3, 0, 0.8]])
    b = np.array([[0, 0, 0], [0, 1, -0.4], [0, 2, 0.1]])
    assert M.planarity(shapes.translational(a, b)).max() < 1e-12


def test_noise_shows_in_every_measure(perturbed_revolution):
    assert M.planarity(perturbed_revolution).max() > 1e-3
    assert M.conical_defect(perturbed_revolution).max() > 1e-3
    assert M.circular_defect(perturbed_revolution).max() > 1e-3


def test_vertex_types_dome_and_cylinder(revolution, rotation):
    assert np.all(M.vertex_types(revolution) == "elliptic")
    assert np.all(M.gauss_image_area(revolution) > 0)
    cyl = shapes.revolution(np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0], [1.0, 3.0]]), 12)
    moved = cyl.with_vertices(cyl.V @ rotation(3).T + [0.3, 2.0, 1.0])
    assert np.all(M.vertex_types(moved) == "parabolic")  # round-off is not curvature


# -- invariance under rigid motion and scale ------------------------------------------------
@pytest.mark.parametrize("scale", [1e-3, 1.0, 7.3, 1e4])
def test_measures_invariant_under_similarity(perturbed_revolution, rotation, scale):
    m = perturbed_revolution
    moved = m.with_vertices(scale * (m.V @ rotation(11).T) + [120.0, -35.0, 8.0])
    for f in (M.planarity, M.conical_defect, M.circular_defect, M.fairness, M.gauss_image_area):
        assert np.allclose(f(moved), f(m), rtol=1e-7, atol=1e-12), f.__name__
    assert np.array_equal(M.vertex_types(moved), M.vertex_types(m))


def test_measures_do_not_change_the_mesh(perturbed_revolution):
    V0 = perturbed_revolution.V.copy()
    M.summary(perturbed_revolution)
    assert np.array_equal(perturbed_revolution.V, V0)


# -- the shipped tunnel (figures: optimize/modelling/design_tunnel.py) and the capped cylinder ------------
def test_tunnel_measures(tunnel_path):
    m = read_mesh(tunnel_path)
    plan = M.planarity(m)
    assert plan.max() == pytest.approx(3e-5, rel=1e-6)  # the design's `planarity`
    con = M.conical_defect(m)
    assert con.max() > 1.0  # far from conical where the tubes meet
    assert 1e-7 < plan.mean() < plan.max()


def test_cylinder_is_planar_and_conical(cylinder_path):
    m = read_mesh(cylinder_path)
    assert M.planarity(m).max() < 1e-12  # quads and both 20-gon caps
    assert M.conical_defect(m).max() < 1e-12
    assert M.circular_defect(m).max() < 1e-12
    assert np.all(M.vertex_types(m) == "parabolic")


def test_summary_is_json_ready(tunnel_path):
    s = M.summary(read_mesh(tunnel_path))
    back = json.loads(json.dumps(s))
    for key in ("planarity", "conical", "circular"):
        assert set(back[key]) >= {"max", "mean", "count", "worst", "tolerance", "ok"}
    assert back["mesh"]["vertices"] == 807 and back["mesh"]["face_sizes"] == {"4": 784}
    assert back["planarity"]["ok"] is False and back["conical"]["count"] > 0


# -- degenerate faces: shrunk edges and straight corners, apart from folds ---------------------------
def test_clean_meshes_have_no_degenerate_faces(perturbed_revolution, tunnel_path, cylinder_path):
    for m in (perturbed_revolution, read_mesh(tunnel_path), read_mesh(cylinder_path), shapes.grid(4, 4)):
        d = M.degenerate(m, m.V, m.V)
        assert d["shrunk_edges"] == {"count": 0, "edges": 0, "faces": []}, m.name
        assert d["straight_corners"] == {"count": 0, "corners": 0, "faces": []}, m.name


@pytest.mark.parametrize("side,short", [(1.5e-9, True), (1.4e-6, True), (1.5e-6, False), (1e-3, False)])
def test_a_side_below_short_edge_of_its_face_has_shrunk(side, short):
    """A quad whose fourth corner sits ``side`` from the first: a triangle when that is below 1e-6 of
    its longest side (sqrt 2, from corner 2 to corner 3)."""
    m = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, side, 0]], [[0, 1, 2, 3]])
    bad = M.shrunk_edges(m)
    assert bad.tolist() == [False, False, False, short]  # the side from corner 3 to corner 0
    assert M.summary(m)["shrunk_edges"]["count"] == int(short)


@pytest.mark.parametrize("kept,shrunk", [(0.005, True), (0.02, False)])
def test_a_side_below_shrunk_of_its_input_length_has_shrunk(grid3x3, kept, shrunk):
    """Vertex 5 slides toward vertex 6 until their edge keeps ``kept`` of its length: below 1%
    it is shrunk (issue 31: stalled runs left edges at 0.1-0.5%); above 0.1% no fold sees it."""
    V = grid3x3.V.copy()
    V[5] = V[6] + kept * (V[5] - V[6])
    d = M.degenerate(grid3x3, V, grid3x3.V)
    assert d["shrunk_edges"]["edges"] == int(shrunk)
    assert d["shrunk_edges"]["faces"] == ([1, 4] if shrunk else [])
    assert not M.folded_faces(grid3x3, V).any()
    assert M.degenerate(grid3x3, V)["shrunk_edges"]["count"] == 0  # without the input: 0.5% is a side


@pytest.mark.parametrize("corner,straight", [((2, 0, 0), True), ((-1, 0, 0), True), ((2, 1e-5, 0), False),
                                             ((2, -1e-5, 0), False)])
def test_a_quad_corner_at_180_or_0_degrees_is_straight(corner, straight):
    """Quad (0, 1, 2, 3) with corner 1 on the line through corners 0 and 2 (180 degrees, or 0: a
    spike back over corner 0); 1e-5 off the line is a corner (sine 1e-5), on either side."""
    m = Mesh([[0, 0, 0], [1, 0, 0], corner, [1, 1, 0]], [[0, 1, 2, 3]])
    m = Mesh([[0, 0, 0], corner, [3, 0, 0], [1, 1, 0]], [[0, 1, 2, 3]]) if corner[0] == 2 else m
    assert M.straight_corners(m)[1] == straight
    assert M.degenerate(m)["straight_corners"]["count"] == int(straight)


def test_straight_corners_of_larger_polygons_are_allowed():
    pent = Mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], [[0, 1, 2, 3, 4]])
    assert not M.straight_corners(pent).any()
    quad = Mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    assert M.straight_corners(quad).tolist() == [False, True, False, False]


@pytest.mark.parametrize("scale,shift", [(1e-200, 0.0), (1.0, 0.0), (1e200, 0.0), (1.0, 1e6)])
def test_degenerate_is_scale_free(scale, shift):
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1.5e-9, 0]])
    m = Mesh(V * scale + shift, [[0, 1, 2, 3]])
    assert M.shrunk_edges(m).tolist() == [False, False, False, True]


# -- range: coordinates float64 cannot measure or build ------------------------------------------------
def test_range_problem_names_overflow_and_resolution(grid3x3):
    assert M.range_problem(grid3x3.V) is None and M.range_problem(grid3x3.V / 3 * 1e150) is None
    why = M.range_problem(grid3x3.V / 3 * 1e307)
    assert why.startswith("coordinates up to 1e+307 mm: their squared lengths and areas overflow float64")
    assert "expected |x| <= 1e+150 mm" in why
    assert M.range_problem(grid3x3.V * 1e12, resolution=1e-3) is None  # 3e12 mm: held to 4.9e-4 mm
    why = M.range_problem(grid3x3.V * 1e15, resolution=1e-3, needs="the CAD tolerance")
    assert "float64 holds them only to 0.5 mm, coarser than the CAD tolerance 0.001 mm" in why
    assert "expected |x| < 4.5e+12 mm" in why
    with pytest.raises(MeshError, match=r"^roof\.obj: coordinates up to 1e\+307 mm"):
        M.check_range(grid3x3.with_vertices(grid3x3.V / 3 * 1e307), "roof.obj")


def test_relative_resolution_far_from_the_origin(grid3x3):
    assert M.relative_resolution(grid3x3) == pytest.approx(np.spacing(3.0) / 1.0)
    far = grid3x3.with_vertices(grid3x3.V * 1000 + 1e14)  # 1 m edges, 1e14 mm out: 1/64 mm
    assert M.relative_resolution(far) == pytest.approx(0.015625 / 1000)
    assert M.relative_resolution(far) == M.relative_resolution(far, far.V)


def test_summary_lengths_do_not_overflow_where_float64_holds_them(grid3x3):
    m = grid3x3.with_vertices(grid3x3.V / 3 * 1.5e308)
    with np.errstate(all="raise"):
        s = M.summary(m)
    assert s["edge_length"]["mean"] == pytest.approx(5e307)
    assert s["face_area"]["mean"] == np.inf and s["mesh"]["bbox_diagonal"] == np.inf
