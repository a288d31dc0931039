"""Second derivatives of the constraints: the curvature term of SQP's Newton-KKT step.

The Hessian of the Lagrangian is ``Hess f + sum_i y_i Hess c_i``.  Every
constraint row is a sum of local functions (a corner angle of three points; a
quad's determinants of four points), so ``sum_i y_i Hess c_i`` is assembled
from small dense blocks, ``(9, 9)`` per corner and ``(12, 12)`` per quad,
each by central differences of the *exact* local gradients
(:func:`optimize.mesh.corners.angle_local`, :func:`optimize.terms.determinants.det_local`,
:func:`optimize.terms.determinants.det_combined_local`) with a step of ``1e-6`` times
the element size (error about ``1e-10`` relative), for all elements at once.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp

from ...mesh import Mesh
from ...mesh.corners import angle_local, corner_vertices
from ...terms.variables import Layout
from ...terms.determinants import det_combined_local, det_local, det_quads

REL_STEP = 1e-6


def local_hessians(grad: Callable, X: np.ndarray) -> np.ndarray:
    """Hessians of local functions by central differences of their exact gradients.

    grad : ``X (k, a, 3) -> (value, G (k, ..., 3 a))``.
    X : (k, a, 3) float, the points of each of ``k`` elements.
    Returns ``(k, ..., 3 a, 3 a)`` float, symmetrized.
    """
    k, a, _ = X.shape
    size = np.linalg.norm(X - X.mean(axis=1, keepdims=True), axis=2).max(axis=1)
    h = REL_STEP * np.maximum(size, 1e-300)  # (k,)
    cols = []
    for j in range(3 * a):  # 3a evaluations, each over all elements
        Xp, Xm = X.copy(), X.copy()
        Xp[:, j // 3, j % 3] += h
        Xm[:, j // 3, j % 3] -= h
        dG = grad(Xp)[1] - grad(Xm)[1]
        cols.append(dG / (2 * h.reshape((k,) + (1,) * (dG.ndim - 1))))
    Hs = np.stack(cols, axis=-1)
    return 0.5 * (Hs + np.swapaxes(Hs, -1, -2))


def _assemble(blocks: np.ndarray, vid: np.ndarray, layout: Layout) -> sp.csr_matrix:
    """(N, N) sparse (``N = layout.size``) from ``blocks (k, 3a, 3a)`` over the vertices ``vid (k, a)``."""
    k, a = vid.shape
    idx = layout.index("vertices")[vid].reshape(k, 3 * a)
    rows = np.broadcast_to(idx[:, :, None], blocks.shape)
    cols = np.broadcast_to(idx[:, None, :], blocks.shape)
    return sp.csr_matrix((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(layout.size, layout.size))


def constraint_curvature(mesh: Mesh, terms: list, V: np.ndarray, y: np.ndarray,
                         blocks: dict[str, slice]) -> sp.csr_matrix:
    """(3 n, 3 n) sparse: ``sum_i y_i Hess c_i`` over the rows of ``terms`` at ``V (n, 3)``.

    y : (r,) multipliers, laid out as ``blocks`` (term name -> slice of rows).
    """
    layout = Layout.vertices_only(mesh.n_vertices)
    vid = corner_vertices(mesh.topology)
    quads = mesh.F[det_quads(mesh), :4]
    w = np.zeros(len(vid))
    out = sp.csr_matrix((layout.size, layout.size))
    for term in terms:
        yb = y[blocks[term.name]]
        if term.kind == "det":
            Hs = local_hessians(det_local, V[quads])  # (q, 4, 12, 12)
            out = out + _assemble(np.einsum("qj,qjab->qab", yb.reshape(-1, 4), Hs), quads, layout)
        elif term.kind == "det1":
            Hs = local_hessians(det_combined_local, V[quads])  # (q, 12, 12)
            out = out + _assemble(yb[:, None, None] * Hs, quads, layout)
        else:
            w += term.signs_matrix(len(vid)).T @ yb
    use = np.nonzero(w)[0]
    if use.size:
        Hs = local_hessians(angle_local, V[vid[use]])  # (u, 9, 9)
        out = out + _assemble(w[use, None, None] * Hs, vid[use], layout)
    return out.tocsr()
