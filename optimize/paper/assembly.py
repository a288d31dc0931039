"""The two linear systems of the paper's methods in banded form, laid out once per run.

- :class:`GramBand`: the penalty method's Gauss-Newton matrix
  ``J^T J = A^T A + w1 K^T K + w2 C^T C`` (constraint rows ``A``, fairness
  ``K``, closeness ``C``) as a lower band for banded Cholesky.
- :class:`KKTBand`: SQP's KKT matrix ``[[H + delta I, A^T], [A, -eps I]]``
  with ``H = 2 (w1 K^T K + w2 C^T C)`` (plus, for the exact Hessian, the
  constraint curvature, whose pattern lies inside ``A^T A``'s) in ``dgbtrf``
  storage, unknowns ``(s (k,), dy (r,))``.

Both take the values the solvers already have on fixed patterns: the
constraint Jacobian's CSR data (:attr:`optimize.paper.system.ConstraintSystem.pattern`)
and the objective Hessian's data (:meth:`optimize.paper.problem.Problem.hessian_data`,
pattern :attr:`~optimize.paper.problem.Problem.hpat`).  :func:`gram_band` and
:func:`kkt_band` return None when the band would be too wide (see
:func:`optimize.paper.banded.band_order`); the solvers then use their sparse path.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .banded import BandLU, BandOrder, RowGram, band_array, band_order, general_positions, lower_positions


def _clique_pattern(indptr: np.ndarray, indices: np.ndarray, k: int) -> sp.coo_matrix:
    """(k, k) pattern of ``A^T A`` for a CSR pattern ``A`` (every row's columns pairwise coupled)."""
    A = sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(len(indptr) - 1, k))
    return (A.T @ A).tocoo()


class GramBand:
    """Lower band of ``A^T A + H`` for the constraint pattern ``(indptr, indices)`` and ``H`` on ``hpat``.

    order : the :class:`BandOrder` of that pattern.
    """

    def __init__(self, order: BandOrder, indptr: np.ndarray, indices: np.ndarray, hpat):
        self.order = order
        self.gram = RowGram(indptr, indices, order)
        self.h_dest, self.h_low = lower_positions(order, hpat.rows, hpat.indices)
        self.dest = np.concatenate([self.gram.dest, self.h_dest])
        self.size = (order.bw + 1) * order.n

    def assemble(self, a_data: np.ndarray, h_data: np.ndarray) -> np.ndarray:
        """(bw + 1, k) float, Fortran-ordered: the ordered lower band of ``A^T A + H``."""
        vals = np.concatenate(self.gram.values(a_data) + [h_data[self.h_low]])
        return band_array(np.bincount(self.dest, weights=vals, minlength=self.size), self.order.bw + 1)


def gram_band(p, system) -> GramBand | None:
    """The :class:`GramBand` of Problem ``p``'s constraint ``system``, or None when not banded."""
    P = system.pattern
    k = P.shape[1]
    G = _clique_pattern(P.indptr, P.indices, k)
    order = band_order(np.concatenate([G.row, p.hpat.rows]), np.concatenate([G.col, p.hpat.indices]), k,
                       keys=p.unknown_levels())
    return None if order is None else GramBand(order, P.indptr, P.indices, p.hpat)


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

    def factor(self, h_data: np.ndarray, a_data: np.ndarray, delta: float, eps: float,
               extra: sp.spmatrix | None = None) -> BandLU | None:
        """Factor the KKT matrix; ``extra (k, k)`` is added to ``H`` (the exact Hessian's curvature).

        Returns None when ``extra`` reaches outside the band.
        """
        n = self.order.n
        ab = np.zeros(self.rows * n)
        ab[self.pos_h] = h_data
        ab[self.pos_top] += delta
        ab[self.pos_a] = a_data
        ab[self.pos_at] = a_data
        ab[self.pos_bottom] = -eps
        band = band_array(ab, self.rows)
        if extra is None:
            # |M|_1 (largest column sum of |M|) from the entries, which occupy distinct
            # positions; H's diagonal and delta are >= 0 (H is positive semidefinite)
            colsum = np.bincount(self.col_h, weights=np.abs(h_data), minlength=n)
            colsum[:self.k] += abs(delta) + np.bincount(self.col_a, weights=np.abs(a_data), minlength=self.k)
            colsum[self.k:] += abs(eps)
            colsum += np.bincount(self.row_a, weights=np.abs(a_data), minlength=n)
            norm1 = colsum.max(initial=0.0)
        else:
            E = sp.coo_matrix(extra)
            try:
                pos = general_positions(self.order, E.row, E.col)
            except ValueError:
                return None
            np.add.at(ab, pos, E.data)
            norm1 = np.abs(band[self.order.bw:]).sum(axis=0).max(initial=0.0)
        return BandLU(band, self.order, norm1)


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
