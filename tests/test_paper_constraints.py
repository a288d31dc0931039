"""The paper's constraint rows: finite-difference Jacobians, zero defect by construction, invariance."""
import numpy as np
import pytest
import scipy.sparse as sp

from optimize.mesh import Mesh
from optimize.mesh.corners import corner_angle_gradients
from optimize.modelling import shapes
from optimize.solvers.paper.hessian import constraint_curvature
from optimize.solvers.paper.problem import Problem
from optimize.solvers.paper.sqp import kkt_matrix, objective
from optimize.terms.anglebalance import at_positions as angle_balance
from optimize.terms.anglesum import at_positions as circular_angles
from optimize.terms.determinants import at_positions as det_constraints
from optimize.terms.determinants import det_combined_local
from optimize.terms.facesum import at_positions as angle_sum

RNG = np.random.default_rng(7)


def dome(k=5, n_around=7, noise=0.0, seed=1):
    m = shapes.revolution(shapes.dome_profile(k=k), n_around)
    return shapes.perturbed(m, noise, seed=seed) if noise else m


def pentagon_mesh():
    V = np.array([[0, 0, 0], [1, 0, 0.2], [1.5, 0.8, -0.1], [0.6, 1.4, 0.3], [-0.3, 0.8, 0.1],
                  [0.5, -1.0, 0.2]], float)
    return Mesh(V, [[0, 1, 2, 3, 4], [0, 5, 1]])


def fd_check(fn, mesh, V, eps=1e-6):
    """Max error of ``J @ d`` against central differences along random directions."""
    r, J = fn(mesh, V)
    worst = 0.0
    for _ in range(3):
        d = RNG.standard_normal(V.shape)
        fd = (fn(mesh, V + eps * d)[0] - fn(mesh, V - eps * d)[0]) / (2 * eps)
        worst = max(worst, float(np.abs(fd - J @ d.ravel()).max() / max(1.0, np.abs(fd).max())))
    return worst


@pytest.mark.parametrize("fn", [angle_sum, angle_balance, circular_angles, det_constraints])
def test_jacobian_matches_finite_differences(fn):
    m = dome(noise=0.2)
    assert fd_check(fn, m, m.V) < 1e-7


def test_angle_sum_jacobian_on_ngons():
    m = pentagon_mesh()
    r, _ = angle_sum(m, m.V)
    assert r.shape == (1,)  # the triangle gets no row
    assert r[0] < 0  # a skew pentagon has an angle sum below 3 pi
    assert fd_check(angle_sum, m, m.V) < 1e-7


def test_corner_angle_gradient_and_value():
    m = dome(noise=0.3)
    phi, cols, vals = corner_angle_gradients(m.topology, m.V)
    from optimize.mesh.measures import corner_angles
    assert np.allclose(phi, corner_angles(m), atol=1e-14)
    assert cols.shape == vals.shape == (len(phi), 9)
    # each angle is invariant under translating its three points together
    assert np.abs(vals.reshape(-1, 3, 3).sum(axis=1)).max() < 1e-12


def test_det_combined_gradient():
    Q = RNG.standard_normal((6, 4, 3))
    D, G = det_combined_local(Q)
    d = RNG.standard_normal(Q.shape)
    eps = 1e-6
    fd = (det_combined_local(Q + eps * d)[0] - det_combined_local(Q - eps * d)[0]) / (2 * eps)
    assert np.abs(fd - np.einsum("qa,qa->q", G, d.reshape(6, 12))).max() < 1e-8


@pytest.mark.parametrize("fn", [angle_sum, angle_balance, circular_angles, det_constraints])
def test_zero_on_surface_of_revolution(fn):
    """Surfaces of revolution are PQ, conical and circular by construction."""
    r, _ = fn(dome(), dome().V)
    assert r.size and np.abs(r).max() < 1e-12


def test_zero_on_translational_net():
    t = np.linspace(0, 1, 5)
    a = np.stack([t, 0 * t, np.sin(2 * t)], axis=1)
    b = np.stack([0 * t, t, 0.5 * t ** 2], axis=1)
    m = shapes.translational(a, b)
    assert np.abs(angle_sum(m, m.V)[0]).max() < 1e-12
    assert np.abs(det_constraints(m, m.V)[0]).max() < 1e-12


