"""Banded storage for the paper's linear systems: one ordering per run, values refilled per iteration.

A strip (one row of quads) couples each vertex only with its neighbours a
few quads away, so suitably ordered its Gauss-Newton matrix and its KKT
matrix are narrow bands (the 336-quad trefoil band: 2016 unknowns,
half-bandwidth 30 by reverse Cuthill-McKee; KKT 2352 unknowns, 28 when
ordered by the distance along the mesh, 38 by reverse Cuthill-McKee).
LAPACK factors such a band in ``O(n b^2)``: the positive definite normal
equations of the penalty method by banded Cholesky (``dpbtrf``), SQP's
indefinite KKT system by banded LU with partial pivoting (``dgbtrf``, the
pivoting SuperLU would do).

The sparsity pattern never changes during a run, so everything symbolic is
done once: the ordering, the bandwidth, and for every value the solver
produces (a Jacobian's CSR data, the objective Hessian's data) the flat
position it lands on in the band array.  An iteration then refills the band
with one ``np.bincount`` or fancy assignment.  ``A^T A`` of a Jacobian is
formed per *row group* (rows with the same columns, e.g. a quad's angle sum
and its four determinants) by one batched ``matmul``.

With the compiled kernels (:mod:`optimize.kernels`) both systems are
factored instead by an ``L D L^T`` without pivoting that works only inside
the band's envelope (:attr:`BandOrder.ext`: the columns' lengths below the
diagonal; a third less work than the full band on the trefoil band), with
LAPACK's LU as the fallback for the KKT system.

:func:`band_order` decides whether a band pays off (``b <= 2 sqrt(n)``, or,
for Cholesky, the factorization costs under ``BAND_FLOPS``); otherwise the
callers keep their sparse (SuperLU) path.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .. import kernels

BAND_FLOPS = 4e6  # n b^2 below this: a band is cheaper than a sparse factorization anyway


class BandOrder:
    """A symmetric permutation ``perm (n,)`` (``inv`` its inverse) and the half-bandwidth ``bw``.

    ``ext (n,)`` int: the envelope, column ``j`` (ordered) has no entry below row
    ``j + ext[j]``, nor has its ``L D L^T`` or Cholesky factor (fill stays inside the
    envelope: rows keep their first entry); ``bw`` for every column unless
    :meth:`set_envelope` was given the pattern.
    """

    def __init__(self, perm: np.ndarray, bw: int):
        self.perm = perm.astype(np.int64)
        self.inv = np.empty_like(self.perm)
        self.inv[self.perm] = np.arange(len(perm))
        self.n, self.bw = len(perm), int(bw)
        self.ext = np.full(self.n, self.bw, dtype=np.int64)

    def set_envelope(self, rows: np.ndarray, cols: np.ndarray) -> None:
        """Compute :attr:`ext` from the symmetric pattern ``(rows, cols)`` (original indices)."""
        i, j = self.inv[rows], self.inv[cols]
        low = i >= j
        first = np.arange(self.n)  # first column of every row, the diagonal at the latest
        np.minimum.at(first, i[low], j[low])
        last = np.arange(self.n)  # the last row whose first column is at or before column j
        np.maximum.at(last, first, np.arange(self.n))
        last = np.maximum.accumulate(last)
        self.ext = np.minimum(last - np.arange(self.n), self.bw).astype(np.int64)


def band_order(rows: np.ndarray, cols: np.ndarray, n: int, pivoting: bool = False,
               keys: np.ndarray | None = None) -> BandOrder | None:
    """A narrow-band ordering of the symmetric pattern ``(rows, cols)`` of an ``(n, n)`` matrix.

    The reverse Cuthill-McKee ordering, or the order of ``keys (n,)`` (e.g. a
    mesh distance; ties keep the index order) when that gives a smaller bandwidth.
    Returns None when the band is too wide to pay off: ``bw > 2 sqrt(n)`` and,
    for a Cholesky factorization (not ``pivoting``), ``n (bw + 1)^2 > BAND_FLOPS``.
    An LU with partial pivoting gets no such allowance: on a band that is
    nearly the whole matrix, row exchanges spread tiny fill values whose
    products underflow to subnormal numbers, which made ``dgbtrf`` some 50
    times slower than SuperLU on the small meshes of the tests.
    """
    rows, cols = np.asarray(rows).ravel(), np.asarray(cols).ravel()
    S = sp.csr_matrix((np.ones(len(rows) + n), (np.append(rows, np.arange(n)), np.append(cols, np.arange(n)))),
                      shape=(n, n))
    S = (S + S.T).tocoo()
    best = None
    perms = [reverse_cuthill_mckee(S.tocsr(), symmetric_mode=True)]
    if keys is not None:
        perms.append(np.argsort(keys, kind="stable"))
    for perm in perms:
        order = BandOrder(perm, 0)
        order.bw = int(np.abs(order.inv[S.row] - order.inv[S.col]).max(initial=0))
        if best is None or order.bw < best.bw:
            best = order
    if best.bw > 2 * np.sqrt(n) and (pivoting or n * (best.bw + 1) ** 2 > BAND_FLOPS):
        return None
    best.set_envelope(S.row, S.col)
    return best


# -- symmetric positive definite: lower band storage (dpbtrf) ---------------------------------
# Band arrays are Fortran-ordered (LAPACK's layout, so nothing is copied): a flat
# position ``j * rows + d`` is row ``d`` of column ``j``; :func:`band_array` views it.

def band_array(flat: np.ndarray, rows: int) -> np.ndarray:
    """(rows, n) Fortran-ordered view of a flat band of ``rows * n`` values (column after column)."""
    return flat.reshape(-1, rows).T


def lower_positions(order: BandOrder, rows: np.ndarray, cols: np.ndarray):
    """Flat positions in a ``(bw + 1, n)`` lower band (see :func:`band_array`) of the entries
    ``(rows, cols)`` on or below the diagonal (after the ordering), and the mask of those
    entries.  Raises ValueError when an entry falls outside the band."""
    i, j = order.inv[rows], order.inv[cols]
    low = i >= j
    d = (i - j)[low]
    if d.size and d.max() > order.bw:
        raise ValueError(f"lower_positions: an entry lies {int(d.max())} off the diagonal, "
                         f"expected at most the bandwidth {order.bw}")
    return j[low] * (order.bw + 1) + d, low


class RowGram:
    """``J^T J`` of a CSR matrix ``J (r, k)`` of fixed pattern, as a lower band of an ordering.

    Rows with identical column sets are grouped; each group's Gram matrix is
    one small dense product (``matmul`` over all groups of a size at once) and
    its lower entries are summed into the band by one ``np.bincount``.
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, order: BandOrder):
        self.order, self.indices = order, indices
        lengths = np.diff(indptr)
        self.classes = []  # (data positions (G, g, m), selected flat block entries) per (g, m)
        dest = []
        for m in np.unique(lengths[lengths > 0]):
            rows = np.nonzero(lengths == m)[0]
            pos = indptr[rows][:, None] + np.arange(m)  # (R, m) positions in the data array
            key = np.ascontiguousarray(indices[pos].astype(np.int64)).view(f"V{8 * m}").ravel()
            _, group, count = np.unique(key, return_inverse=True, return_counts=True)
            srt = np.argsort(group, kind="stable")
            for g in np.unique(count):  # groups of g rows each
                members = (count == g)[group[srt]]
                P = pos[srt[members]].reshape(-1, g, m)  # (G, g, m)
                cols = indices[P[:, 0, :]]  # (G, m), the same for every row of a group
                r = np.broadcast_to(cols[:, :, None], (len(P), m, m)).ravel()
                c = np.broadcast_to(cols[:, None, :], (len(P), m, m)).ravel()
                flat, low = lower_positions(order, r, c)
                self.classes.append((P, np.nonzero(low)[0]))
                dest.append(flat)
        self.dest = np.concatenate(dest) if dest else np.zeros(0, dtype=np.int64)

    def plans(self) -> list[tuple]:
        """Per class of groups ``(starts (G, g), m, ii, jj (l,), dest (G, l))``: the pairs
        ``(ii, jj)`` of the upper triangle of an ``(m, m)`` Gram block, and where pair ``t``
        of group ``G_i`` lands in the flat band (its lower entry, whichever way round the
        ordering puts it); the arguments of the compiled ``group_gram``.
        Raises ValueError unless every row's values are contiguous in the data (CSR)."""
        out = []
        order, w = self.order, self.order.bw + 1
        for P, _ in self.classes:
            G, g, m = P.shape
            if not np.array_equal(P, P[:, :, :1] + np.arange(m)):
                raise ValueError("RowGram.plans: a row's values are not contiguous, expected CSR rows")
            ii, jj = np.triu_indices(m)
            cols = self.indices[P[:, 0, :]]  # (G, m)
            oi, oj = order.inv[cols[:, ii]], order.inv[cols[:, jj]]
            dest = np.minimum(oi, oj) * w + np.abs(oi - oj)  # (G, l): the lower entry
            out.append((np.ascontiguousarray(P[:, :, 0], dtype=np.int64), int(m), ii.astype(np.int64),
                        jj.astype(np.int64), np.ascontiguousarray(dest, dtype=np.int64)))
        return out

    def values(self, data: np.ndarray) -> list[np.ndarray]:
        """Lower Gram entries of the rows with CSR values ``data (nnz,)``, in ``self.dest`` order."""
        out = []
        for P, sel in self.classes:
            D = data[P]  # (G, g, m)
            out.append(np.matmul(D.transpose(0, 2, 1), D).ravel()[sel])
        return out


