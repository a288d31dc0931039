"""Every constraint of the optimizer: Jacobian against finite differences, zero on meshes
that satisfy it by construction, layout bookkeeping."""
import numpy as np
import pytest

from optimize import proximity
from optimize.errors import ConfigError
from optimize.modelling import shapes
from optimize.terms import (
    anglebalance,
    anglesum,
    circular,
    conical,
    determinants,
    diagonals,
    facesum,
    glide,
    planarity,
    unit,
)
from optimize.terms import fixed as fixed_mod
from optimize.terms.formulation import Formulation
from optimize.terms.variables import Layout


def _revolution():
    return shapes.revolution(shapes.dome_profile(k=6), 12)


def _translational():
    u = np.linspace(0, 3, 6)
    a = np.stack([u, np.zeros_like(u), 0.3 * np.sin(u)], axis=1)
    w = np.linspace(0, 2, 5)
    b = np.stack([np.zeros_like(w), w, 0.2 * w ** 2], axis=1)
    return shapes.translational(a, b)


def _fd_check(fun, x, seed=0, h=1e-6):
    """Max relative error of J @ d against central differences along random directions."""
    rng = np.random.default_rng(seed)
    r, J = fun(x)
    worst = 0.0
    for _ in range(3):
        d = rng.standard_normal(x.size)
        fd = (fun(x + h * d)[0] - fun(x - h * d)[0]) / (2 * h)
        worst = max(worst, np.abs(fd - J @ d).max() / max(1.0, np.abs(fd).max()))
    return worst


def _random_x(form, seed=1):
    """A generic point: perturbed positions and auxiliary values (no constraint holds)."""
    rng = np.random.default_rng(seed)
    x = form.start(form.mesh.V)
    return x + 0.1 * rng.standard_normal(x.size)


@pytest.mark.parametrize("unknowns", ["auxiliary", "vertices"])
@pytest.mark.parametrize("target", ["pq", "conical", "circular"])
def test_formulation_jacobian_finite_differences(target, unknowns):
    form = Formulation(shapes.perturbed(_revolution(), 0.1, seed=2), target, unknowns)
    x = _random_x(form)
    assert _fd_check(form.terms, x) < 1e-7


def test_vertex_formulation_jacobian_with_ngons():
    cap = shapes.revolution(np.array([[1.0, 0.0], [1.0, 1.0], [0.8, 1.5]]), 8)
    from optimize import Mesh

    mesh = shapes.perturbed(Mesh(cap.V, cap.faces_list() + [list(range(0, 24, 3))]), 0.05, seed=3)
    form = Formulation(mesh, "conical", "vertices")
    assert len(form.ngons) == 1
    assert _fd_check(form.terms, _random_x(form, 11)) < 1e-7


def test_node_axis_rows_jacobian_and_zero_on_a_surface_of_revolution():
    from optimize.terms import nodeaxes

    mesh = shapes.perturbed(_revolution(), 0.1, seed=4)
    form = Formulation(mesh, "conical", "vertices", beams=True)
    assert form.layout.blocks["node_axes"] == (mesh.n_vertices, 3)
    assert _fd_check(form.terms, _random_x(form, 12)) < 1e-7
    exact = Formulation(_revolution(), "conical", "vertices", beams=True)
    x = exact.start(exact.mesh.V)
    d = exact.axis_defects(x)  # a surface of revolution: cones and planar beams by construction
    interior = ~exact.mesh.topology.is_boundary_vertex
    owner = np.repeat(np.arange(len(exact.axis_vertices)), exact.mesh.topology.star_size[exact.axis_vertices])
    assert d["node_cone"][interior[exact.axis_vertices][owner]].max() < 1e-9
    E = exact.beam_edges
    both = interior[E[:, 0]] & interior[E[:, 1]]
    assert d["beam"][both].max() < 1e-9
    with pytest.raises(ConfigError, match="torsion_free_beams"):
        Formulation(_revolution(), "conical", "auxiliary", beams=True)
    assert nodeaxes.beam_edges(exact.mesh, boundary=False).shape[0] == both.sum()


