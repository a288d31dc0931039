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


def spd(n: int, seed: int, *, generator: bool = False) -> sp.csr_matrix:
    """A sparse SPD matrix ``(n, n)`` with a mesh-like pattern (banded plus random).  ``generator``: the
    random pattern drawn by NumPy's Generator, for large ``n`` (SciPy draws it from the legacy
    RandomState by shuffling all n^2 positions: about 30 s at n = 20000)."""
    rng = np.random.default_rng(seed)
    pattern_rng = np.random.default_rng([seed, 1]) if generator else seed
    B = sp.random(n, n, density=4.0 / n, random_state=pattern_rng) + sp.eye(n, k=1) * rng.normal()
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


def test_upper_triangle_is_read_from_the_csr_arrays_with_every_diagonal_stored():
    A = spd(400, 6)
    data, indptr, indices = pardiso.upper_triangle(A)
    U = sp.csr_matrix((data, indices, indptr), shape=A.shape)
    np.testing.assert_array_equal(U.toarray(), sp.triu(A).toarray())
    assert indptr.dtype == indices.dtype == np.int32
    np.testing.assert_array_equal(indices[indptr[:-1]], np.arange(400))  # the diagonal first in each row
    # a product's unsorted indices and duplicates, a row without its diagonal entry
    B = sp.csr_matrix((np.array([1.0, 2.0, 3.0, 4.0]), np.array([1, 0, 0, 1]), np.array([0, 2, 4])),
                      shape=(2, 2))
    assert not B.has_canonical_format
    data, indptr, indices = pardiso.upper_triangle(B)
    np.testing.assert_array_equal(sp.csr_matrix((data, indices, indptr), shape=(2, 2)).toarray(),
                                  [[2.0, 1.0], [0.0, 4.0]])
    C = sp.csr_matrix(np.array([[0.0, 1.0], [1.0, 2.0]]))
    C.eliminate_zeros()
    data, indptr, indices = pardiso.upper_triangle(C)
    np.testing.assert_array_equal(indices, [0, 1, 1])
    np.testing.assert_array_equal(data, [0.0, 1.0, 2.0])


def test_upper_triangle_needs_no_copy_of_the_whole_matrix_in_64_bit_indices():
    # SciPy's triu went through COO with 64-bit row and column arrays: about 2x the bytes of the
    # matrix on top of it (at a million faces several GiB); the mask keeps it under 0.9x
    import tracemalloc

    A = spd(20000, 7, generator=True)
    A.indices, A.indptr = A.indices.astype(np.int32), A.indptr.astype(np.int32)
    size = A.data.nbytes + A.indices.nbytes + A.indptr.nbytes
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    out = pardiso.upper_triangle(A)
    peak = tracemalloc.get_traced_memory()[1] - base
    tracemalloc.stop()
    assert peak < 1.0 * size, (peak, size)  # scipy.sparse.triu and the conversions: 1.6
    assert sum(a.nbytes for a in out) < 0.7 * size


def test_a_shifted_matrix_is_factored_without_preparing_it_again(mkl):
    A = spd(600, 8)
    b = np.cos(np.arange(600, dtype=float))
    f = mkl.PardisoCholesky()
    for shift in (1e-3, 1e-2, 10.0, 0.0):
        x = f.update(A, shift=shift).solve(b)
        np.testing.assert_allclose(A @ x + shift * x, b, atol=1e-9)
    assert f.analyses == 1
    held = f._arrays[0]
    f.update(A, shift=5.0)
    assert f._arrays[0] is held  # the same upper triangle, its diagonal shifted in place
    A2 = A * 3.0  # a new matrix of the same pattern: prepared anew, analysis kept
    x = f.update(A2, shift=5.0).solve(b)
    np.testing.assert_allclose(A2 @ x + 5.0 * x, b, atol=1e-9)
    assert f._arrays[0] is not held and f.analyses == 1


@pytest.mark.parametrize("backend", ["superlu", "auto"])
def test_normal_solver_solves_a_shifted_matrix(backend):
    A = spd(300, 9)
    b = np.linspace(-1.0, 1.0, 300)
    s = linalg.NormalSolver(backend)
    for mu in (1e-2, 1.0):
        x = s.solve(linalg.Shifted(A, mu), b)
        # the solver's contract: a direct solve, or CG from the last factor to the relative residual
        # cg_rtol; which one depends on how long the factorization took (the reuse budget), so the
        # bound is the contract's, not a direct solve's (this failed on a loaded machine at 1.2e-6)
        assert np.linalg.norm(A @ x + mu * x - b) <= s.cg_rtol * np.linalg.norm(b)


