"""The two linear systems of the paper's methods in banded form, laid out once per run.

- :class:`GramBand`: the penalty method's Gauss-Newton matrix
  ``J^T J = A^T A + w1 K^T K + w2 C^T C`` (constraint rows ``A``, fairness
  ``K``, closeness ``C``) as a lower band for banded Cholesky.
- :class:`KKTBand`: SQP's KKT matrix ``[[H + delta I, A^T], [A, -eps I]]``
  with ``H = 2 (w1 K^T K + w2 C^T C)`` (plus, for the exact Hessian, the
  constraint curvature, whose pattern lies inside ``A^T A``'s) in ``dgbtrf``
  storage, unknowns ``(s (k,), dy (r,))``.

Both take the values the solvers already have on fixed patterns: the
constraint Jacobian's CSR data (:attr:`optimize.solvers.paper.system.ConstraintSystem.pattern`)
and the objective Hessian's data (:meth:`optimize.solvers.paper.problem.Problem.hessian_data`,
pattern :attr:`~optimize.solvers.paper.problem.Problem.hpat`).  :func:`gram_band` and
:func:`kkt_band` return None when the band would be too wide (see
:func:`optimize.linalg.banded.band_order`); the solvers then use their sparse path.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ... import kernels
from ...linalg.banded import (
    BandLU,
    BandOrder,
    RowGram,
    band_array,
    band_order,
    general_positions,
    lower_positions,
)


def _clique_pattern(indptr: np.ndarray, indices: np.ndarray, k: int) -> sp.coo_matrix:
    """(k, k) pattern of ``A^T A`` for a CSR pattern ``A`` (every row's columns pairwise coupled)."""
    A = sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(len(indptr) - 1, k))
    return (A.T @ A).tocoo()


class GramBand:
    """Lower band of ``A^T A + H`` for the constraint pattern ``(indptr, indices)`` and ``H`` on ``hpat``.

    order : the :class:`BandOrder` of that pattern.  problem : the
    :class:`optimize.solvers.paper.problem.Problem` whose objective Hessian
    ``w1 K^T K + w2 C^T C`` :meth:`assemble_objective` adds (optional).
    """

    def __init__(self, order: BandOrder, indptr: np.ndarray, indices: np.ndarray, hpat, problem=None):
        self.order = order
        self.gram = RowGram(indptr, indices, order)
        self.h_dest, self.h_low = lower_positions(order, hpat.rows, hpat.indices)
        self.dest = np.concatenate([self.gram.dest, self.h_dest])
        self.size = (order.bw + 1) * order.n
        self._plans = None
        self.problem = problem
        if problem is not None:  # K^T K in the band once, and where the closeness blocks land
            self.fair_band = np.zeros(self.size)
            self.fair_band[self.h_dest] = problem._h_fair[self.h_low]
            at = np.full(hpat.nnz, -1, dtype=np.int64)
            at[np.nonzero(self.h_low)[0]] = self.h_dest
            close = at[problem._h_close]  # (9 f,): -1 for the blocks' upper entries
            self.close_keep = np.nonzero(close >= 0)[0]
            self.close_dest = close[self.close_keep]

    def assemble_objective(self, a_data: np.ndarray, w1: float, w2: float, N: np.ndarray | None) -> np.ndarray:
        """:meth:`assemble` with ``H = w1 K^T K + w2 C^T C`` (closeness rows with unit normals
        ``N (n, 3)``; ``Problem.hessian_data``), without forming ``H`` on its pattern."""
        p = self.problem
        if kernels.get() is None:  # needs ``problem`` (given by gram_band)
            return self.assemble(a_data, p.hessian_data(w1, w2, N))
        out = w1 * self.fair_band
        if w2 > 0:
            Nf = N[p._cv]
            out[self.close_dest] += w2 * np.einsum("ia,ib->iab", Nf, Nf).ravel()[self.close_keep]
        k = kernels.get()
        if self._plans is None:
            self._plans = self.gram.plans()
        a = np.ascontiguousarray(a_data, dtype=np.float64)
        for plan in self._plans:
            k.group_gram(a, *plan, out)
        return band_array(out, self.order.bw + 1)

    def assemble(self, a_data: np.ndarray, h_data: np.ndarray) -> np.ndarray:
        """(bw + 1, k) float, Fortran-ordered: the ordered lower band of ``A^T A + H``."""
        k = kernels.get()
        if k is not None:  # the same sums, compiled: one pass over the groups of rows
            if self._plans is None:
                self._plans = self.gram.plans()
            out = np.zeros(self.size)
            out[self.h_dest] = h_data[self.h_low]  # distinct positions: H is stored as CSR
            a = np.ascontiguousarray(a_data, dtype=np.float64)
            for plan in self._plans:
                k.group_gram(a, *plan, out)
            return band_array(out, self.order.bw + 1)
        vals = np.concatenate(self.gram.values(a_data) + [h_data[self.h_low]])
        return band_array(np.bincount(self.dest, weights=vals, minlength=self.size), self.order.bw + 1)


