"""Building blocks of the optimizer: fairness operator, exact closest points, result object."""
import numpy as np
import pytest

from optimize.modelling import shapes
from optimize.terms.closeness import closeness_terms
from optimize.proximity import Reference, closest_on_triangles
from optimize.terms.fairness import fairness_energy, fairness_matrix
from optimize.mesh.measures import edge_lengths, fairness
from optimize.result import OptimizeResult


def _wavy(nu=9, nv=7):
    return shapes.grid(nu, nv, size=(3.0, 2.0), height=lambda x, y: 0.3 * np.sin(2 * x) * np.cos(3 * y))


def _brute_closest(P, tris):
    """Loop reference: closest point over every triangle, by dense sampling-free exact formula."""
    best = np.full(len(P), np.inf)
    Y = np.zeros_like(P)
    for A, B, C in tris:  # reference loop, tests only
        y = closest_on_triangles(P, np.broadcast_to(A, P.shape), np.broadcast_to(B, P.shape),
                                 np.broadcast_to(C, P.shape))
        d = np.linalg.norm(y - P, axis=1)
        better = d < best
        best[better], Y[better] = d[better], y[better]
    return Y, best


def test_fairness_matrix_matches_second_differences():
    mesh = shapes.perturbed(_wavy(), 0.1, seed=1)
    K = fairness_matrix(mesh)
    t = len(mesh.topology.fair_triples)
    assert K.shape == (3 * t, 3 * mesh.n_vertices)
    d = (K @ mesh.V.ravel()).reshape(-1, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1) / edge_lengths(mesh).mean(), fairness(mesh))
    assert fairness_energy(mesh) == pytest.approx(np.sum(fairness(mesh) ** 2))


def test_fairness_zero_on_affine_grid_and_scale_free():
    flat = shapes.grid(6, 5)
    assert np.abs(fairness_matrix(flat) @ flat.V.ravel()).max() < 1e-12
    mesh = shapes.perturbed(_wavy(), 0.2, seed=2)
    scaled = mesh.with_vertices(7.5 * mesh.V + 3.0)
    assert fairness_energy(scaled) == pytest.approx(fairness_energy(mesh), rel=1e-12)


def test_point_triangle_regions():
    A, B, C = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    P = np.array([[0.2, 0.2, 1.0], [-1, -1, 0.5], [2, -0.5, 0], [0.5, -1, 0], [1, 1, 0], [-1, 0.5, 0]])
    want = np.array([[0.2, 0.2, 0], [0, 0, 0], [1, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0]])
    k = len(P)
    got = closest_on_triangles(P, np.tile(A, (k, 1)), np.tile(B, (k, 1)), np.tile(C, (k, 1)))
    np.testing.assert_allclose(got, want, atol=1e-15)


@pytest.mark.parametrize("spread", [0.05, 0.5, 3.0])
def test_closest_points_exact_against_brute_force(spread):
    mesh = shapes.perturbed(_wavy(), 0.15, seed=3)
    ref = Reference(mesh, k=4)
    rng = np.random.default_rng(4)
    P = mesh.V[rng.integers(0, mesh.n_vertices, 300)] + spread * rng.standard_normal((300, 3))
    Y, N = ref.closest(P)
    Yb, db = _brute_closest(P, mesh.V[mesh.triangulate()])
    np.testing.assert_allclose(np.linalg.norm(Y - P, axis=1), db, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0)
    # the footpoint lies on the triangle reported, and the normal leans the same way as its normal
    _, _, tri = ref.closest(P, return_index=True)
    a = mesh.V[mesh.triangulate()[tri, 0]]
    assert np.abs(np.einsum("ij,ij->i", Y - a, ref.normals[tri])).max() < 1e-12
    assert np.einsum("ij,ij->i", N, ref.normals[tri]).min() > 0.5


def test_normals_are_continuous_at_shared_vertices():
    mesh = shapes.perturbed(_wavy(), 0.15, seed=9)
    ref = Reference(mesh)
    Y, N, tri = ref.closest(mesh.V, return_index=True)
    np.testing.assert_allclose(N, ref.vertex_normals, atol=1e-12)


def test_points_on_the_surface_have_zero_distance():
    mesh = _wavy()
    ref = Reference(mesh)
    assert ref.distance(mesh.V).max() < 1e-12


def test_closeness_terms_jacobian_and_residual():
    mesh = _wavy()
    ref = Reference(mesh)
    rng = np.random.default_rng(5)
    V = mesh.V + 0.01 * rng.standard_normal(mesh.V.shape)
    J, r = closeness_terms(V, ref)
    assert J.shape == (mesh.n_vertices, 3 * mesh.n_vertices)
    Y, N = ref.closest(V)
    np.testing.assert_allclose(r, np.einsum("ij,ij->i", V - Y, N))
    dx = 1e-6 * rng.standard_normal(3 * mesh.n_vertices)
    _, r2 = closeness_terms(V.ravel() + dx, ref, Y, N)
    np.testing.assert_allclose(r2 - r, J @ dx, atol=1e-15)
    # signed distance sizes: |r| never exceeds the true distance
    assert np.all(np.abs(r) <= ref.distance(V) + 1e-15)


def test_result_refuses_inconsistent_status():
    mesh = shapes.grid(3, 3)
    with pytest.raises(ValueError, match="status"):
        OptimizeResult(mesh=mesh, success=False, status="done", message="", nit=0)
    with pytest.raises(ValueError, match="success"):
        OptimizeResult(mesh=mesh, success=True, status="stalled", message="", nit=0)
    res = OptimizeResult(mesh=mesh, success=False, status="max_iter", message="x", nit=3,
                         history=[{"planarity": np.float64(1e-3)}], timings={"total": 0.5})
    rep = res.report()
    assert rep["history"][0]["planarity"] == 1e-3 and type(rep["history"][0]["planarity"]) is float
