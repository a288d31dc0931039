"""Sparse solves for the paper's methods, with a stated fallback for near-singular systems.

What we do about (near-)singular systems (the paper falls back to an SVD):

1. The systems are regularized so that they are non-singular in exact
   arithmetic: Levenberg-Marquardt damping ``lam * D`` in the penalty method,
   a proximal term ``delta I`` and a negative ``-eps I`` block (a symmetric
   quasi-definite KKT matrix) in SQP.
2. The matrix is factored by SuperLU.  If the factorization fails (exactly
   singular to working precision), the solution's relative residual exceeds
   ``1e-8``, or the solution is huge (``|x| |M|_1 > 1e12 |b|``: the matrix is
   near-singular), the system is solved instead by LSQR
   (``scipy.sparse.linalg.lsqr``, stopped at condition estimate ``1e12``): the
   minimum-norm least-squares solution that ignores directions below that
   relative singular value, the sparse counterpart of the paper's truncated
   SVD solve.  The caller learns which path was taken.
"""
from __future__ import annotations

import logging
import warnings

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.sparse.csgraph import reverse_cuthill_mckee

log = logging.getLogger(__name__)

RESIDUAL_TOL = 1e-8
COND_LIMIT = 1e12


class SPDSolver:
    """Repeated solves ``M x = b`` with symmetric positive definite ``M`` of a fixed pattern.

    The symbolic work is done on the first call and reused: a reverse
    Cuthill-McKee ordering; when it gives a narrow band (strips and other thin
    meshes: bandwidth ``<= 2 sqrt(n)``) every later matrix is factored by
    LAPACK's banded Cholesky (``scipy.linalg.solveh_banded``), otherwise by
    :func:`solve` (SuperLU, then the LSQR fallback).  A banded factorization
    that finds the matrix not positive definite also falls back to :func:`solve`.
    """

    def __init__(self):
        self.perm = None
        self.inv = None
        self.bandwidth = None
        self.calls = 0

    def _analyse(self, M: sp.csr_matrix) -> None:
        n = M.shape[0]
        self.perm = reverse_cuthill_mckee(M, symmetric_mode=True).astype(np.int64)
        self.inv = np.empty(n, dtype=np.int64)
        self.inv[self.perm] = np.arange(n)
        C = M.tocoo()
        bw = int(np.abs(self.inv[C.row] - self.inv[C.col]).max(initial=0))
        self.bandwidth = bw if bw <= 2 * np.sqrt(n) else None

    def solve(self, M: sp.spmatrix, b: np.ndarray) -> tuple[np.ndarray, str]:
        """``x (k,)`` and how it was solved (``"banded"``, ``"lu"`` or ``"lsqr"``)."""
        self.calls += 1
        M = sp.csr_matrix(M)
        M.sum_duplicates()
        if self.perm is None or len(self.perm) != M.shape[0]:
            self._analyse(M)
        if self.bandwidth is not None:
            C = M.tocoo()
            r, c = self.inv[C.row], self.inv[C.col]
            if np.abs(r - c).max(initial=0) > self.bandwidth:  # the pattern grew
                self._analyse(M)
                return self.solve(M, b)
            low = r >= c
            ab = np.zeros((self.bandwidth + 1, M.shape[0]))
            ab[(r - c)[low], c[low]] = C.data[low]
            try:
                y = la.solveh_banded(ab, b[self.perm], lower=True, check_finite=False)
                x = np.empty_like(y)
                x[self.perm] = y
                if np.all(np.isfinite(x)):
                    return x, "banded"
            except la.LinAlgError as exc:
                log.debug("banded Cholesky failed (%s); falling back", exc)
        return solve(M, b)


class Factor:
    """A factorization of a square sparse ``M (k, k)`` reused for several right-hand sides.

    SuperLU (symmetric mode and ordering for ``symmetric``, else COLAMD with
    partial pivoting).  :meth:`solve` checks each solution (finite, relative
    residual <= 1e-8, not near-singular) and otherwise returns LSQR's.
    """

    def __init__(self, M: sp.spmatrix, *, symmetric: bool = True):
        self.M = sp.csc_matrix(M)
        if self.M.shape[0] != self.M.shape[1]:
            raise ValueError(f"Factor: matrix has shape {self.M.shape}, expected a square matrix")
        self.lu = None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", sla.MatrixRankWarning)
                opts = dict(SymmetricMode=True) if symmetric else {}
                self.lu = sla.splu(self.M, permc_spec="MMD_AT_PLUS_A" if symmetric else "COLAMD",
                                   diag_pivot_thresh=0.0 if symmetric else 1.0, options=opts)
        except (RuntimeError, sla.MatrixRankWarning) as exc:  # singular to working precision
            log.debug("sparse LU failed (%s); LSQR will be used", exc)
        self._norm1 = None

    def solve(self, b: np.ndarray) -> tuple[np.ndarray, str]:
        """``x (k,)`` with ``M x = b`` and ``"lu"`` or ``"lsqr"`` (the fallback)."""
        if b.shape[0] != self.M.shape[0]:
            raise ValueError(f"solve: matrix has shape {self.M.shape}, right-hand side {b.shape}; "
                             "expected a vector matching the matrix")
        bn = float(np.linalg.norm(b))
        if bn == 0.0:
            return np.zeros_like(b), "lu"
        if self.lu is not None:
            x = self.lu.solve(b)
            if self._norm1 is None:
                self._norm1 = sla.norm(self.M, 1)
            if (np.all(np.isfinite(x)) and np.linalg.norm(self.M @ x - b) <= RESIDUAL_TOL * bn
                    and np.linalg.norm(x) * self._norm1 <= COND_LIMIT * bn):
                return x, "lu"
        return lstsq(self.M, b), "lsqr"


def solve(M: sp.spmatrix, b: np.ndarray, *, symmetric: bool = True) -> tuple[np.ndarray, str]:
    """Solve ``M x = b`` for a square sparse ``M (k, k)``, ``b (k,)``.

    Returns ``x (k,)`` and ``"lu"`` (direct) or ``"lsqr"`` (the minimum-norm
    least-squares fallback); see :class:`Factor`.
    """
    return Factor(M, symmetric=symmetric).solve(b)


def lstsq(M: sp.spmatrix, b: np.ndarray) -> np.ndarray:
    """(k,) float: minimum-norm least-squares solution of ``M x = b`` by LSQR (cond. limit 1e12)."""
    out = sla.lsqr(M, b, atol=1e-14, btol=1e-14, conlim=COND_LIMIT, iter_lim=20 * max(M.shape))
    return out[0]