def test_normal_equations_are_the_sum_of_the_exact_and_majorized_products():
    from optimize.solvers.guided import normal_equations

    rng = np.random.default_rng(10)
    size = 60
    J = sp.random(40, size, density=0.1, random_state=11, format="csr")
    parts = [[sp.random(15, size, density=0.1, random_state=12 + k, format="csr") for k in range(2)],
             [sp.random(7, size, density=0.2, random_state=20 + k, format="csr") for k in range(3)]]
    r = rng.normal(size=40 + 15 + 7)
    free = np.setdiff1d(np.arange(size), [3, 17, 41])
    S = sp.csr_matrix((np.ones(len(free)), (free, np.arange(len(free)))), shape=(size, len(free)))
    want = J.T @ J
    for p in parts:
        want = want + len(p) * sum(Jk.T @ Jk for Jk in p)
    Jw = sp.vstack([sum(p[1:], p[0]) for p in parts])
    g_want = sp.vstack([J, Jw]).T @ r
    for sel in (None, S):
        M, g = normal_equations(J, parts, r, sel)
        T = sp.eye(size) if sel is None else S
        np.testing.assert_allclose(M.toarray(), (T.T @ want @ T).toarray(), atol=1e-12)
        np.testing.assert_allclose(g, T.T @ g_want, atol=1e-12)


def test_a_matrix_inside_the_analysed_pattern_is_factored_without_a_new_analysis(mkl):
    # rows that come and go (the guided solver's convexity hinges) or exact zeros a sparse
    # product dropped: the analysis of the wider pattern is kept, the missing entries are zeros
    A = spd(500, 13)
    wide = (A + 0.01 * (sp.eye(500, k=9) + sp.eye(500, k=-9))).tocsr()
    b = np.sin(np.arange(500.0))
    f = mkl.PardisoCholesky()
    f.update(wide)
    for M in (A, A * 2.0, wide):
        x = f.update(M, shift=0.5).solve(b)
        np.testing.assert_allclose(M @ x + 0.5 * x, b, atol=1e-9)
    assert f.analyses == 1 and f.embedded == 2
    grown = (A + 0.01 * (sp.eye(500, k=31) + sp.eye(500, k=-31))).tocsr()  # outside: analysed anew
    x = f.update(grown).solve(b)
    np.testing.assert_allclose(grown @ x, b, atol=1e-9)
    assert f.analyses == 2


def test_large_systems_are_factored_in_single_precision_and_refined_in_double(mkl, monkeypatch):
    from optimize.linalg import normal

    monkeypatch.setattr(normal, "SINGLE_FROM", 500)  # this 800-unknown system counts as large
    A = spd(800, 14)
    b = np.cos(np.arange(800.0))
    s = linalg.NormalSolver("pardiso")
    for mu in (1e-3, 1e-1):
        x = s.solve(linalg.Shifted(A, mu), b)
        assert np.linalg.norm(A @ x + mu * x - b) <= 1e-10 * np.linalg.norm(b)
    assert s._pardiso.single and s._pardiso.analyses == 1 and s.cg_iterations >= 1
    double = mkl.PardisoCholesky().update(A)
    assert s._pardiso.iparm[16] < 0.75 * double.iparm[16]  # the numeric phase's memory (KB)


def test_a_single_precision_factor_that_fails_is_replaced_by_a_double_one(mkl, monkeypatch):
    from optimize.linalg import normal

    monkeypatch.setattr(normal, "SINGLE_FROM", 2)
    # positive definite, but its Schur complement 1e-9 is lost in float32: not PD there
    A = sp.csr_matrix(np.array([[1.0, 1.0], [1.0, 1.0 + 1e-9]]))
    s = linalg.NormalSolver("pardiso")
    x = s.solve(A, np.array([1.0, 2.0]))
    np.testing.assert_allclose(A @ x, [1.0, 2.0], atol=1e-6)
    assert not s._pardiso.single