def cholesky_solve(ab: np.ndarray, b: np.ndarray, order: BandOrder) -> np.ndarray | None:
    """Solve with the lower band ``ab (bw + 1, n)`` (ordered, Fortran) by ``dpbtrf``/``dpbtrs``.

    ``ab`` is overwritten.  Returns ``x (n,)`` in the original order, or None when
    the matrix is not positive definite to working precision (the caller falls back).
    With the compiled kernels (:mod:`optimize.kernels`) the factorization is
    their ``L D L^T``, which fails where ``dpbtrf`` does (a pivot ``<= 0``).
    """
    k = kernels.get()
    if k is not None:
        L = ab.T  # (n, bw + 1), C order: L[j, d] = M[j + d, j]
        if not L.flags.c_contiguous or not k.ldl_factor(L, True, order.ext):
            return None
        y = k.ldl_solve(L, np.ascontiguousarray(b[order.perm]), order.ext)
        if not np.all(np.isfinite(y)):
            return None
        x = np.empty_like(y)
        x[order.perm] = y
        return x
    c, info = lapack.dpbtrf(ab, lower=1, overwrite_ab=1)
    if info != 0:
        return None
    y, info = lapack.dpbtrs(c, b[order.perm], lower=1)
    if info != 0 or not np.all(np.isfinite(y)):
        return None
    x = np.empty_like(y)
    x[order.perm] = y
    return x


