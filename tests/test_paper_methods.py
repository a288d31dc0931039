"""The paper's methods (penalty, SQP, hybrid): convergence, KKT conditions, purity, errors."""
import numpy as np
import pytest
import scipy.sparse as sp

from optimize.mesh import measures
from optimize.modelling import shapes
from optimize.errors import ConfigError, MeshError
from optimize.solvers.paper import run_paper_method
from optimize.linalg.spd import SPDSolver, solve
from optimize.solvers.paper.problem import Problem
from optimize.solvers.paper.sqp import kkt_matrix, kkt_residual, kkt_step, objective
from optimize.tolerances import Tolerances

TOL = Tolerances()


def perturbed_dome(amount=0.02, seed=1):
    """A surface of revolution with its interior perturbed; the boundary stays exact (and is fixed)."""
    m0 = shapes.revolution(shapes.dome_profile(k=6), 10)
    m = shapes.perturbed(m0, amount, seed=seed)
    V = m.V.copy()
    b = m0.topology.is_boundary_vertex
    V[b] = m0.V[b]
    return m0, m.with_vertices(V)


def skew_grid(n=3, amount=0.25, seed=0):
    """A few highly non-planar quads (the paper's Fig. 5 situation)."""
    m = shapes.grid(n, n, size=(n - 1.0, n - 1.0))
    V = m.V.copy()
    V[:, 2] += amount * np.random.default_rng(seed).standard_normal(len(V))
    return m.with_vertices(V)


def assert_defects(res, target, mesh):
    """The result meets the tolerances, keeps the input's faces ``mesh.F`` and is finite."""
    V = res.mesh.V
    assert measures.planarity(res.mesh).max() <= TOL.planarity
    if target == "conical":
        assert measures.conical_defect(res.mesh).max() <= TOL.conical
    if target == "circular":
        assert measures.circular_defect(res.mesh).max() <= TOL.circular
    assert np.array_equal(res.mesh.F, mesh.F) and np.all(np.isfinite(V))


CASES = [("penalty", "pq", {}), ("penalty", "conical", {"mu": 1.0}), ("penalty", "circular", {"mu": 1.0}),
         ("sqp", "pq", {}), ("sqp", "conical", {}), ("sqp", "circular", {}),
         ("hybrid", "pq", {}), ("hybrid", "conical", {}), ("hybrid", "circular", {})]


FOLDS = {("penalty", "pq"), ("sqp", "pq")}  # they pull the top ring's quads over the opening (normals reversed)


@pytest.mark.parametrize("method,target,extra", CASES)
def test_reaches_tolerance_on_perturbed_surface_of_revolution(method, target, extra):
    m0, m = perturbed_dome()
    res = run_paper_method(m, target, method, fixed="boundary", **extra)
    folded = measures.folded_faces(m, res.mesh.V)
    assert res.defects["folded"]["count"] == folded.sum()
    if (method, target) in FOLDS:  # the tolerances are met, but the result is not cuttable: said so
        assert folded.any() and res.status == "folded" and not res.success, res.message
    else:
        assert res.success and not folded.any(), res.message
        assert res.status == "converged"
    assert res.method == method and res.target == target
    assert_defects(res, target, m)
    assert res.max_distance < 0.02  # stays near the input surface (relative to its bbox diagonal)
    assert (res.multipliers is None) == (method == "penalty")
    if target == "conical":
        assert res.axes.shape == (m.n_vertices, 3) and np.allclose(np.linalg.norm(res.axes, axis=1), 1)


def test_penalty_angle_sum_alone_on_pq_halves_weights():
    _, m = perturbed_dome(0.05)
    res = run_paper_method(m, "pq", "penalty", fixed="boundary")
    # planar, but face 39 turned over: folded, no success (the default method keeps faces convex).
    # In the model's axes its per-coordinate damping shrank edges of faces 4, 9, 14 instead (degenerate);
    # it now solves in the input's canonical frame (optimize.solvers.paper.frame), which moves with it
    assert not res.missed() and res.status == "folded", res.message
    assert res.defects["folded"]["faces"] == [39]
    w = [h["w_fair"] for h in res.history]
    assert np.allclose(w[1:], np.array(w[:-1]) / 2)
    assert all(h["phase"] == "penalty" for h in res.history)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("method", ["penalty", "sqp", "hybrid"])
def test_highly_non_planar_quads_without_closeness(method, seed):
    m = skew_grid(seed=seed)
    assert measures.planarity(m).max() > 0.1
    res = run_paper_method(m, "pq", method, closeness=0.0, fairness=1e-3, fixed="corners", max_iter=300)
    assert res.success, res.message
    assert measures.planarity(res.mesh).max() <= TOL.planarity
    ang = measures.corner_angles(res.mesh).reshape(-1, 4)
    assert np.all(ang < np.pi - 1e-3)  # convex quads: the angle sum criterion keeps them so
    assert np.allclose(ang.sum(axis=1), 2 * np.pi, atol=1e-5)


