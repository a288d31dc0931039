"""The paper's methods' fast paths: banded systems, exact cached footpoints, cached measures.

Each fast path is checked against the plain computation it replaces: the
sparse ``J^T J`` and KKT matrix (SuperLU), ``Reference.closest``, fresh angle
and determinant values.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from optimize.mesh import measures
from optimize.modelling import shapes
from optimize.proximity import Reference
from optimize.solvers.paper.assembly import gram_band, kkt_band
from optimize.linalg.banded import band_order
from optimize.proximity import Footpoints
from optimize.linalg.spd import solve
from optimize.solvers.paper.penalty import Linearized
from optimize.solvers.paper.problem import Problem
from optimize.solvers.paper.sqp import KKTFactor, kkt_matrix, objective
from optimize.modelling.designs import trefoil_band_mesh as trefoil_band

RNG = np.random.default_rng(11)


def strip_problem(fixed=None, n_quads=40):
    m = trefoil_band(n_quads, 0.4)
    return Problem(m, "strip", fixed=fixed, fairness=3e-3, closeness=2e-2)


def unpermute_lower(ab: np.ndarray, order) -> np.ndarray:
    """Dense symmetric matrix of a lower band ``ab (bw + 1, n)`` in ``order``."""
    n, bw = order.n, order.bw
    M = np.zeros((n, n))
    for d in range(bw + 1):
        j = np.arange(n - d)
        M[j + d, j] = ab[d, : n - d]
    M = M + np.tril(M, -1).T
    return M[np.ix_(order.inv, order.inv)]


@pytest.mark.parametrize("fixed", [None, np.array([0, 5, 17, 40])])
def test_gram_band_equals_sparse_normal_matrix(fixed):
    p = strip_problem(fixed)
    x = p.x0() + 0.05 * RNG.standard_normal(3 * p.mesh.n_vertices)
    foot = p.footpoints(x)
    band = gram_band(p, p.system)
    assert band is not None
    lin = Linearized(p, x, 3e-3, 2e-2, foot, band, None)
    A = p.system.pattern.csr(lin.a)
    K, C = p.K, p.closeness(x, foot)[1]
    J = sp.vstack([A, np.sqrt(3e-3) * K, np.sqrt(2e-2) * C]).tocsr()
    N = (J.T @ J).toarray()
    assert np.abs(unpermute_lower(lin.ab, band.order) - N).max() < 1e-12 * np.abs(N).max()
    c = p.system.evaluate(x.reshape(-1, 3), jac=False, weighted=True)
    R = np.concatenate([c, np.sqrt(3e-3) * p.fairness(x)[0], np.sqrt(2e-2) * p.closeness(x, foot)[0]])
    assert np.allclose(lin.g, J.T @ R, rtol=1e-12, atol=1e-14)
    assert np.isclose(lin.E, R @ R, rtol=1e-13)
    s, how = lin.solve(0.1)
    D = np.maximum(np.diag(N), 1e-9 * max(np.diag(N).max(), 1.0))
    assert how == "banded"
    assert np.allclose(s, np.linalg.solve(N + 0.1 * np.diag(D), -lin.g), rtol=1e-9, atol=1e-12)
    assert np.isclose(lin.curvature(s), s @ N @ s, rtol=1e-12)


@pytest.mark.parametrize("hessian", ["gauss-newton", "exact"])
def test_kkt_band_solution_equals_sparse_lu(hessian):
    from optimize.solvers.paper.hessian import constraint_curvature

    p = strip_problem(np.array([3, 50]), n_quads=120)  # bandwidth <= 2 sqrt(n) for the LU
    x = p.x0() + 0.05 * RNG.standard_normal(3 * p.mesh.n_vertices)
    foot = p.footpoints(x)
    f, g, H = objective(p, x, p.w_fair, p.w_close, foot=foot)
    c, a = p.sqp_system.evaluate_data(x.reshape(-1, 3))
    A = p.sqp_system.pattern.csr(a)
    extra = None
    if hessian == "exact":
        y = RNG.standard_normal(len(c))
        extra = p.cols2(constraint_curvature(p.mesh, p.sqp_terms, x.reshape(-1, 3), y, p.sqp_system.blocks))
    band = kkt_band(p, p.sqp_system, exact=hessian == "exact")
    assert band is not None
    Hx = H if extra is None else H + extra
    fac = KKTFactor(Hx, A, 1e-4, band=band, h_data=H.data, a_data=a, extra=extra)
    b = RNG.standard_normal(Hx.shape[0] + len(c))
    xb, how = fac.solve(b)
    assert how == "banded"
    M = kkt_matrix(Hx, A, 1e-4)
    assert np.abs(M @ xb - b).max() < 1e-9 * np.abs(b).max()
    assert np.allclose(xb, solve(M, b, symmetric=False)[0], rtol=1e-7, atol=1e-9)
    assert np.isclose(fac.lu.norm1, sp.linalg.norm(M, 1), rtol=1e-12)


def test_kkt_band_rejects_entries_outside_the_band_and_falls_back():
    p = strip_problem(n_quads=120)
    x = p.x0()
    f, g, H = objective(p, x, p.w_fair, p.w_close)
    c, a = p.sqp_system.evaluate_data(x.reshape(-1, 3))
    A = p.sqp_system.pattern.csr(a)
    band = kkt_band(p, p.sqp_system)  # Gauss-Newton layout
    k = H.shape[0]
    ends = band.order.perm[band.order.perm < k][[0, -1]]  # the first and last coordinate in the band
    far = sp.coo_matrix(([1.0, 1.0], (ends, ends[::-1])), shape=(k, k))
    assert band.factor(H.data, a, 1e-3, 1e-8, extra=far) is None
    fac = KKTFactor(H + far, A, 1e-3, band=band, h_data=H.data, a_data=a, extra=far)
    b = RNG.standard_normal(k + len(c))
    xs, how = fac.solve(b)
    assert how == "lu"
    assert np.abs(kkt_matrix(H + far, A, 1e-3) @ xs - b).max() < 1e-8 * np.abs(b).max()


def test_band_order_declines_wide_bands():
    n = 200
    rows, cols = np.triu_indices(n, 1)  # a dense pattern: bandwidth n - 1
    assert band_order(rows, cols, n, pivoting=True) is None
    order = band_order(np.arange(n - 1), np.arange(1, n), n)  # a path: bandwidth 1
    assert order is not None and order.bw == 1


@pytest.mark.parametrize("mesh", [trefoil_band(80, 0.3),
                                  shapes.perturbed(shapes.revolution(shapes.dome_profile(k=5), 8), 0.05, seed=3)],
                         ids=["strip", "dome"])
def test_cached_footpoints_equal_reference_closest(mesh):
    ref = Reference(mesh)
    h = measures.edge_lengths(mesh).mean()
    fp = Footpoints(ref, 0.1 * h)
    P = mesh.V.copy()
    for it in range(30):  # large moves first (every point gets new candidates), then small ones
        P = P + (0.4 if it < 6 else 0.02) * h * RNG.standard_normal(P.shape)
        Y, N = fp.closest(P)
        Y0, N0 = ref.closest(P)
        d, d0 = np.linalg.norm(P - Y, axis=1), np.linalg.norm(P - Y0, axis=1)
        assert np.abs(d - d0).max() <= 1e-12 * ref.bbox_diagonal
        same = np.linalg.norm(Y - Y0, axis=1) <= 1e-12 * ref.bbox_diagonal  # not a tie between far points
        assert same.mean() > 0.99
        assert np.allclose(N[same], N0[same], atol=1e-10)
    assert 0 < fp.rebuilt < 30 * len(P) and not fp.delegate


def test_measure_does_not_reuse_values_of_another_iterate():
    p = strip_problem()
    x1 = p.x0()
    x2 = x1 + 0.1 * RNG.standard_normal(len(x1))
    p.system.evaluate_data(x1.reshape(-1, 3), jac=False)  # leaves x1's values in the cache
    fresh = Problem(p.mesh, "strip", fairness=3e-3, closeness=2e-2).measure(x2)
    assert p.measure(x2) == fresh
    p.system.evaluate_data(x2.reshape(-1, 3), jac=False)  # now the cache holds x2's values
    assert p.measure(x2) == fresh