def test_diagonal_distance_is_the_planarity_measure_times_mean_diagonal():
    from optimize.mesh import measures

    mesh = shapes.perturbed(_revolution(), 0.1, seed=9)
    form = Formulation(mesh, "pq", "vertices")
    r, J = diagonals.terms(form.start(mesh.V), form.layout, mesh)
    P = mesh.V[mesh.F[:, :4]]
    mean_diag = 0.5 * (np.linalg.norm(P[:, 2] - P[:, 0], axis=1) + np.linalg.norm(P[:, 3] - P[:, 1], axis=1))
    np.testing.assert_allclose(np.abs(r) / mean_diag, measures.planarity(mesh), rtol=1e-9)
    assert _fd_check(lambda y: diagonals.terms(y, form.layout, mesh), _random_x(form, 10)) < 1e-7


def test_ngon_rows_of_the_vertex_formulation_vanish_only_when_it_is_planar():
    from optimize import Mesh

    t = np.linspace(0, 2 * np.pi, 7)[:-1]
    hexagon = np.stack([np.cos(t), np.sin(t), np.zeros(6)], axis=1)
    flat = Mesh(hexagon, [list(range(6))])
    assert diagonals.quadruples(flat).shape == (3, 4)  # runs of four vertices (not used for n-gons)
    form = Formulation(flat, "pq", "vertices")
    assert form.layout.blocks["ngon_normals"] == (1, 3)  # an n-gon keeps a unit normal
    r, _ = form.terms(form.start(flat.V))
    assert r.shape == (7,) and np.abs(r).max() < 1e-15  # 6 corner rows + the unit row
    bent = flat.with_vertices(flat.V + np.array([0, 0, 0, 0, 0, 0.1])[:, None] * [0, 0, 1])
    bform = Formulation(bent, "pq", "vertices")
    assert np.abs(bform.terms(bform.start(bent.V))[0]).max() > 1e-3


def test_unknown_formulation_raises_config_error():
    with pytest.raises(ConfigError, match="formulation.*'normals'"):
        Formulation(_revolution(), "pq", "normals")


@pytest.mark.parametrize("module,target", [(planarity, "pq"), (conical, "conical"), (anglesum, "circular"),
                                           (anglebalance, "conical"), (circular, "circular")])
def test_each_constraint_jacobian(module, target):
    form = Formulation(shapes.perturbed(_revolution(), 0.1, seed=3), target)
    x = _random_x(form, seed=4)
    r, J = module.terms(x, form.layout, form.mesh)
    assert J.shape == (r.size, form.layout.size) and r.size > 0
    assert _fd_check(lambda y: module.terms(y, form.layout, form.mesh), x) < 1e-7


def test_angle_sum_rows_on_mixed_faces():
    """The angle-sum term (rows of different lengths: quads and an octagon) against a loop
    over the faces; zero on a surface of revolution (planar convex faces), below zero once
    perturbed; Jacobian by finite differences."""
    from optimize import Mesh
    from optimize.mesh.measures import corner_angles

    cap = shapes.revolution(np.array([[1.0, 0.0], [1.0, 1.0], [0.8, 1.5]]), 8)
    exact = Mesh(cap.V, cap.faces_list() + [list(range(0, 24, 3))])
    assert sorted(set(exact.face_sizes.tolist())) == [4, 8]
    assert np.abs(facesum.at_positions(exact, exact.V)[0]).max() < 1e-12
    mesh = shapes.perturbed(exact, 0.05, seed=3)
    r, J = facesum.at_positions(mesh, mesh.V)
    phi, t = corner_angles(mesh), mesh.topology
    ref = [phi[t.offsets[f]:t.offsets[f] + t.face_sizes[f]].sum() - (t.face_sizes[f] - 2) * np.pi
           for f in range(mesh.n_faces) if t.face_sizes[f] >= 4]
    assert np.allclose(r, ref, atol=1e-13) and (r < 0).all()
    assert J.shape == (len(ref), 3 * mesh.n_vertices)
    layout = Layout().add("vertices", mesh.n_vertices, 3)
    assert _fd_check(lambda y: facesum.terms(y, layout, mesh), mesh.V.ravel()) < 1e-7
    big = np.nonzero(mesh.face_sizes > 4)[0]
    assert np.allclose(facesum.at_positions(mesh, mesh.V, big)[0], r[-1:])


