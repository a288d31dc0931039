"""Planarity on vertices alone: the signed distance between the two diagonals of a quad.

For four points ``p0..p3`` with diagonals ``d1 = p2 - p0``, ``d2 = p3 - p1``
and ``e = p1 - p0``, the residual is ``t / s`` with the triple product
``t = e . (d1 x d2)`` and ``s = |d1 x d2|``: the signed distance between the
diagonal lines, zero exactly when the four points are coplanar (the quad
planarity measure times the mean diagonal length).  A quad gives one row;
triangles give none.  ``quadruples`` also lists runs of four consecutive
vertices of n-gons, but their rows miss a face that hinges about three
nearly collinear vertices (the straight corner of a T-junction pentagon):
the vertex formulation keeps a unit normal per n-gon instead
(``formulation``; ``terms.planarity`` with ``faces``).

Unlike ``terms.planarity`` this needs no auxiliary normals: the
conical target then has only the vertices as unknowns and the sparse factor
of each step is about 3x smaller (see ``formulation``).  Not quadratic:
``dr = dt / s - t ds / s^2`` with ``dt/de = d1 x d2``, ``dt/dd1 = d2 x e``,
``dt/dd2 = e x d1``, ``ds/dd1 = d2 x n``, ``ds/dd2 = n x d1`` (``n = c / s``).

Block: ``vertices (n, 3)``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .variables import Layout


def quadruples(mesh: Mesh, max_size: int | None = None) -> np.ndarray:
    """(q, 4) int: the runs of four consecutive vertices, ``n - 3`` per n-gon (quads: the
    face), for faces of at most ``max_size`` vertices (default all)."""
    F = mesh.F
    sizes = (F >= 0).sum(axis=1)
    out = []
    top = int(sizes.max(initial=0)) if max_size is None else int(max_size)
    for k in range(4, top + 1):  # loop over face sizes, not faces
        G = F[sizes == k, :k]
        if len(G):
            out.append(np.concatenate([G[:, i:i + 4] for i in range(k - 3)], axis=0))
    return np.concatenate(out, axis=0) if out else np.zeros((0, 4), dtype=np.int64)


def terms(x: np.ndarray, layout: Layout, mesh: Mesh, Q: np.ndarray | None = None):
    """Residual ``(q,)`` and Jacobian ``(q, layout.size)`` for the quadruples ``Q (q, 4)``
    (default :func:`quadruples`)."""
    Q = quadruples(mesh) if Q is None else Q
    V = layout.view(x, "vertices")
    P = V[Q]  # (q, 4, 3)
    e, d1, d2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]
    c = np.cross(d1, d2)
    s = np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    t = np.einsum("ij,ij->i", e, c)
    n = c / s[:, None]
    r = t / s
    gt_e, gt_d1, gt_d2 = c, np.cross(d2, e), np.cross(e, d1)
    gs_d1, gs_d2 = np.cross(d2, n), np.cross(n, d1)
    k1, k2 = (1.0 / s)[:, None], (t / s ** 2)[:, None]
    g_e = k1 * gt_e
    g_d1 = k1 * gt_d1 - k2 * gs_d1
    g_d2 = k1 * gt_d2 - k2 * gs_d2
    # e = p1 - p0, d1 = p2 - p0, d2 = p3 - p1
    G = np.stack([-g_e - g_d1, g_e - g_d2, g_d1, g_d2], axis=1)  # (q, 4, 3)
    iv = layout.index("vertices")
    rows = np.repeat(np.arange(len(Q)), 12)
    J = sp.csr_matrix((G.ravel(), (rows, iv[Q].ravel())), shape=(len(Q), layout.size))
    return r, J
