"""The MKL PARDISO Cholesky wrapper against SciPy's direct solver.

MKL ships for x86-64 only; where it cannot be loaded the tests of the wrapper
fail with the reason unless the machine is not x86-64 (then ``auto`` falls
back to SuperLU, which the last test checks).
"""
from __future__ import annotations

import platform

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from optimize import linalg
from optimize.linalg import pardiso

X86 = platform.machine().lower() in ("x86_64", "amd64")


@pytest.fixture
def mkl():
    if not pardiso.available():
        if X86:
            pytest.fail("MKL PARDISO did not load on x86-64: " + pardiso._LIB_ERROR, pytrace=False)
        pytest.skip("MKL is not available on " + platform.machine())
    return pardiso


def spd(n: int, seed: int) -> sp.csr_matrix:
    """A sparse SPD matrix ``(n, n)`` with a mesh-like pattern (banded plus random)."""
    rng = np.random.default_rng(seed)
    B = sp.random(n, n, density=4.0 / n, random_state=seed) + sp.eye(n, k=1) * rng.normal()
    return (B @ B.T + 0.1 * sp.eye(n)).tocsr()


def test_factor_solves_like_scipy(mkl):
    A = spd(800, 1)
    b = np.random.default_rng(2).normal(size=800)
    f = mkl.PardisoCholesky().update(A)
    x = f.solve(b)
    np.testing.assert_allclose(x, spla.spsolve(A.tocsc(), b), rtol=1e-9, atol=1e-12)
    assert f.factor_nnz >= sp.triu(A).nnz


def test_analysis_is_reused_for_the_same_pattern_and_redone_for_a_new_one(mkl):
    A = spd(500, 3)
    b = np.ones(500)
    f = mkl.PardisoCholesky().update(A)
    A2 = A.copy()
    A2.data = A2.data * 2.0 + 0.0  # same pattern, new values
    x2 = f.update(A2).solve(b)
    assert f.analyses == 1
    np.testing.assert_allclose(A2 @ x2, b, atol=1e-9)
    A3 = (A + 0.01 * (sp.eye(500, k=7) + sp.eye(500, k=-7))).tocsr()  # new pattern, still SPD
    x3 = f.update(A3).solve(b)
    assert f.analyses == 2
    np.testing.assert_allclose(A3 @ x3, b, atol=1e-9)


def test_missing_diagonal_entries_are_stored(mkl):
    A = sp.csr_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
    x = mkl.PardisoCholesky().update(A).solve(np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(A @ x, [1.0, 2.0, 3.0], atol=1e-12)
    # a row with no diagonal entry at all: PARDISO needs it stored, the matrix is not PD
    B = sp.csr_matrix(np.array([[2.0, 1.0], [1.0, 0.0]]))
    B.eliminate_zeros()
    with pytest.raises(RuntimeError, match="not positive definite"):
        mkl.PardisoCholesky().update(B)


def test_bad_right_hand_side_shape_names_both_shapes(mkl):
    f = mkl.PardisoCholesky().update(spd(20, 4))
    with pytest.raises(ValueError, match=r"\(3,\).*\(20,\)"):
        f.solve(np.ones(3))


def test_normal_solver_auto_picks_pardiso_where_mkl_loads():
    s = linalg.NormalSolver("auto")
    assert s.backend == ("pardiso" if pardiso.available() else "superlu")
    A = spd(300, 5)
    b = np.arange(300, dtype=float)
    np.testing.assert_allclose(A @ s.solve(A, b), b, atol=1e-8)


def test_large_system_with_a_small_factor_refactors_and_solves(mkl):
    # more unknowns than pardiso.SMALL but a tiny factor: analysed once on every core, then again
    # on one thread (a numeric phase on fewer threads than its analysis crashed MKL)
    n = mkl.SMALL + 5000
    A = sp.diags([np.full(n - 1, -1.0), np.full(n, 4.0), np.full(n - 1, -1.0)], [-1, 0, 1], format="csr")
    f = mkl.PardisoCholesky().update(A)
    assert f.factor_nnz < mkl.SMALL_FACTOR and f.threads == 1 and f.analyses == 2
    b = np.sin(np.arange(n, dtype=float))
    for scale in (1.0, 2.0):
        x = f.update(A * scale).solve(b)
        np.testing.assert_allclose((A * scale) @ x, b, atol=1e-10)
    assert f.analyses == 2