@pytest.mark.parametrize("module", [determinants, facesum])
def test_vertex_terms_take_their_columns_from_the_layout(module):
    """The paper's determinant and angle-sum rows with the vertices block after another one:
    the columns are the layout's (the same matrix as at positions, moved), the Jacobian
    checks by finite differences, and the rows vanish on a translational net (planar quads)."""
    from optimize import Mesh

    cap = shapes.revolution(np.array([[1.0, 0.0], [1.0, 1.0], [0.8, 1.5]]), 8)
    mesh = shapes.perturbed(Mesh(cap.V, cap.faces_list() + [list(range(0, 24, 3))]), 0.05, seed=5)
    layout = Layout().add("normals", mesh.n_faces, 3).add("vertices", mesh.n_vertices, 3)
    x = np.random.default_rng(6).standard_normal(layout.size)
    layout.view(x, "vertices")[:] = mesh.V
    r, J = module.terms(x, layout, mesh)
    r0, J0 = module.at_positions(mesh, mesh.V)
    assert r.size and np.array_equal(r, r0)
    cols = layout.index("vertices").ravel()
    assert abs(J[:, cols] - J0).max() == 0 and J[:, layout.index("normals").ravel()].nnz == 0
    assert _fd_check(lambda y: module.terms(y, layout, mesh), x) < 1e-7
    flat = _translational()
    assert np.abs(module.at_positions(flat, flat.V)[0]).max() < 1e-12


@pytest.mark.parametrize("name", ["normals", "axes"])
def test_unit_jacobian(name):
    form = Formulation(_revolution(), "conical")
    x = _random_x(form, seed=5)
    assert _fd_check(lambda y: unit.terms(y, form.layout, name), x) < 1e-7


def test_glide_jacobian_and_footpoints():
    mesh = shapes.perturbed(shapes.grid(5, 4, height=lambda x, y: x * y), 0.05, seed=6)
    form = Formulation(mesh, "pq")
    curve = proximity.BoundaryCurve(mesh)
    bnd = np.nonzero(mesh.topology.is_boundary_vertex)[0]
    x = form.start(mesh.V)
    r, _ = glide.terms(x, form.layout, bnd, curve)
    assert np.abs(r).max() < 1e-12  # the mesh's own boundary lies on its curve
    rng = np.random.default_rng(7)
    x = x + 0.01 * rng.standard_normal(x.size)
    foot = curve.closest(form.layout.view(x, "vertices")[bnd])
    assert _fd_check(lambda y: glide.terms(y, form.layout, bnd, curve, foot), x) < 1e-9
    # exact closest points against brute force over all segments
    P = mesh.V[bnd] + 0.3 * rng.standard_normal((len(bnd), 3))
    Y, _ = curve.closest(P)
    best = np.min([np.linalg.norm(proximity.closest_on_segments(P, np.broadcast_to(a, P.shape),
                                                            np.broadcast_to(b, P.shape)) - P, axis=1)
                   for a, b in zip(curve.A, curve.B)], axis=0)
    np.testing.assert_allclose(np.linalg.norm(Y - P, axis=1), best, atol=1e-14)


def test_edge_floor_rows_act_only_on_short_edges():
    from optimize.terms import edgefloor

    mesh = shapes.grid(4, 3)
    form = Formulation(mesh, "pq")
    E = mesh.topology.edges
    x = form.start(mesh.V)
    length = np.linalg.norm(mesh.V[E[:, 0]] - mesh.V[E[:, 1]], axis=1)
    floor = length * np.where(np.arange(len(E)) % 2 == 0, 1.5, 0.5)  # every other edge is too short
    r, J = edgefloor.terms(x, form.layout, E, floor)
    np.testing.assert_allclose(r, np.where(np.arange(len(E)) % 2 == 0, -0.5 * length, 0.0), atol=1e-12)
    assert np.all(J.getnnz(axis=1)[1::2] == 0) and np.all(J.getnnz(axis=1)[::2] == 6)
    np.testing.assert_allclose(edgefloor.shortfall(mesh.V, E, floor), -r, atol=1e-12)
    rng = np.random.default_rng(3)
    y = x + 0.01 * rng.standard_normal(x.size)  # no edge near its floor: the hinge is smooth there
    assert _fd_check(lambda z: edgefloor.terms(z, form.layout, E, floor), y) < 1e-8


