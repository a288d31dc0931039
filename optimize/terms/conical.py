"""Conical vertices: the face normals around a vertex make one angle with a node axis.

At every interior valence-4 vertex ``v`` (``topology.interior_valence4``, in
that order) with unit axis ``a_v`` and ``c_v = cos(theta_v)``:
``n_f . a_v - c_v = 0`` for the four faces ``f`` around ``v``.  With unit
normals, unit axes and planar faces this is the paper's angle balance
``w1 + w3 = w2 + w4`` (the four face planes touch one cone of revolution).

Blocks: ``normals (m, 3)``, ``axes (p, 3)``, ``cos (p,)``.  Rows ``4 i + s``
for vertex ``i`` and star slot ``s``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .variables import Layout


def cone_faces(mesh: Mesh) -> np.ndarray:
    """(p, 4) int: the faces around each interior valence-4 vertex, cyclic order."""
    t = mesh.topology
    return t.star_faces[t.interior_valence4, :4]


def terms(x: np.ndarray, layout: Layout, mesh: Mesh) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(4p,)`` and Jacobian ``(4p, layout.size)``."""
    S = cone_faces(mesh)  # (p, 4)
    N, A, c = layout.view(x, "normals"), layout.view(x, "axes"), layout.view(x, "cos")
    p = len(S)
    n = N[S]  # (p, 4, 3)
    a = np.broadcast_to(A[:, None, :], n.shape)
    r = (np.einsum("psj,psj->ps", n, a) - c[:, None]).ravel()
    inn, ia, ic = layout.index("normals"), layout.index("axes"), layout.index("cos")
    cols = np.concatenate([inn[S], np.broadcast_to(ia[:, None, :], (p, 4, 3)),
                           np.broadcast_to(ic[:, None, None], (p, 4, 1))], axis=2)  # (p, 4, 7)
    vals = np.concatenate([a, n, -np.ones((p, 4, 1))], axis=2)
    rows = np.repeat(np.arange(4 * p), 7)
    J = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(4 * p, layout.size))
    return r, J
