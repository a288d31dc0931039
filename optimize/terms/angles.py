"""Signed sums of corner angles as constraint rows: the shared kernel of the angle constraints.

Row ``i`` is ``sum_s sign[s] * angle(C[i, s]) - offset[i]``; the angles and their
gradients are :func:`optimize.mesh.corners.angle_local`'s (the one corner-angle kernel).
Both methods take their angle rows from here: the default method through the
terms' ``terms(x, layout, ...)``, the paper's through the same corner sets
(``rows``) on its fixed patterns (:mod:`optimize.solvers.paper.system`) and
:func:`rows_at`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..mesh.corners import angle_local
from .variables import Layout


def angle_rows(x: np.ndarray, layout: Layout, mesh: Mesh, C: np.ndarray,
               sign: np.ndarray, offset: np.ndarray, parts: bool = False):
    """Rows ``sum_s sign[s] * angle(C[i, s]) - offset[i]`` and their Jacobian.

    C : (p, k) int corners (``-1`` in unused slots: rows of different lengths);
    sign : (k,) float; offset : (p,) float.
    Returns ``r (p,)`` and ``J (p, layout.size)``; with ``parts`` also the list
    of ``k`` matrices ``J_s`` (the terms of corner slot ``s``, ``J = sum J_s``),
    each within one face.
    """
    if (C < 0).any():
        if parts:
            raise ValueError("angle_rows: parts=True needs every corner slot used (no -1 in C)")
        return _padded_rows(x, layout, mesh, C, sign, offset)
    t = mesh.topology
    V = layout.view(x, "vertices")
    p, k = C.shape
    vid = np.stack([t.corner_vertex[C], t.corner_next_vertex[C], t.corner_prev_vertex[C]], axis=2)  # (p, k, 3)
    phi, G = angle_local(V[vid.reshape(-1, 3)])  # (p k,), (p k, 9): d/d(corner, next, prev)
    r = phi.reshape(p, k) @ sign - offset
    iv = layout.index("vertices")  # (n, 3)
    cols = iv[vid].reshape(p, k, 9)
    vals = G.reshape(p, k, 9) * sign[None, :, None]
    rows = np.repeat(np.arange(p), 9 * k)
    J = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(p, layout.size))
    if not parts:
        return r, J
    rows1 = np.repeat(np.arange(p), 9)
    Js = [sp.csr_matrix((vals[:, s].ravel(), (rows1, cols[:, s].ravel())), shape=(p, layout.size))
          for s in range(k)]
    return r, J, Js


def _padded_rows(x: np.ndarray, layout: Layout, mesh: Mesh, C: np.ndarray, sign: np.ndarray,
                 offset: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """:func:`angle_rows` over the used slots ``C >= 0`` only."""
    t = mesh.topology
    V = layout.view(x, "vertices")
    row, slot = np.nonzero(C >= 0)
    c = C[row, slot]
    s = np.asarray(sign, dtype=np.float64)[slot]
    vid = np.stack([t.corner_vertex[c], t.corner_next_vertex[c], t.corner_prev_vertex[c]], axis=1)  # (u, 3)
    phi, G = angle_local(V[vid])
    r = np.bincount(row, weights=s * phi, minlength=len(C)) - offset
    cols = layout.index("vertices")[vid].reshape(-1, 9)
    J = sp.csr_matrix(((G * s[:, None]).ravel(), (np.repeat(row, 9), cols.ravel())), shape=(len(C), layout.size))
    return r, J


def rows_at(mesh: Mesh, V: np.ndarray, C: np.ndarray, sign: np.ndarray,
            offset: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """:func:`angle_rows` at positions ``V (n, 3)`` (the unknowns are the vertices alone):
    ``r (p,)`` and ``J (p, 3 n)`` with columns ``x = V.ravel()``."""
    layout = Layout.vertices_only(mesh.n_vertices)
    return angle_rows(np.asarray(V, dtype=np.float64).ravel(), layout, mesh, C, sign, offset)
