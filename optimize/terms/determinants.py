"""Planarity of strip quads by determinants of normalized edge vectors (paper, PQ strips).

For a quad with edge vectors ``e_j = v_{j+1} - v_j`` (``j = 0..3`` cyclic) and
unit edges ``u_j = e_j / |e_j|`` the four constraints are

    c_det[j] = det(u_j, u_{j+1}, u_{j+2}) = u_j . (u_{j+1} x u_{j+2}),   j = 0..3.

Each vanishes exactly when the quad is planar, and, unlike the angle sum, each
is linear in an out-of-plane displacement and stays of order one for thin quads
whose vertices nearly lie on a line segment (the quads of a developable strip
near its edge of regression), where the angle sum hardly notices a twist.
The paper's methods use them on strips (and SQP / hybrid on every quad mesh;
:mod:`optimize.solvers.paper.targets`); the default method's planarity on
vertices alone is the diagonal distance (``diagonals``: the same triple product
``e_0 . (e_1 x e_2)``, divided by ``|d1 x d2|`` instead of the three edge
lengths, so not the same rows up to a constant).

Block: ``vertices (n, 3)``.  Rows ``4 i + j`` for quad ``i`` (:func:`det_quads`, in order).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..mesh.corners import cross
from .variables import Layout


def det_quads(mesh: Mesh) -> np.ndarray:
    """(q,) int: the quad faces (four rows each)."""
    return np.nonzero(mesh.face_sizes == 4)[0]


NEXT = np.array([1, 2, 3, 0])
NEXT2 = np.array([2, 3, 0, 1])


def _unit_edges(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    E = Q[:, NEXT] - Q  # (q, 4, 3): edge j from vertex j to j + 1
    L = np.maximum(np.sqrt(np.einsum("qjk,qjk->qj", E, E)), 1e-300)  # a zero-length edge gives 0
    return E / L[:, :, None], L


def det_values(Q: np.ndarray) -> np.ndarray:
    """(q, 4) float: the four determinants of quads ``Q (q, 4, 3)`` (values only)."""
    U, _ = _unit_edges(Q)
    return np.einsum("qjk,qjk->qj", U, cross(U[:, NEXT], U[:, NEXT2]))


def det_local(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Determinants and their gradients for quads given by their points.

    Q : (q, 4, 3) float, the four vertices of each quad in order.
    Returns ``D (q, 4)`` (``D[:, j] = det(u_j, u_{j+1}, u_{j+2})``) and
    ``G (q, 4, 12)`` = ``d D[:, j] / d Q.reshape(q, 12)``.

    With ``P_k = u_k x u_{k+1}`` and ``R_j = u_{j+2} x u_j``, the gradient of
    ``D_j`` with respect to the unit edges ``u_j, u_{j+1}, u_{j+2}`` is
    ``P_{j+1}, R_j, P_j`` (cyclic triple product), each with ``u . grad = D_j``;
    through the normalization ``d u / d e = (I - u u^T) / |e|`` edge ``j + t``
    gets ``(grad - D_j u_{j+t}) / |e_{j+t}|``, and edge ``k`` (from vertex ``k``
    to ``k + 1``) passes it to its end minus its start.
    """
    q = len(Q)
    U, L = _unit_edges(Q)
    P = cross(U, U[:, NEXT])  # (q, 4, 3): P_k = u_k x u_{k+1}
    R = cross(U[:, NEXT2], U)  # R_j = u_{j+2} x u_j
    D = np.einsum("qjk,qjk->qj", U, P[:, NEXT])  # (q, 4)
    Dx = D[:, :, None]
    A = (P[:, NEXT] - Dx * U) / L[:, :, None]  # edge j
    B = (R - Dx * U[:, NEXT]) / L[:, NEXT, None]  # edge j + 1
    C = (P - Dx * U[:, NEXT2]) / L[:, NEXT2, None]  # edge j + 2
    rel = np.stack([-A, A - B, B - C, C], axis=2)  # (q, 4 dets, vertex j + t, 3)
    gV = rel[:, _J, _T]  # (q, 4 dets, 4 vertices, 3)
    return D, gV.reshape(q, 4, 12)


_J = np.arange(4)[:, None]  # det j ...
_T = (np.arange(4)[None, :] - _J) % 4  # ... vertex v is vertex j + t


ALTERNATING = np.array([1.0, -1.0, 1.0, -1.0]) / 4


def det_combined_local(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One planarity row per quad: ``(D_0 - D_1 + D_2 - D_3) / 4`` and its gradient.

    Consecutive determinants alternate in sign (``det(e1, e2, e3) = -det(e0, e1, e2)``
    for ``e3 = -(e0 + e1 + e2)``; the normalization keeps the signs), so the
    alternating mean vanishes exactly when the quad is planar and is not
    redundant like the four rows are (they have rank one at a planar quad).
    SQP uses it as its constraint.  Returns ``(q,)`` and ``(q, 12)``.
    """
    D, G = det_local(Q)
    return D @ ALTERNATING, np.einsum("j,qja->qa", ALTERNATING, G)


def terms(x: np.ndarray, layout: Layout, mesh: Mesh) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(4 q,)`` (row ``4 i + j`` = ``c_det[j]`` of quad ``i``; dimensionless, in
    [-1, 1]) and Jacobian ``(4 q, layout.size)``."""
    F = mesh.F[det_quads(mesh), :4]  # (q, 4)
    q = len(F)
    D, G = det_local(layout.view(x, "vertices")[F])
    rows = np.broadcast_to(np.arange(4 * q).reshape(q, 4, 1), G.shape)
    cols = np.broadcast_to(layout.index("vertices")[F].reshape(q, 1, 12), G.shape)
    J = sp.csr_matrix((G.ravel(), (rows.ravel(), cols.ravel())), shape=(4 * q, layout.size))
    return D.ravel(), J


def at_positions(mesh: Mesh, V: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """:func:`terms` at positions ``V (n, 3)``: ``r (4 q,)`` and ``J (4 q, 3 n)``, ``x = V.ravel()``."""
    return terms(np.asarray(V, dtype=np.float64).ravel(), Layout.vertices_only(mesh.n_vertices), mesh)
