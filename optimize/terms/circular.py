"""Circular quads: a circle centre per quad, equidistant from its vertices, in its plane.

For quad ``f`` (faces with ``face_sizes == 4``, in face order) with centre
``c_f`` and squared radius ``R_f``: ``|v_i - c_f|^2 - R_f = 0`` for its four
vertices and ``n_f . (c_f - v_0) = 0``.  With planarity (``terms.planarity``)
and unit normals, a zero residual means the quad has a circumcircle, i.e.
``phi1 + phi3 = phi2 + phi4 = pi``.

Blocks: ``vertices (n, 3)``, ``normals (m, 3)``, ``centres (q, 3)``,
``radius2 (q,)``.  Rows: ``4 q`` distance rows (quad-major) then ``q`` plane rows.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .variables import Layout


def circle_faces(mesh: Mesh) -> np.ndarray:
    """(q,) int: the quads, in face order."""
    return np.nonzero(mesh.face_sizes == 4)[0]


def terms(x: np.ndarray, layout: Layout, mesh: Mesh) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(5q,)`` and Jacobian ``(5q, layout.size)``."""
    Q = circle_faces(mesh)
    Fq = mesh.F[Q, :4]  # (q, 4)
    q = len(Q)
    V, N = layout.view(x, "vertices"), layout.view(x, "normals")
    C, R = layout.view(x, "centres"), layout.view(x, "radius2")
    iv, inn = layout.index("vertices"), layout.index("normals")
    ic, ir = layout.index("centres"), layout.index("radius2")
    d = V[Fq] - C[:, None, :]  # (q, 4, 3)
    r1 = (np.einsum("qsj,qsj->qs", d, d) - R[:, None]).ravel()
    cols1 = np.concatenate([iv[Fq], np.broadcast_to(ic[:, None, :], (q, 4, 3)),
                            np.broadcast_to(ir[:, None, None], (q, 4, 1))], axis=2)  # (q, 4, 7)
    vals1 = np.concatenate([2 * d, -2 * d, -np.ones((q, 4, 1))], axis=2)
    rows1 = np.repeat(np.arange(4 * q), 7)
    n = N[Q]
    g = C - V[Fq[:, 0]]
    r2 = np.einsum("ij,ij->i", n, g)
    cols2 = np.concatenate([inn[Q], ic, iv[Fq[:, 0]]], axis=1)  # (q, 9)
    vals2 = np.concatenate([g, n, -n], axis=1)
    rows2 = 4 * q + np.repeat(np.arange(q), 9)
    J = sp.csr_matrix((np.concatenate([vals1.ravel(), vals2.ravel()]),
                       (np.concatenate([rows1, rows2]), np.concatenate([cols1.ravel(), cols2.ravel()]))),
                      shape=(5 * q, layout.size))
    return np.concatenate([r1, r2]), J