def test_gliding_boundary_vertex_does_not_slide_into_a_corner():
    """The atrium roof's remeshed quads, conical with the boundary gliding: without the edge floor a
    vertex next to a corner slid into it (an edge of 0.0 mm, a panel the CAD stage refused)."""
    from optimize.api import GLIDE_EDGE_FLOOR, optimize_mesh
    from optimize.remesh.quads import remesh
    from optimize.remesh.surfaces import holed_roof

    surf = holed_roof()
    quads, rep = remesh(surf, 0.3, with_report=True)
    res = optimize_mesh(quads, "conical", reference=surf, glide_boundary=True, fixed=rep.corners)
    assert res.status == "converged", res.message
    E = quads.topology.edges
    at = quads.topology.is_boundary_vertex[E].any(1)
    before = np.linalg.norm(quads.V[E[:, 0]] - quads.V[E[:, 1]], axis=1)
    after = np.linalg.norm(res.mesh.V[E[:, 0]] - res.mesh.V[E[:, 1]], axis=1)
    assert np.all(after[at] >= GLIDE_EDGE_FLOOR * before[at] * (1 - 1e-6))
    assert res.defects["planarity"]["max"] <= 1e-6 and res.defects["conical"]["max"] <= 1e-6


@pytest.mark.parametrize("unknowns", ["auxiliary", "vertices"])
def test_zero_residual_on_translational_surface_pq(unknowns):
    form = Formulation(_translational(), "pq", unknowns)
    r, _ = form.terms(form.start(form.mesh.V))
    assert np.abs(r).max() < 1e-12


@pytest.mark.parametrize("unknowns", ["auxiliary", "vertices"])
@pytest.mark.parametrize("target", ["conical", "circular"])
def test_zero_residual_on_surface_of_revolution(target, unknowns):
    form = Formulation(_revolution(), target, unknowns)
    r, _ = form.terms(form.start(form.mesh.V))
    assert np.abs(r).max() < 1e-10


@pytest.mark.parametrize("unknowns", ["auxiliary", "vertices"])
def test_nonzero_residual_on_noise(unknowns):
    for target in ("pq", "conical", "circular"):
        form = Formulation(shapes.perturbed(_revolution(), 0.1, seed=8), target, unknowns)
        r, _ = form.terms(form.start(form.mesh.V))
        assert np.abs(r).max() > 1e-3


def test_ngon_planarity_rows_vanish_on_planar_cap():
    cap = shapes.revolution(np.array([[1.0, 0.0], [1.0, 1.0]]), 8)
    faces = cap.faces_list() + [list(range(0, 16, 2))]  # bottom octagon, planar
    from optimize import Mesh

    mesh = Mesh(cap.V, faces)
    form = Formulation(mesh, "pq")
    r, _ = form.terms(form.start(mesh.V))
    assert np.abs(r).max() < 1e-12


def test_layout_named_slices():
    L = Layout().add("vertices", 4, 3).add("cos", 2, 1)
    x = L.pack(vertices=np.arange(12.0), cos=[7.0, 8.0])
    assert L.size == 14 and L.view(x, "cos").tolist() == [7.0, 8.0]
    assert L.index("cos").tolist() == [12, 13] and L.view(x, "vertices").shape == (4, 3)
    with pytest.raises(ValueError, match="expected 2 x 1"):
        L.pack(vertices=np.zeros(12), cos=[1.0])
    with pytest.raises(KeyError):
        L.offset("normals")


def test_fixed_resolution():
    mesh = shapes.grid(4, 3)
    assert fixed_mod.resolve(mesh, "corners").tolist() == [0, 2, 9, 11]
    assert len(fixed_mod.resolve(mesh, "boundary")) == 10
    assert fixed_mod.resolve(mesh, None).size == 0
    assert fixed_mod.resolve(mesh, [3, 1, 3]).tolist() == [1, 3]
    with pytest.raises(ConfigError, match="out of range"):
        fixed_mod.resolve(mesh, [12])
    with pytest.raises(ConfigError, match="not known"):
        fixed_mod.resolve(mesh, "edges")


def test_fairness_and_angle_parts_sum_to_the_whole():
    from optimize.terms.fairness import fairness_matrix, fairness_matrix_parts

    mesh = shapes.perturbed(_revolution(), 0.1, seed=9)
    K1, K2 = fairness_matrix_parts(mesh)
    assert abs(K1 + K2 - fairness_matrix(mesh)).max() == 0
    form = Formulation(mesh, "conical")
    x = _random_x(form, seed=10)
    r, J, parts = anglebalance.terms(x, form.layout, mesh, parts=True)
    assert len(parts) == 4 and abs(sum(parts[1:], parts[0]) - J).max() < 1e-12
    # each part stays inside one face: at most the 3 vertices of one corner per row
    assert max(np.diff(p.tocsr().indptr).max() for p in parts) <= 9