def test_inputs_not_mutated_and_fixed_vertices_exact():
    _, m = perturbed_dome()
    V0, F0 = m.V.copy(), m.F.copy()
    fixed = np.array([0, 7, 20])
    for method in ("penalty", "sqp"):
        res = run_paper_method(m, "pq", method, fixed=fixed, max_iter=5)
        assert np.array_equal(m.V, V0) and np.array_equal(m.F, F0)
        assert np.array_equal(res.mesh.V[fixed], V0[fixed])
        assert res.nit <= 5 and len(res.history) == res.nit


def test_sqp_multipliers_satisfy_kkt_at_solution():
    m = skew_grid(4, 0.3)
    kw = dict(fixed="corners", fairness=1e-2, closeness=0.0)
    res = run_paper_method(m, "pq", "sqp", max_iter=400, kkt_tol=1e-8, kkt_patience=400,
                           hessian="exact", **kw)
    assert res.success, res.message
    p = Problem(m, "pq", mu=1.0, **kw)
    x = p.scaled(res.mesh.V).ravel()
    y = res.multipliers
    assert y.shape == (p.constraints(x, sqp=True)[0].size,)
    k = kkt_residual(p, x, y)
    assert k["gradient"] > 1e-3  # the fairness pulls: the multipliers carry real load
    assert k["stationarity"] <= 1e-6 * max(1.0, k["gradient"])
    assert k["feasibility"] <= 1e-9
    assert np.abs(kkt_residual(p, x, 0 * y)["stationarity"]) > 1e-3  # and they are needed


def test_near_singular_systems_fall_back_to_least_squares():
    A = sp.csr_matrix(np.array([[2.0, 1, 0], [1, 2, 0], [0, 0, 0]]))
    b = np.array([1.0, 2, 3])
    x, how = solve(A, b)
    assert how == "lsqr" and np.allclose(x, np.linalg.pinv(A.toarray()) @ b, atol=1e-10)
    A2 = sp.csr_matrix(np.array([[2.0, 1, 0], [1, 2, 0], [0, 0, 1e-17]]))
    x2, how2 = solve(A2, b)
    assert how2 == "lsqr" and np.all(np.isfinite(x2)) and np.abs(x2).max() < 10


def test_banded_cholesky_matches_sparse_lu():
    from optimize.modelling.designs import trefoil_band_mesh as trefoil_band
    m = trefoil_band(60, 0.4)
    p = Problem(m, "strip")
    c, A, _ = p.constraints(p.x0())
    M = (A.T @ A + 1e-3 * sp.identity(A.shape[1])).tocsr()
    b = np.random.default_rng(0).standard_normal(M.shape[0])
    solver = SPDSolver()
    x, how = solver.solve(M, b)
    assert how == "banded" and solver.bandwidth is not None
    assert np.allclose(x, solve(M, b)[0], atol=1e-9)


def test_kkt_step_with_redundant_and_degenerate_rows():
    """All four determinants and the angle sums as constraints at a planar mesh (rank deficient)."""
    m = shapes.revolution(shapes.dome_profile(k=4), 6)
    p = Problem(m, "pq", mu=1.0, fairness=1e-3, closeness=1.0)
    x = p.x0()
    f, g, H = objective(p, x, p.w_fair, p.w_close)
    c, A, _ = p.constraints(x)  # penalty rows: angle sums (zero gradient here) and 4 dets per quad
    y = np.zeros(len(c))
    s, dy, how = kkt_step(H, A, g, c, y, delta=1e-10, eps=1e-8)
    assert np.all(np.isfinite(s)) and np.all(np.isfinite(dy))
    sol = np.concatenate([s, dy])
    M = kkt_matrix(H, A, 1e-10, 1e-8)
    assert np.abs(M @ sol + np.concatenate([g, c])).max() < 1e-10


def test_errors_name_the_value():
    _, m = perturbed_dome()
    with pytest.raises(ConfigError, match="newton"):
        run_paper_method(m, "pq", "newton")
    with pytest.raises(ConfigError, match="switch"):
        run_paper_method(m, "pq", "sqp", switch=3)
    with pytest.raises(ConfigError, match="glide_boundary"):
        run_paper_method(m, "pq", "penalty", glide_boundary=True)
    with pytest.raises(ConfigError, match="hessian"):
        run_paper_method(m, "pq", "sqp", hessian="bfgs")
    with pytest.raises(ConfigError, match="target"):
        run_paper_method(m, "minimal", "penalty")
    with pytest.raises(MeshError, match="strip"):
        run_paper_method(m, "strip", "penalty")


def test_dispatch_from_optimize_mesh():
    from optimize.api import optimize_mesh
    _, m = perturbed_dome()
    res = optimize_mesh(m, "pq", method="penalty", fixed="boundary", max_iter=3)
    assert res.method == "penalty" and res.nit == 3
