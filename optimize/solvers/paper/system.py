"""The stacked constraint rows of a target, assembled on a sparsity pattern fixed once.

Every iteration of penalty and SQP evaluates the same rows at new positions;
the positions of the Jacobian's nonzeros never change.  :class:`Pattern`
computes, once, where each triplet of a fixed ``(rows, cols)`` list lands in
a CSR matrix (duplicates summed, fixed columns dropped, free columns
renumbered), so each evaluation is one ``np.bincount`` instead of a COO sort.
:class:`ConstraintSystem` lays the blocks of :class:`optimize.solvers.paper.targets.Term`
(the problem description's rows, prepared) out in that way.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ... import kernels
from ...mesh import Mesh
from ...mesh.corners import angle_local, angle_values, corner_vertices
from ...terms.determinants import (
    ALTERNATING,
    det_combined_local,
    det_local,
    det_quads,
    det_values,
)
from ...terms.variables import Layout


class Pattern:
    """A CSR pattern for triplets at fixed ``rows (t,)``, ``cols (t,)``.

    shape : (r, N) of the full matrix.  free : (k,) int columns kept (renumbered
    0..k-1), or None for all.  :meth:`matrix` takes the ``(t,)`` values.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int],
                 free: np.ndarray | None = None):
        rows, cols = np.asarray(rows).ravel(), np.asarray(cols).ravel()
        ncols = shape[1]
        if free is not None:
            colmap = np.full(shape[1], -1, dtype=np.int64)
            colmap[free] = np.arange(len(free))
            cols = colmap[cols]
            ncols = len(free)
        self.keep = cols >= 0
        key = rows[self.keep] * ncols + cols[self.keep]
        uniq, self.inv = np.unique(key, return_inverse=True)
        self.nnz = len(uniq)
        self.indices = (uniq % ncols).astype(np.int32)
        self.indptr = np.searchsorted(uniq // ncols, np.arange(shape[0] + 1)).astype(np.int32)
        self.shape = (shape[0], ncols)
        self._all = bool(self.keep.all())

    def data(self, vals: np.ndarray) -> np.ndarray:
        """(nnz,) CSR values: the triplet values ``vals (t,)`` summed into place."""
        v = vals.ravel() if self._all else vals.ravel()[self.keep]
        return np.bincount(self.inv, weights=v, minlength=self.nnz)

    def csr(self, data: np.ndarray) -> sp.csr_matrix:
        """(r, k) CSR of the pattern with values ``data (nnz,)`` (no copy, no checks)."""
        M = sp.csr_matrix(self.shape)
        M.data, M.indices, M.indptr = data, self.indices, self.indptr
        return M

    def matrix(self, vals: np.ndarray) -> sp.csr_matrix:
        """(r, k) CSR with the triplet values ``vals (t,)`` summed into place."""
        return self.csr(self.data(vals))

    @property
    def rows(self) -> np.ndarray:
        """(nnz,) int: the row of every stored entry."""
        if getattr(self, "_rows", None) is None:
            self._rows = np.repeat(np.arange(self.shape[0]), np.diff(self.indptr))
        return self._rows


class ConstraintSystem:
    """Residuals ``c (r,)`` and Jacobian ``A (r, k)`` of a list of terms, on free columns.

    mesh : Mesh.  terms : list of :class:`optimize.solvers.paper.targets.Term`.
    free : (k,) int free coordinates of ``x`` (None: all of them).
    layout : the unknowns' :class:`optimize.terms.variables.Layout` (default
        :meth:`~optimize.terms.variables.Layout.vertices_only`, ``x = V.ravel()``).
    """

    def __init__(self, mesh: Mesh, terms: list, free: np.ndarray | None = None, layout: Layout | None = None):
        self.mesh, self.terms = mesh, terms
        t = mesh.topology
        layout = Layout.vertices_only(mesh.n_vertices) if layout is None else layout
        iv = layout.index("vertices")  # (n, 3)
        self.vid = corner_vertices(t).astype(np.int64)  # (c, 3)
        nc = len(self.vid)
        ccols = iv[self.vid].reshape(nc, 9)
        self.quads = np.ascontiguousarray(mesh.F[det_quads(mesh), :4], dtype=np.int64)
        qcols = iv[self.quads].reshape(-1, 12)
        self.blocks, self._entries, rows, cols, at = {}, [], [], [], 0
        for term in terms:
            if term.kind in ("det", "det1"):
                per = 4 if term.kind == "det" else 1
                r = per * len(self.quads)
                rows.append(np.repeat(at + np.arange(r), 12))
                cols.append(np.repeat(qcols, per, axis=0).ravel())
                self._entries.append(None)
            else:
                S = term.signs_matrix(nc).tocoo()
                r = S.shape[0]
                rows.append(np.repeat(at + S.row, 9))
                cols.append(ccols[S.col].ravel())
                self._entries.append((S.col, S.data, S.tocsr()))
            self.blocks[term.name] = slice(at, at + r)
            at += r
        self.n_rows = at
        self._kinds = {term.kind for term in terms}
        self._last = None
        self.pattern = Pattern(np.concatenate(rows), np.concatenate(cols), (at, layout.size), free)
        # where each term's triplets land in the CSR data (-1: a fixed coordinate), for the kernels
        dest = np.full(sum(len(r_) for r_ in rows), -1, dtype=np.int64)
        dest[self.pattern.keep] = self.pattern.inv
        self._dest, start = [], 0
        for r_, term in zip(rows, terms):
            width = 9 if term.kind == "angle" else 12
            self._dest.append(dest[start:start + len(r_)].reshape(-1, width))
            start += len(r_)

    def local(self, V: np.ndarray, jac: bool) -> dict:
        """The local quantities the terms need at ``V (n, 3)``: corner angles ``phi (c,)``,
        determinants ``D (q, 4)``, alternating means ``D1 (q,)`` and, with ``jac``, their
        gradients ``G (c, 9)``, ``GD (q, 4, 12)``, ``G1 (q, 12)``.

        Values without gradients are kept for the last ``V`` (a copy is compared), so
        that :meth:`optimize.solvers.paper.problem.Problem.measure` after a trial step reuses them.
        """
        kinds = self._kinds
        last = self._last
        if not jac and last is not None and np.array_equal(last[0], V):
            return last[1]
        out = {}
        k = kernels.get()
        if k is not None:  # the same quantities, compiled (optimize.kernels)
            V = np.ascontiguousarray(V, dtype=np.float64)
            if "angle" in kinds:
                out["phi"], G = k.angles(V, self.vid, jac)
                if jac:
                    out["G"] = G
            if "det" in kinds or "det1" in kinds:
                D, GD = k.dets(V, self.quads, jac)
                out["D"] = D
                if "det1" in kinds:
                    out["D1"] = D @ ALTERNATING
                if jac:
                    if "det" in kinds:
                        out["GD"] = GD
                    if "det1" in kinds:
                        out["G1"] = np.einsum("j,qja->qa", ALTERNATING, GD)
        else:
            self._local_numpy(V, jac, out)
        if not jac:
            self._last = (V.copy(), out)
        return out

    def _local_numpy(self, V: np.ndarray, jac: bool, out: dict) -> None:
        """:meth:`local` by the NumPy functions of ``angles`` and ``det`` (no compiled kernels)."""
        kinds = self._kinds
        if "angle" in kinds:
            if jac:
                out["phi"], out["G"] = angle_local(V[self.vid])
            else:
                out["phi"] = angle_values(V[self.vid])
        if "det" in kinds or "det1" in kinds:
            if jac:
                if "det" in kinds:
                    out["D"], out["GD"] = det_local(V[self.quads])
                if "det1" in kinds:
                    out["D1"], out["G1"] = det_combined_local(V[self.quads])
            else:
                out["D"] = det_values(V[self.quads])
                out["D1"] = out["D"] @ ALTERNATING

    def cached(self, V: np.ndarray) -> dict:
        """The values :meth:`local` last computed, if they were computed at ``V`` (else ``{}``)."""
        last = self._last
        return last[1] if last is not None and np.array_equal(last[0], V) else {}

    def evaluate_data(self, V: np.ndarray, jac: bool = True, weighted: bool = False):
        """``c (r,)`` and, with ``jac``, the Jacobian's CSR values ``(nnz,)`` on :attr:`pattern`."""
        loc = self.local(V, jac)
        cs, vals = [], []
        fused = jac and kernels.get() is not None  # then the values are scattered below
        for term, ent in zip(self.terms, self._entries):
            w = np.sqrt(term.weight) if weighted and term.weight != 1.0 else 1.0
            if term.kind == "det":
                cs.append(w * loc["D"].ravel())
                if jac and not fused:
                    vals.append(w * loc["GD"].reshape(-1, 12))
            elif term.kind == "det1":
                cs.append(w * loc["D1"])
                if jac and not fused:
                    vals.append(w * loc["G1"])
            else:
                corner, sign, S = ent
                cs.append(w * (kernels.matvec(S, loc["phi"]) - term.offset))
                if jac and not fused:
                    vals.append((w * sign)[:, None] * loc["G"][corner])
        c = np.concatenate(cs)
        if not jac:
            return c
        k = kernels.get()
        if k is None:
            return c, self.pattern.data(np.concatenate([v.ravel() for v in vals]))
        data = np.zeros(self.pattern.nnz)  # the same sums in the same order, without the copies
        for term, ent, dest in zip(self.terms, self._entries, self._dest):
            w = np.sqrt(term.weight) if weighted and term.weight != 1.0 else 1.0
            if term.kind in ("det", "det1"):
                src = loc["GD"].reshape(-1, 12) if term.kind == "det" else loc["G1"]
                k.scatter_rows(data, dest, np.full(len(src), w), src, np.arange(len(src)))
            else:
                corner, sign, _ = ent
                k.scatter_rows(data, dest, np.ascontiguousarray(w * sign, dtype=np.float64), loc["G"], corner)
        return c, data

    def evaluate(self, V: np.ndarray, jac: bool = True, weighted: bool = False):
        """``c (r,)`` and, with ``jac``, ``A (r, k)`` csr at ``V (n, 3)``.

        weighted : multiply each block by ``sqrt(term.weight)`` (penalty rows).
        """
        out = self.evaluate_data(V, jac, weighted)
        return (out[0], self.pattern.csr(out[1])) if jac else out