@pytest.mark.parametrize("fn", [angle_sum, angle_balance, circular_angles, det_constraints])
def test_invariant_under_rigid_motion_and_scale(fn):
    m = dome(noise=0.2)
    Q, _ = np.linalg.qr(RNG.standard_normal((3, 3)))
    V2 = 3.7 * m.V @ Q.T + np.array([10.0, -4.0, 2.0])
    assert np.allclose(fn(m, m.V)[0], fn(m, V2)[0], atol=1e-11)


def test_system_matches_blocks_with_fixed_columns_and_weights():
    m = dome(noise=0.2)
    p = Problem(m, "conical", fixed="boundary", mu=0.25)
    x = p.x0()
    c, A, blocks = p.constraints(x)
    V = x.reshape(-1, 3)
    J = sp.vstack([angle_sum(m, V)[1], angle_balance(m, V)[1], det_constraints(m, V)[1]]).tocsr()
    assert np.allclose(A.toarray(), J[:, p.free].toarray(), atol=1e-12)
    cw, Aw, _ = p.constraints(x, weighted=True)
    assert np.allclose(cw[blocks["det"]], 0.5 * c[blocks["det"]])
    assert np.allclose(Aw[blocks["det"]].toarray(), 0.5 * A[blocks["det"]].toarray())
    assert np.allclose(p.constraints(x, jac=False), c)


def test_constraint_curvature_matches_finite_differences():
    m = dome(noise=0.2)
    p = Problem(m, "circular", mu=1.0)
    x = p.x0()
    for sqp_rows in (False, True):
        c, A, blocks = p.constraints(x, sqp=sqp_rows)
        terms = p.sqp_terms if sqp_rows else p.terms
        y = RNG.standard_normal(len(c))
        H = constraint_curvature(m, terms, x.reshape(-1, 3), y, blocks)
        assert abs(H - H.T).max() < 1e-9
        d = RNG.standard_normal(len(x))
        eps = 1e-6
        fd = (p.constraints(x + eps * d, sqp=sqp_rows)[1].T @ y
              - p.constraints(x - eps * d, sqp=sqp_rows)[1].T @ y) / (2 * eps)
        assert np.abs(fd - H @ d).max() < 1e-6 * np.abs(fd).max()


def test_kkt_assembly_matches_finite_differences():
    """The KKT matrix: H block = derivative of the objective gradient, A block = dc/dx."""
    m = dome(noise=0.1)
    ref = dome()
    p = Problem(m, "conical", reference=ref, fixed="corners", fairness=1e-2, closeness=0.5, mu=1.0)
    x = p.x0()
    foot = p.footpoints(x)  # the tangent-plane model: footpoints fixed
    f, g, H = objective(p, x, p.w_fair, p.w_close, foot=foot)
    c, A, _ = p.constraints(x, sqp=True)
    M = kkt_matrix(H, A, delta=0.0, eps=0.0).toarray()
    k = len(g)
    d = RNG.standard_normal(k)
    eps = 1e-6
    xp, xm = p.step(x, d, eps), p.step(x, d, -eps)
    g_fd = (objective(p, xp, p.w_fair, p.w_close, foot=foot)[1]
            - objective(p, xm, p.w_fair, p.w_close, foot=foot)[1]) / (2 * eps)
    c_fd = (p.constraints(xp, jac=False, sqp=True) - p.constraints(xm, jac=False, sqp=True)) / (2 * eps)
    assert np.abs(M[:k, :k] @ d - g_fd).max() < 1e-7 * max(1.0, np.abs(g_fd).max())
    assert np.abs(M[k:, :k] @ d - c_fd).max() < 1e-7 * max(1.0, np.abs(c_fd).max())
    assert np.allclose(M[:k, k:], M[k:, :k].T)
    f_fd = (objective(p, xp, p.w_fair, p.w_close, False, foot)
            - objective(p, xm, p.w_fair, p.w_close, False, foot)) / (2 * eps)
    assert abs(f_fd - g @ d) < 1e-7 * max(1.0, abs(f_fd))