def gram_band(p, system) -> GramBand | None:
    """The :class:`GramBand` of Problem ``p``'s constraint ``system``, or None when not banded."""
    P = system.pattern
    k = P.shape[1]
    G = _clique_pattern(P.indptr, P.indices, k)
    order = band_order(np.concatenate([G.row, p.hpat.rows]), np.concatenate([G.col, p.hpat.indices]), k,
                       keys=p.unknown_levels())
    return None if order is None else GramBand(order, P.indptr, P.indices, p.hpat, p)


class KKTBand:
    """``dgbtrf`` storage of ``[[H + delta I, A^T], [A, -eps I]]`` for fixed patterns (``order`` of the whole)."""

    def __init__(self, order: BandOrder, indptr: np.ndarray, indices: np.ndarray, hpat):
        self.order = order
        k, r = hpat.shape[0], len(indptr) - 1
        self.k, self.r = k, r
        rows = k + np.repeat(np.arange(r), np.diff(indptr))
        self.pos_h = general_positions(order, hpat.rows, hpat.indices)
        self.pos_a = general_positions(order, rows, indices)
        self.pos_at = general_positions(order, indices, rows)
        self.pos_top = general_positions(order, np.arange(k), np.arange(k))
        self.pos_bottom = general_positions(order, k + np.arange(r), k + np.arange(r))
        self.col_h, self.col_a, self.row_a = hpat.indices, indices, rows  # for |M|_1
        self.rows = 3 * order.bw + 1
        # the same entries in a lower band (n, bw + 1), C order, for the compiled L D L^T
        w = order.bw + 1

        def lower(r, c):
            i, j = order.inv[r], order.inv[c]
            return np.minimum(i, j) * w + np.abs(i - j)
        self.low_h = lower(hpat.rows, hpat.indices)
        keep = order.inv[hpat.rows] >= order.inv[hpat.indices]  # H is symmetric: one of each pair
        self.low_h_keep = np.nonzero(keep)[0]
        self.low_h = self.low_h[self.low_h_keep]
        self.low_a = lower(rows, indices)
        self.low_top = lower(np.arange(k), np.arange(k))
        self.low_bottom = lower(k + np.arange(r), k + np.arange(r))

    def factor(self, h_data: np.ndarray, a_data: np.ndarray, delta: float, eps: float,
               extra: sp.spmatrix | None = None) -> "BandKKT | None":
        """Factor the KKT matrix; ``extra (k, k)`` is added to ``H`` (the exact Hessian's curvature).

        Returns None when ``extra`` reaches outside the band.
        """
        n = self.order.n
        if extra is None and kernels.get() is not None:
            return BandKKT(None, self.order, self._norm1(h_data, a_data, delta, eps),
                           lower=self._lower(h_data, a_data, delta, eps), refill=(self, h_data, a_data, delta, eps))
        ab = np.zeros(self.rows * n)
        ab[self.pos_h] = h_data
        ab[self.pos_top] += delta
        ab[self.pos_a] = a_data
        ab[self.pos_at] = a_data
        ab[self.pos_bottom] = -eps
        band = band_array(ab, self.rows)
        if extra is None:
            norm1 = self._norm1(h_data, a_data, delta, eps)
        else:
            E = sp.coo_matrix(extra)
            try:
                pos = general_positions(self.order, E.row, E.col)
            except ValueError:
                return None
            np.add.at(ab, pos, E.data)
            norm1 = np.abs(band[self.order.bw:]).sum(axis=0).max(initial=0.0)
        return BandKKT(band, self.order, norm1)

    def _norm1(self, h_data, a_data, delta, eps) -> float:
        """``|M|_1`` (largest column sum of ``|M|``) from the entries, which occupy distinct
        positions; ``H``'s diagonal and ``delta`` are >= 0 (``H`` is positive semidefinite)."""
        n = self.order.n
        colsum = np.bincount(self.col_h, weights=np.abs(h_data), minlength=n)
        colsum[:self.k] += abs(delta) + np.bincount(self.col_a, weights=np.abs(a_data), minlength=self.k)
        colsum[self.k:] += abs(eps)
        colsum += np.bincount(self.row_a, weights=np.abs(a_data), minlength=n)
        return float(colsum.max(initial=0.0))

    def _lower(self, h_data, a_data, delta, eps) -> np.ndarray:
        """(n, bw + 1) float, C order: the KKT matrix's lower band, ``L[j, d] = M[j + d, j]``."""
        out = np.zeros(self.order.n * (self.order.bw + 1))
        out[self.low_h] = h_data[self.low_h_keep]
        out[self.low_top] += delta
        out[self.low_a] = a_data
        out[self.low_bottom] = -eps
        return out.reshape(self.order.n, self.order.bw + 1)


