"""Corner angles and their gradients: the shared kernel of the angle constraints.

The angle at corner ``c`` (vertex ``p``, neighbours ``q = next``, ``s = prev``
in its face) is ``atan2(|u x w|, u . w)`` with ``u = q - p``, ``w = s - p``;
``d/dq = -(w^ - cos u^) / (|u| sin)``, ``d/ds = -(u^ - cos w^) / (|w| sin)``,
``d/dp = -(d/dq + d/ds)``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..variables import Layout


def corner_angle_terms(x: np.ndarray, layout: Layout, mesh: Mesh, C: np.ndarray,
                       sign: np.ndarray, offset: np.ndarray, parts: bool = False):
    """Rows ``sum_s sign[s] * angle(C[i, s]) - offset[i]`` and their Jacobian.

    C : (p, k) int corners; sign : (k,) float; offset : (p,) float.
    Returns ``r (p,)`` and ``J (p, layout.size)``; with ``parts`` also the list
    of ``k`` matrices ``J_s`` (the terms of corner slot ``s``, ``J = sum J_s``),
    each within one face.
    """
    t = mesh.topology
    V = layout.view(x, "vertices")
    P = V[t.corner_vertex[C]]
    U = V[t.corner_next_vertex[C]] - P  # (p, k, 3)
    W = V[t.corner_prev_vertex[C]] - P
    lu, lw = np.linalg.norm(U, axis=2), np.linalg.norm(W, axis=2)
    uh, wh = U / lu[..., None], W / lw[..., None]
    cos = np.einsum("psj,psj->ps", uh, wh)
    sin = np.linalg.norm(np.cross(uh, wh), axis=2)
    r = np.arctan2(sin, cos) @ sign - offset
    s = np.maximum(sin, 1e-300)[..., None]
    dU = -(wh - cos[..., None] * uh) / (lu[..., None] * s)
    dW = -(uh - cos[..., None] * wh) / (lw[..., None] * s)
    iv = layout.index("vertices")
    p, k = C.shape
    cols = np.concatenate([iv[t.corner_next_vertex[C]], iv[t.corner_prev_vertex[C]],
                           iv[t.corner_vertex[C]]], axis=2)  # (p, k, 9)
    vals = np.concatenate([dU, dW, -(dU + dW)], axis=2) * sign[None, :, None]
    rows = np.repeat(np.arange(p), 9 * k)
    J = sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(p, layout.size))
    if not parts:
        return r, J
    rows1 = np.repeat(np.arange(p), 9)
    Js = [sp.csr_matrix((vals[:, s].ravel(), (rows1, cols[:, s].ravel())), shape=(p, layout.size))
          for s in range(k)]
    return r, J, Js
