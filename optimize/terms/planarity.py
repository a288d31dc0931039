"""Planarity through auxiliary face normals: ``n_f . (v_j - v_i) = 0`` on every half-edge.

Blocks: ``vertices (n, 3)``, ``normals (m, 3)``.  One row per corner ``c``
(half-edge ``i -> j`` of face ``f``), in topology corner order.  With the unit
constraint on ``n_f`` (``terms.unit``) a zero residual means that every
face lies in a plane with normal ``n_f``; for an n-gon the ``k`` rows have
rank ``k - 1``.  Triangles are included (always satisfiable).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .variables import Layout


def terms(x: np.ndarray, layout: Layout, mesh: Mesh, faces: np.ndarray | None = None,
          block: str = "normals") -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(c,)`` and Jacobian ``(c, layout.size)``; ``c`` = number of corners.

    faces : (q,) int, only the corners of these faces; then row ``i`` of block
        ``block`` (``(q, 3)``) is the normal of ``faces[i]`` (default: every face,
        block ``normals (m, 3)``).
    """
    t = mesh.topology
    V, N = layout.view(x, "vertices"), layout.view(x, block)
    if faces is None:
        corners, slot = np.arange(len(t.corner_face)), t.corner_face
    else:
        size = t.face_sizes[faces]
        slot = np.repeat(np.arange(len(faces)), size)
        corners = t.offsets[faces][slot] + (np.arange(len(slot)) - np.repeat(np.cumsum(size) - size, size))
    vi, vj, f = t.corner_vertex[corners], t.corner_next_vertex[corners], slot
    e = V[vj] - V[vi]  # (c, 3)
    n = N[f]  # (c, 3)
    r = np.einsum("ij,ij->i", n, e)
    iv, inn = layout.index("vertices"), layout.index(block)
    nc = len(r)
    cols = np.concatenate([iv[vj], iv[vi], inn[f]], axis=1)  # (c, 9)
    vals = np.concatenate([n, -n, e], axis=1)
    rows = np.repeat(np.arange(nc), 9)
    J = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(nc, layout.size))
    return r, J