class BandKKT:
    """Solvers of a banded KKT matrix in ``dgbtrf`` storage ``band (3 bw + 1, n)``, cheapest first.

    With the kernels, :meth:`KKTBand.factor` passes the lower band directly
    (``lower``) and ``band`` is built only if the LU is asked for.

    :meth:`solvers` yields ``L D L^T`` without pivoting of its lower band
    (compiled, :mod:`optimize.kernels`; the matrix is symmetric
    quasi-definite, so such a factorization exists, though it is not always
    accurate), then LAPACK's banded LU with partial pivoting, factored only
    when it is asked for.  The caller checks each solution and takes the first
    good one.  ``norm1`` is ``|M|_1``, for the caller's conditioning test.
    """

    def __init__(self, band: np.ndarray | None, order: BandOrder, norm1: float, lower=None, refill=None):
        self.band, self.order, self.norm1 = band, order, float(norm1)
        self._ldl = self._lu = None
        self._refill = refill  # (KKTBand, its factor arguments): builds ``band`` when the LU is needed
        k = kernels.get()
        if k is not None:
            L = np.ascontiguousarray(band[2 * order.bw:].T) if lower is None else lower  # L[j, d] = M[j + d, j]
            self._ldl = L if k.ldl_factor(L, False, order.ext) else None

    def solvers(self):
        """Functions ``b (n,) -> x (n,)`` in the original order, cheapest first."""
        if self._ldl is not None:
            k, perm = kernels.get(), self.order.perm

            def ldl(b):
                y = k.ldl_solve(self._ldl, np.ascontiguousarray(b[perm]), self.order.ext)
                x = np.empty_like(y)
                x[perm] = y
                return x
            yield ldl
        if self._lu is None:
            if self.band is None:
                kkt, *args = self._refill
                with kernels.disabled():
                    self.band = kkt.factor(*args).band
            self._lu = BandLU(self.band.copy(order="F"), self.order, self.norm1)
        if self._lu.ok:
            yield self._lu.solve


def kkt_band(p, system, exact: bool = False) -> KKTBand | None:
    """The :class:`KKTBand` of Problem ``p`` and SQP's constraint ``system``, or None when not banded.

    exact : the Hessian will carry the constraint curvature: its pattern (that
    of ``A^T A``) is included in the ordering.
    """
    P = system.pattern
    k, r = P.shape[1], P.shape[0]
    rows = k + np.repeat(np.arange(r), np.diff(P.indptr))
    R = [p.hpat.rows, rows]
    C = [p.hpat.indices, P.indices]
    if exact:
        G = _clique_pattern(P.indptr, P.indices, k)
        R.append(G.row)
        C.append(G.col)
    levels = p.unknown_levels()  # a constraint row goes just after the mean level of its vertices
    row_levels = np.bincount(rows - k, weights=levels[P.indices], minlength=r) / np.maximum(np.diff(P.indptr), 1)
    order = band_order(np.concatenate(R), np.concatenate(C), k + r, pivoting=True,
                       keys=np.concatenate([levels, row_levels + 0.25]))
    return None if order is None else KKTBand(order, P.indptr, P.indices, p.hpat)
