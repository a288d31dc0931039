"""Checked sparse solves, with a stated fallback for near-singular systems (the paper's methods).

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

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from .banded import BandOrder, band_array, band_order, cholesky_solve, lower_positions
from .superlu import superlu
from ..warnfilter import filtered

log = logging.getLogger(__name__)

RESIDUAL_TOL = 1e-8
COND_LIMIT = 1e12


class SPDSolver:
    """Repeated solves ``M x = b`` with symmetric positive definite ``M`` of a fixed pattern.

    The symbolic work is done on the first call and reused: the narrow-band
    ordering of :func:`optimize.linalg.banded.band_order` (reverse Cuthill-McKee;
    kept when the half-bandwidth is ``<= 2 sqrt(n)``: strips and other thin
    meshes); every later matrix is then factored inside that band by
    :func:`optimize.linalg.banded.cholesky_solve` (LAPACK's banded Cholesky, or
    the compiled ``L D L^T``), otherwise by :func:`solve` (SuperLU, then the LSQR
    fallback).  A banded factorization that finds the matrix not positive
    definite also falls back to :func:`solve`; a pattern that leaves the band's
    envelope is analysed anew.
    """

    def __init__(self):
        self.order: BandOrder | None = None
        self.n = None
        self.calls = 0

    @property
    def bandwidth(self) -> int | None:
        """The half-bandwidth of the banded path, None when the sparse path is used."""
        return None if self.order is None else self.order.bw

    def _analyse(self, C: sp.coo_matrix) -> None:
        self.n = C.shape[0]
        self.order = band_order(C.row, C.col, self.n, pivoting=True)  # pivoting: the plain 2 sqrt(n) rule

    def solve(self, M: sp.spmatrix, b: np.ndarray) -> tuple[np.ndarray, str]:
        """``x (k,)`` and how it was solved (``"banded"``, ``"lu"`` or ``"lsqr"``)."""
        self.calls += 1
        M = sp.csr_matrix(M)
        M.sum_duplicates()
        C = M.tocoo()
        if self.n != M.shape[0]:
            self._analyse(C)
        o = self.order
        if o is not None:
            i, j = o.inv[C.row], o.inv[C.col]
            low = i >= j
            if np.any((i - j)[low] > o.ext[j[low]]):  # the pattern grew out of the envelope
                self._analyse(C)
                return self.solve(M, b)
            pos, low = lower_positions(o, C.row, C.col)
            flat = np.zeros((o.bw + 1) * o.n)
            flat[pos] = C.data[low]
            x = cholesky_solve(band_array(flat, o.bw + 1), b, o)
            if x is not None:
                return x, "banded"
            log.debug("banded Cholesky failed (not positive definite); falling back")
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
            with filtered("error", sla.MatrixRankWarning):
                self.lu = superlu(self.M, symmetric=symmetric)
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
