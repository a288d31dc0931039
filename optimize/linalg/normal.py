"""Sparse solves of the regularized Gauss-Newton systems.

Each iteration solves ``(J^T J + D + mu I) dx = -g``: a symmetric positive
definite matrix with the same sparsity pattern every iteration.  Backends:

- ``"auto"`` (default): ``"pardiso"`` where MKL is installed (x86-64),
  otherwise ``"superlu"``.
- ``"pardiso"``: sparse Cholesky by Intel MKL PARDISO (``optimize.linalg.pardiso``):
  METIS ordering and symbolic analysis done once per sparsity pattern and
  reused, only the numeric factorization repeats; 6-10x faster than SuperLU
  on these systems (10k-face conical system 0.63 s against 5.7 s).
- ``"superlu"``: SciPy's SuperLU in symmetric mode
  (``diag_pivot_thresh=0``, ``MMD_AT_PLUS_A`` ordering).
- ``"eliminate"``: per-face auxiliary unknowns (normals, circle centres)
  couple only within their face, so their diagonal blocks are small and
  independent; they are eliminated (batched dense inverses, Schur
  complement), the smaller system is factored with SuperLU and the
  eliminated unknowns recovered by back substitution.

Measured on 10k-face systems (one fresh factorization, shared 2-core
machine): PQ 60k unknowns cholespy 0.62 s, SuperLU 0.56 s, eliminate 0.51 s;
circular 100k: 0.89 / 0.53 / 0.40 s; conical 100k: 18.1 / 8.3 / 12.1 s (the
conical rows couple a whole vertex star: much more fill).  cholespy (CHOLMOD
with a reference BLAS), once a backend, was never faster than SuperLU (1-3x
slower) and is no longer offered.

SuperLU exposes no numeric-only refactorization (factoring its matrix permuted by a previous ``perm_c``
with the ``NATURAL`` ordering was measured 10x slower, the etree postorder
being lost).  What is reused across iterations instead is the whole factor:
a new system is first solved by conjugate gradients preconditioned with the
last factor (a few steps while the matrix changes little) and factored anew
only when that does not reach ``cg_rtol`` within a budget of steps (by
default about half the time of the last factorization, 10 to 200 steps).
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..options import LINEAR_SOLVERS
from .superlu import superlu

log = logging.getLogger(__name__)

BACKENDS = LINEAR_SOLVERS  # the settings' values (optimize.options), one list
SINGLE_FROM = 400_000
"""PARDISO factors systems of this many unknowns and more in single precision (a 70k-face PQ or
130k-face conical mesh): half the factor's memory (100k-face conical: 948 -> 474 MB), the numeric
phase ~1.2x faster; each solve is then refined in double by CG preconditioned with that factor
(one or two steps: relative residual 1e-7 -> 3e-11 in one on the 100k-face conical system)."""
SINGLE_RTOL, SINGLE_STEPS = 1e-10, 30


def resolve_backend(backend: str) -> str:
    """The backend ``"auto"`` stands for here: ``"pardiso"`` when MKL loads, else ``"superlu"``."""
    if backend != "auto":
        return backend
    from . import pardiso

    return "pardiso" if pardiso.available() else "superlu"


class SolveError(RuntimeError):
    """The factorization failed (matrix not positive definite or singular)."""


def _superlu_factor(A: sp.spmatrix):
    """A function ``b -> A^{-1} b`` from SuperLU in symmetric mode (:func:`optimize.linalg.superlu.superlu`)."""
    return superlu(A, symmetric=True).solve


@dataclass(frozen=True)
class Shifted:
    """``matrix + shift I`` without forming it: the damped Gauss-Newton matrix of one iteration,
    solved for several ``shift`` values (the damping) on one ``matrix`` (symmetric, CSR).

    :class:`NormalSolver` prepares ``matrix`` once (PARDISO: its upper triangle) and then
    only adds the shift to the diagonal; the same ``matrix`` object passed again is taken as
    unchanged, so it must not be modified in place between the solves."""

    matrix: sp.csr_matrix
    shift: float = 0.0

    def formed(self) -> sp.csr_matrix:
        """``matrix + shift I`` as a new CSR matrix (the backends without a shifted path)."""
        return (self.matrix + sp.diags(np.full(self.matrix.shape[0], float(self.shift)))).tocsr()

    def __matmul__(self, v: np.ndarray) -> np.ndarray:
        return self.matrix @ v + self.shift * v


class NormalSolver:
    """Solves ``A x = b`` for a sequence of SPD matrices ``A`` with one sparsity pattern.

    backend : one of :data:`BACKENDS`.
    blocks : (m, b) int or None
        For ``"eliminate"``: the unknowns forming independent diagonal blocks
        (``-1`` padded), e.g. each face's normal.
    reuse : try CG preconditioned by the last factor before factoring anew (default: yes,
        except with PARDISO, whose numeric refactorization is cheap).
    cg_rtol : relative residual the CG solve must reach (an inexact Gauss-Newton
        step; the solver's acceptance test guards the outer iteration).
    cg_maxiter : CG step budget; None = about half the last factorization time.
    """

    def __init__(self, backend: str = "auto", blocks: np.ndarray | None = None,
                 reuse: bool | None = None, cg_rtol: float = 1e-6, cg_maxiter: int | None = None):
        if backend not in BACKENDS:
            raise ValueError(f"linear solver backend {backend!r}, expected one of {BACKENDS}")
        backend = resolve_backend(backend)
        if backend == "eliminate" and blocks is None:
            backend = "superlu"
        self.backend = backend
        self._pardiso = None
        if reuse is None:  # PARDISO: a numeric refactorization costs only ~15 solves, CG rarely pays
            reuse = backend != "pardiso"
        self.blocks = blocks
        self._factor = None
        self.reuse = reuse
        self.cg_rtol, self.cg_maxiter = cg_rtol, cg_maxiter
        self._budget = 30  # CG steps worth trying before a refactorization (see solve)
        self.factorizations = 0
        self.cg_iterations = 0

    def solve(self, A: sp.spmatrix | Shifted, b: np.ndarray) -> np.ndarray:
        """``x (k,)`` with ``A (k, k) x = b (k,)``.  Raises :class:`SolveError` on failure.

        ``A`` may be a :class:`Shifted` matrix: PARDISO then factors ``matrix + shift I`` from
        the upper triangle it prepared for that ``matrix`` (no copy of the matrix per shift)."""
        if not isinstance(A, Shifted):
            A = Shifted(A)
        if self.reuse and self._factor is not None:
            x = self._preconditioned_cg(A, b)
            if x is not None:
                return x
        self.factorizations += 1
        t0 = time.perf_counter()
        x = None
        try:
            if self.backend == "pardiso":
                x = self._pardiso_solve(A, b)  # solved already when the factor is single precision
            elif self.backend == "superlu":
                self._factor = None  # the previous factor freed before the new one is made
                self._factor = _superlu_factor(A.formed())
            else:
                self._factor = None
                self._factor = self._eliminate_factor(A.formed())
            t1 = time.perf_counter()
            if x is None:
                x = self._factor(b)
            t2 = time.perf_counter()
        except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
            raise SolveError(f"sparse factorization failed ({self.backend}): {exc}") from exc
        if not np.all(np.isfinite(x)):
            raise SolveError(f"sparse solve ({self.backend}) returned non-finite values")
        # CG with the old factor is worth up to about half a new factorization
        self._budget = (self.cg_maxiter if self.cg_maxiter is not None else
                        int(np.clip((t1 - t0) / max(2 * (t2 - t1), 1e-6), 10, 200)))
        return x

    def _pardiso_solve(self, A: Shifted, b: np.ndarray) -> np.ndarray | None:
        """Factor ``A`` with PARDISO (``self._factor``); with a single-precision factor (systems
        of ``SINGLE_FROM`` unknowns and more) also solve, refined in double by CG to
        ``SINGLE_RTOL``, and return ``x``.  None: the caller solves with the factor.  A single
        factor that fails (not positive definite in float32) or whose CG does not converge is
        replaced by a double one for the rest of the run."""
        from .pardiso import PardisoCholesky

        if self._pardiso is None:
            self._pardiso = PardisoCholesky(single=A.matrix.shape[0] >= SINGLE_FROM)
        if self._pardiso.single:
            try:
                self._factor = self._pardiso.update(A.matrix, shift=A.shift)
                x = self._preconditioned_cg(A, b, SINGLE_RTOL, SINGLE_STEPS)
            except RuntimeError as exc:
                log.info("single-precision factor failed (%s): double precision from here", exc)
                x = None
            if x is not None:
                return x
            self._factor = None
            self._pardiso.close()
            self._pardiso = PardisoCholesky(single=False)
        self._factor = self._pardiso.update(A.matrix, shift=A.shift)
        return None

    def _preconditioned_cg(self, A, b, rtol: float | None = None, budget: int | None = None):
        """CG on ``A x = b`` (a :class:`Shifted`) preconditioned by the last factor, to the
        relative residual ``rtol`` (default ``cg_rtol``) within ``budget`` steps (default: the
        reuse budget); None if it does not converge."""
        M = self._factor
        rtol = self.cg_rtol if rtol is None else rtol
        budget = self._budget if budget is None else budget
        x = M(b)
        r = b - A @ x
        z = M(r)
        p = z.copy()
        rz = r @ z
        stop = rtol * np.linalg.norm(b)
        for k in range(budget):
            if np.linalg.norm(r) <= stop:
                self.cg_iterations += k
                return x
            Ap = A @ p
            alpha = rz / (p @ Ap)
            x += alpha * p
            r -= alpha * Ap
            z = M(r)
            rz, rz_old = r @ z, rz
            p = z + (rz / rz_old) * p
        if np.linalg.norm(r) <= stop:
            self.cg_iterations += budget
            return x
        return None

    def _eliminate_factor(self, A):
        A = A.tocsr()
        k = A.shape[0]
        B = self.blocks
        valid = B >= 0
        e_idx = B[valid]
        is_e = np.zeros(k, dtype=bool)
        is_e[e_idx] = True
        keep = np.nonzero(~is_e)[0]
        # dense diagonal blocks (m, w, w); padded slots get an identity
        m, w = B.shape
        Bi = np.where(valid, B, 0)
        rows = np.broadcast_to(Bi[:, :, None], (m, w, w)).ravel()
        cols = np.broadcast_to(Bi[:, None, :], (m, w, w)).ravel()
        D = np.asarray(A[rows, cols]).reshape(m, w, w)
        mask = valid[:, :, None] & valid[:, None, :]
        D = np.where(mask, D, 0.0) + np.where(~valid, 1.0, 0.0)[:, :, None] * np.eye(w)[None]
        Dinv = np.linalg.inv(D)
        # block-diagonal inverse as a sparse matrix in the local numbering of the eliminated set
        pos = np.full(k, -1, dtype=np.int64)
        pos[e_idx] = np.arange(len(e_idx))
        loc = np.where(valid, pos[Bi], -1)
        ok = (loc[:, :, None] >= 0) & (loc[:, None, :] >= 0)
        r_ = np.broadcast_to(loc[:, :, None], (m, w, w))[ok]
        c_ = np.broadcast_to(loc[:, None, :], (m, w, w))[ok]
        ne = len(e_idx)
        Einv = sp.csr_matrix((Dinv[ok], (r_, c_)), shape=(ne, ne))
        A_kk = A[keep][:, keep]
        A_ke = A[keep][:, e_idx]
        S = (A_kk - A_ke @ Einv @ A_ke.T).tocsr()
        inner = _superlu_factor(S)

        def apply(b):
            b_k, b_e = b[keep], b[e_idx]
            x_k = inner(b_k - A_ke @ (Einv @ b_e))
            x = np.empty(k)
            x[keep], x[e_idx] = x_k, Einv @ (b_e - A_ke.T @ x_k)
            return x

        return apply


def normal_matrix(J: sp.csr_matrix, mu: np.ndarray | float) -> sp.csr_matrix:
    """``J^T J + diag(mu)`` (CSR); ``mu`` scalar or ``(k,)``."""
    k = J.shape[1]
    return (J.T @ J + sp.diags(np.broadcast_to(mu, (k,)).astype(float))).tocsr()