# -- general (indefinite) matrices: LU band storage (dgbtrf) ----------------------------------

def general_positions(order: BandOrder, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Flat positions of the entries ``(rows, cols)`` in a ``(3 bw + 1, n)`` band (see
    :func:`band_array`) for ``dgbtrf`` with ``kl = ku = bw``: entry ``(i, j)`` of the
    ordered matrix in row ``2 bw + i - j``.  Raises ValueError when an entry falls outside
    the band."""
    i, j = order.inv[rows], order.inv[cols]
    d = i - j
    if d.size and np.abs(d).max() > order.bw:
        raise ValueError(f"general_positions: an entry lies {int(np.abs(d).max())} off the diagonal, "
                         f"expected at most the bandwidth {order.bw}")
    return j * (3 * order.bw + 1) + 2 * order.bw + d


class BandLU:
    """An LU factorization (partial pivoting) of a banded ``M (n, n)`` given in ``dgbtrf`` storage.

    ab : (3 bw + 1, n) float, Fortran-ordered, overwritten.  norm1 : ``|M|_1``
    (for the caller's conditioning test).  ``ok`` is False when ``U`` has an
    exactly zero pivot; :meth:`solve` returns solutions in the original order.
    """

    def __init__(self, ab: np.ndarray, order: BandOrder, norm1: float):
        self.order, self.norm1 = order, float(norm1)
        self.lu, self.piv, info = lapack.dgbtrf(ab, order.bw, order.bw, overwrite_ab=1)
        self.ok = info == 0

    def solve(self, b: np.ndarray) -> np.ndarray:
        """(n,) float: ``M^{-1} b`` (non-finite if the factorization was not ``ok``)."""
        bw = self.order.bw
        y, _ = lapack.dgbtrs(self.lu, bw, bw, b[self.order.perm], self.piv)
        x = np.empty_like(y)
        x[self.order.perm] = y
        return x
